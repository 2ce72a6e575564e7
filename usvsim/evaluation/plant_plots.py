"""Plots of the plant: turning circle, heading steps, Bode plot, Kalman filter vs GPS, trials.

Every function returns a matplotlib Figure; :func:`save_plant_plots` writes them as PNG files
(atomically) and returns their paths. Uses the non-interactive Agg backend when no display is set.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from usvsim.common.fileio import atomic_savefig
from usvsim.common.mpl import use_file_backend_if_headless
from usvsim.evaluation.manoeuvre import TrialReport
from usvsim.vessel.plant import Plant

use_file_backend_if_headless()  # before any figure: files only when headless

__all__ = [
    "bode_figure",
    "heading_step_figure",
    "kalman_figure",
    "manoeuvre_figure",
    "save_plant_plots",
    "turning_circle_figure",
]


def turning_circle_figure(plant: Plant, seconds: float = 120.0) -> Figure:
    """Paths of boats turning with hard-over steering, autopilot-commanded and rate-limited.

    The path holds the heading reference 90° to starboard of the current heading, so the
    autopilot turns at its reference model's rate limit (not hard over: the open-loop turning
    circle at maximum helm is ``usvsim manoeuvre``); speed control stays active.
    """
    n = round(seconds / plant.dt_s)
    state = plant.initial_state(np.zeros((1, 3)))
    path = np.empty((n, 2))
    for k in range(n):  # reference 90° ahead of the current heading: a continuous turn
        state, _ = plant.step(state, state.x[:, 2] + math.pi / 2)
        path[k] = state.x[0, 0:2]
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(path[:, 1], path[:, 0], lw=1.2, label="autopilot turn at its rate limit")
    ax.plot([0], [0], "ko", label="start")
    ax.set_xlabel("y east (m)")
    ax.set_ylabel("x north (m)")
    ax.set_aspect("equal")
    tail = path[n // 2 :]
    radius = np.hypot(*(tail - tail.mean(axis=0)).T).mean()
    ax.set_title(f"{plant.vessel.name}: rate-limited autopilot turn, radius ≈ {radius:.1f} m")
    ax.legend(loc="best")
    fig.tight_layout()
    return fig


def heading_step_figure(plant: Plant, steps_deg: tuple[float, ...] = (10.0, 30.0)) -> Figure:
    """Heading step responses of the closed loop (nonlinear plant) with the ±1° band."""
    seconds = 15.0
    n = round(seconds / plant.dt_s)
    t = plant.dt_s * np.arange(n + 1)
    fig, (ax_psi, ax_act) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for deg in steps_deg:
        state = plant.initial_state(np.zeros((1, 3)))
        _, traj = plant.step(state, math.radians(deg), n_steps=n)
        psi = np.concatenate([[0.0], np.degrees(traj[0, :, 2])])
        psi_d = np.concatenate([[0.0], np.degrees(traj[0, :, 8])])
        (line,) = ax_psi.plot(t, psi, label=f"ψ, {deg:g}° step")
        if plant.kind == "pid":
            ax_psi.plot(t, psi_d, "--", color=line.get_color(), lw=0.8, label="ψ_d (ref. model)")
        ax_psi.axhspan(deg - 1, deg + 1, color=line.get_color(), alpha=0.12)
        ax_act.plot(t[1:], np.degrees(traj[0, :, 7]), color=line.get_color(), label=f"{deg:g}°")
    ax_psi.axvline(2.0, color="k", lw=0.6, ls=":")
    ax_psi.set_ylabel("heading (deg)")
    ax_psi.set_title(
        f"{plant.vessel.name}, {plant.kind} autopilot, "
        f"{plant.cruise_speed_mps:g} m/s: heading steps (band ±1°)"
    )
    ax_psi.legend(fontsize=8)
    unit = "deg" if plant.vessel.actuation.kind == "waterjet" else "N"
    ax_act.set_ylabel(f"steering actuator a2 ({unit})")
    ax_act.set_xlabel("time (s)")
    fig.tight_layout()
    return fig


def bode_figure(plant: Plant) -> Figure:
    """Bode plot of the open heading loop L(s) = C(s) G(s) with gain and phase margins."""
    import control

    from usvsim.vessel.autopilot import loop_transfer

    loop = loop_transfer(plant.vessel, plant.design, plant.dt_s)
    plt.figure(figsize=(7, 6))
    control.bode_plot(loop, omega=np.logspace(-3, 2, 400), display_margins=True)
    fig = plt.gcf()
    fig.suptitle(f"{plant.vessel.name}: full heading loop (PID × sway–yaw × actuator × delay)")
    return fig


def kalman_figure(seed: int = 0, seconds: float = 120.0) -> Figure:
    """Kalman-filter estimate vs raw GPS on a box manoeuvre of the default vessel.

    The raw GPS shown is an independent draw at the same noise level as the filter's input.
    """
    from usvsim.nav.filter import Navigator
    from usvsim.nav.models import NavConfig

    plant = Plant("default")
    rng = np.random.default_rng(seed)
    cfg = NavConfig()
    nav = Navigator(cfg, 1)
    state = plant.initial_state(np.zeros((1, 3)))
    nav.reset(state.eta, state.nu, rng)
    n_decisions = round(seconds / 2.0)
    true, est, gps = [], [], []
    for k in range(n_decisions):  # box: 90° to starboard every 30 s
        psi_ref = math.radians(90.0 * ((k // 15) % 4))
        state, traj = plant.step(state, psi_ref, n_steps=20)
        estimate = nav.run(traj[:, :, 0:3], traj[:, :, 3:6], rng, first_step_index=20 * k + 1)
        true.append(traj[0, :, 0:2])
        est.append(estimate.pos_ne[0])
        gps.append(traj[0, :, 0:2] + rng.normal(0.0, cfg.sensors.gps_sigma_m, (20, 2)))
    true_xy, est_xy, gps_xy = (np.concatenate(a) for a in (true, est, gps))
    gps_xy = gps_xy[1::2]  # 5 Hz fixes
    rmse_est = math.sqrt(np.mean(np.sum((est_xy - true_xy) ** 2, axis=1)))
    rmse_gps = math.sqrt(np.mean(np.sum((gps_xy - true_xy[1::2]) ** 2, axis=1)))
    fig, ax = plt.subplots(figsize=(7, 5))
    ax.plot(
        gps_xy[:, 1],
        gps_xy[:, 0],
        ".",
        ms=2,
        color="0.6",
        label=f"raw GPS (5 Hz, RMSE {rmse_gps:.2f} m)",
    )
    ax.plot(true_xy[:, 1], true_xy[:, 0], "k-", lw=1.0, label="true path")
    ax.plot(
        est_xy[:, 1], est_xy[:, 0], "-", lw=1.0, label=f"Kalman estimate (RMSE {rmse_est:.2f} m)"
    )
    ax.set_aspect("equal")
    ax.set_xlabel("y east (m)")
    ax.set_ylabel("x north (m)")
    ax.set_title("Navigation: Kalman filter vs raw GPS (box manoeuvre)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def manoeuvre_figure(report: TrialReport) -> Figure:
    """The trials of one vessel: turning circle (in boat lengths), both zig-zags, stopping."""
    L = report.length_m
    fig, axes = plt.subplots(2, 2, figsize=(10, 8))
    ax = axes[0, 0]
    tc = report.turning
    ax.plot(tc.path[:, 1] / L, tc.path[:, 0] / L, lw=1.2)
    ax.plot([0], [0], "ko")
    ax.set_aspect("equal")
    ax.set_xlabel("transfer (L)")
    ax.set_ylabel("advance (L)")
    ax.set_title(
        f"turning circle, max helm: D_T {tc.tactical_diameter_m / L:.2f} L, "
        f"R {tc.steady_radius_m / L:.2f} L, β {tc.drift_angle_deg:.0f}°"
    )
    for ax, z in ((axes[0, 1], report.zigzag10), (axes[1, 0], report.zigzag20)):
        ax.plot(z.t_s, z.heading_deg, label="heading change ψ")
        ax.plot(z.t_s, z.helm_deg_t, "--", label="helm δ")
        ax.axhline(z.helm_deg, color="0.6", lw=0.6)
        ax.axhline(-z.helm_deg, color="0.6", lw=0.6)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("deg")
        ax.set_title(
            f"{z.helm_deg:g}°/{z.helm_deg:g}° zig-zag: overshoots "
            f"{z.first_overshoot_deg:.1f}° / {z.second_overshoot_deg:.1f}°"
        )
        ax.legend(fontsize=8)
    ax = axes[1, 1]
    st = report.stopping
    ax.plot(st.t_s, st.surge_mps)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("surge u (m/s)")
    mode = "full astern" if st.astern else "coasting (no astern)"
    ax.set_title(f"stopping, {mode}: track reach {st.track_reach_m / L:.2f} L in {st.time_s:.1f} s")
    fig.suptitle(f"{report.vessel}: manoeuvring trials at {report.speed_mps:g} m/s (open loop)")
    fig.tight_layout()
    return fig


def save_plant_plots(plant: Plant, out_dir: str | Path) -> list[Path]:
    """Write all plant plots as PNG into ``out_dir``; returns the paths."""
    out = Path(out_dir)
    figures = {
        "turning_circle.png": turning_circle_figure(plant),
        "heading_steps.png": heading_step_figure(plant),
        "bode.png": bode_figure(plant),
        "kalman_vs_gps.png": kalman_figure(),
    }
    paths = []
    for name, fig in figures.items():
        atomic_savefig(fig, out / name, dpi=120)
        plt.close(fig)
        paths.append(out / name)
    return paths
