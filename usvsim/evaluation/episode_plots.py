"""Plots of one evaluated episode (PNG via matplotlib's Agg backend).

:func:`plot_episode`: the true path with start, pole and goal marked as in the study's figures
(start ●, pole ✕ with its 10 m safety circle, goal ★ with its 10 m goal circle; north up, east
right), the actions (heading changes) and the two reward terms over time.
:func:`plot_radar_strip`: the radar images the boat saw at a few decisions, re-rendered from the
recorded navigation estimate.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from usvsim.common.mpl import use_file_backend_if_headless
from usvsim.evaluation.episodes import EpisodeRecord
from usvsim.task.observations import relative_polar
from usvsim.task.radar import RadarConfig, render_radar
from usvsim.task.scenario import Scenario

use_file_backend_if_headless()  # before any figure: files only when headless

__all__ = ["plot_episode", "plot_radar_strip"]


def _save(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_episode(
    record: EpisodeRecord, path: str | Path | None = None, scenario: Scenario | None = None
) -> Figure:
    """Path, actions and reward terms of ``record``; saved as PNG when ``path`` is given."""
    sc = scenario or Scenario()
    fig, (ax_path, ax_act, ax_rew) = plt.subplots(
        1, 3, figsize=(14, 4.5), gridspec_kw={"width_ratios": [1.3, 1, 1]}
    )
    xy = record.trajectory[:, :2]
    pole, goal = record.pole_ne, record.goal_ne
    # east on the horizontal axis, north up (plot y_E, x_N)
    ax_path.plot(xy[:, 1], xy[:, 0], lw=1.5, label="path (true)")
    ax_path.plot(
        record.est_pose[:, 1],
        record.est_pose[:, 0],
        ".",
        ms=3,
        color="0.5",
        label="estimate at decisions",
    )
    ax_path.plot(xy[0, 1], xy[0, 0], "o", color="tab:green", label="start")
    ax_path.plot(pole[1], pole[0], "x", color="tab:red", ms=9, mew=2, label="pole")
    ax_path.plot(goal[1], goal[0], "*", color="tab:orange", ms=13, label="goal")
    t = np.linspace(0.0, 2.0 * math.pi, 100)
    for centre, radius, colour in (
        (pole, sc.safety_distance_m, "tab:red"),
        (goal, sc.goal_radius_m, "tab:orange"),
    ):
        ax_path.plot(
            centre[1] + radius * np.sin(t),
            centre[0] + radius * np.cos(t),
            "--",
            lw=0.8,
            color=colour,
        )
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set(
        xlabel="east y_E (m)",
        ylabel="north x_N (m)",
        title=f"{record.outcome}, min pole distance {record.min_pole_distance_m:.1f} m",
    )
    ax_path.legend(fontsize=7, loc="best")

    t_dec = sc.decision_period_s * np.arange(record.n_decisions)
    ax_act.step(t_dec, np.degrees(record.actions_rad), where="post")
    ax_act.axhline(0.0, color="0.7", lw=0.8)
    lim = math.degrees(sc.max_heading_change_rad)
    ax_act.set(
        xlabel="time (s)",
        ylabel="heading change Δψ (°)",
        ylim=(-1.1 * lim, 1.1 * lim),
        title="actions",
    )
    t_end = t_dec + sc.decision_period_s
    ax_rew.plot(t_end, record.reward_pole, label="r_pole")
    ax_rew.plot(t_end, record.reward_goal, label="r_goal")
    ax_rew.plot(t_end, record.reward_pole + record.reward_goal, "k", lw=0.8, label="r")
    ax_rew.set(xlabel="time (s)", ylabel="reward", title="reward terms")
    ax_rew.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def plot_radar_strip(
    record: EpisodeRecord,
    path: str | Path | None = None,
    n_frames: int = 6,
    scenario: Scenario | None = None,
    radar: RadarConfig | None = None,
) -> Figure:
    """``n_frames`` radar images at evenly spaced decisions of ``record`` (from its estimates)."""
    sc = scenario or Scenario()
    radar = radar or RadarConfig()
    k = np.unique(np.linspace(0, record.n_decisions, n_frames).round().astype(int))
    pose = record.est_pose[k]
    r, b = relative_polar(pose[:, :2], pose[:, 2], np.repeat(record.pole_ne[None], k.size, 0))
    images = render_radar(r, b, sc.pole_radius_m, radar)
    fig, axes = plt.subplots(1, k.size, figsize=(2.4 * k.size, 2.2), squeeze=False)
    fov = math.degrees(radar.half_fov_rad)
    for ax, img, kk in zip(axes[0], images, k, strict=True):
        ax.imshow(
            img[0],
            cmap="gray",
            vmin=0,
            vmax=255,
            origin="lower",
            aspect="auto",
            extent=(-fov, fov, 0.0, radar.max_range_m),
        )
        ax.set_title(f"t = {kk * sc.decision_period_s:.0f} s", fontsize=9)
        ax.set_xlabel("bearing (°)", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0, 0].set_ylabel("range (m)", fontsize=8)
    fig.tight_layout()
    return _save(fig, path)
