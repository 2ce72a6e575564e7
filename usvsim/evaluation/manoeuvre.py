"""Standard manoeuvring trials of a vessel, open loop: turning circle, zig-zags, stopping.

The trials follow the IMO Standards for Ship Manoeuvrability (resolution MSC.137(76), 2002,
and its explanatory notes MSC/Circ.1053): approach on a straight course at the test speed with
the thrust held at its trim value, then a fixed helm programme, with no autopilot.

* **Turning circle** at maximum helm: *advance* (distance along the approach course, from the
  helm order to 90° heading change), *transfer* (sideways at 90°), *tactical diameter*
  (sideways at 180°), steady radius R = U / r, speed loss U / U₀, drift angle β = atan2(v, u)
  (reported bow-in positive), all in the steady part (heading change 360°–540°).
* **Z-manoeuvre** δ/ψ (10°/10°, 20°/20°): helm δ to starboard; when the heading has changed ψ
  (second execute), helm δ to port; when it has changed -ψ (third execute), to starboard. First
  overshoot: largest heading beyond +ψ after the second execute; second: beyond -ψ after the
  third. *Initial turning*: distance run until the second execute of the 10°/10° test.
* **Stopping** (crash stop): full astern from the test speed, helm amidships; *track reach* is
  the distance along the path until the surge speed is 0 (or below 5 % of the approach speed
  when the vessel has no astern thrust).

"Helm δ" is the nozzle angle for a waterjet; for a lateral-force actuator it is the fraction
δ / 30° of the largest force (as in the hull audit), signed so that positive helm turns to
starboard.

IMO criteria (reference column; upper bounds for ships, not a realism test of small craft):
advance ≤ 4.5 L, tactical diameter ≤ 5 L, initial turning ≤ 2.5 L, 10°/10° first overshoot
≤ 10° and second ≤ 25° (L/U < 10 s), 20°/20° first overshoot ≤ 25°, track reach ≤ 15 L.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.vessel.model import build_dynamics, build_rk4_step, surge_trim
from usvsim.vessel.vessels import Actuation, VesselParams

__all__ = [
    "IMO_LIMITS",
    "Stopping",
    "TrialReport",
    "TurningCircle",
    "ZigZag",
    "helm_command",
    "run_trials",
    "stopping_trial",
    "trials_summary",
    "trials_table",
    "turning_circle",
    "zigzag",
]

# IMO MSC.137(76), §5.2 (L/U < 10 s for the overshoots)
IMO_LIMITS = {
    "advance_L": 4.5,
    "tactical_diameter_L": 5.0,
    "initial_turning_L": 2.5,
    "zigzag10_first_deg": 10.0,
    "zigzag10_second_deg": 25.0,
    "zigzag20_first_deg": 25.0,
    "track_reach_L": 15.0,
}


@dataclass(frozen=True)
class TurningCircle:
    """Turning circle at maximum helm (see module docstring). Lengths in m, angles in deg."""

    speed_mps: float  # approach speed
    advance_m: float
    transfer_m: float
    tactical_diameter_m: float
    steady_radius_m: float
    speed_ratio: float  # steady U / U0
    drift_angle_deg: float  # steady β, bow-in positive
    steady_yaw_rate_deg_s: float
    min_surge_mps: float  # smallest u during the whole trial
    path: NDArray[np.float64]  # (T, 2) [x along approach, y to starboard] in m


@dataclass(frozen=True)
class ZigZag:
    """Z-manoeuvre δ/ψ (see module docstring)."""

    helm_deg: float
    first_overshoot_deg: float
    second_overshoot_deg: float
    time_to_second_execute_s: float
    initial_turning_m: float  # distance run until the second execute
    t_s: NDArray[np.float64]  # (T,)
    heading_deg: NDArray[np.float64]  # (T,) heading change
    helm_deg_t: NDArray[np.float64]  # (T,) helm ordered


@dataclass(frozen=True)
class Stopping:
    """Crash stop from the approach speed (see module docstring)."""

    track_reach_m: float
    head_reach_m: float  # along the approach course
    time_s: float
    astern: bool  # False: no astern thrust, the vessel coasts
    t_s: NDArray[np.float64]
    surge_mps: NDArray[np.float64]


@dataclass(frozen=True)
class TrialReport:
    """All trials of one vessel at one speed."""

    vessel: str
    length_m: float
    speed_mps: float
    turning: TurningCircle
    zigzag10: ZigZag
    zigzag20: ZigZag
    stopping: Stopping


def helm_command(act: Actuation, helm_deg: float) -> float:
    """Steering actuator value (rad or N) for helm ``helm_deg`` (positive: to starboard)."""
    if act.kind == "waterjet":
        return float(np.clip(math.radians(helm_deg), act.a2_min, act.a2_max))
    frac = float(np.clip(helm_deg / 30.0, -1.0, 1.0))
    return frac * act.a2_max * (1.0 if act.lever_m > 0 else -1.0)


class _OpenLoop:
    """The vessel ODE with RK4 over dt_s, N boats per call (F.map), actuator commands held."""

    def __init__(self, vessel: VesselParams, dt_s: float, n: int) -> None:
        self.vessel = vessel
        self.dt_s = dt_s
        self.F = build_rk4_step(build_dynamics(vessel), dt_s).map(n)
        u = ca.SX.sym("u")
        self._trim = ca.Function("trim", [u], [surge_trim(vessel, u)])

    def start(self, speeds: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Initial states (N, 8) straight ahead at ``speeds`` and their trim thrust (N,)."""
        act = self.vessel.actuation
        thrust = np.clip(np.asarray(self._trim(speeds[None, :])).ravel(), act.a1_min, act.a1_max)
        x = np.zeros((speeds.size, 8))
        x[:, 3] = speeds
        x[:, 6] = thrust
        return x, thrust

    def step(self, x: NDArray[np.float64], a_cmd: NDArray[np.float64]) -> NDArray[np.float64]:
        """One step of all boats: x (N, 8), a_cmd (N, 2)."""
        return np.asarray(self.F(x.T, a_cmd.T, np.zeros((2, x.shape[0])))).T


def turning_circle(
    vessel: VesselParams, speeds_mps: tuple[float, ...], dt_s: float = 0.1, max_s: float = 600.0
) -> list[TurningCircle]:
    """Turning circles at maximum starboard helm from each approach speed (one batch)."""
    speeds = np.asarray(speeds_mps, dtype=float)
    sim = _OpenLoop(vessel, dt_s, speeds.size)
    x, thrust = sim.start(speeds)
    a = np.stack([thrust, np.full(speeds.size, helm_command(vessel.actuation, 90.0))], axis=1)
    n = round(max_s / dt_s)
    traj = np.empty((n + 1, speeds.size, 8))
    traj[0] = x
    heading = np.zeros(speeds.size)
    k = 0
    while k < n and np.any(heading < math.radians(540.0)):
        psi_old = x[:, 2]
        x = sim.step(x, a)
        heading = heading + (x[:, 2] - psi_old)  # the model does not wrap ψ
        k += 1
        traj[k] = x
    traj = traj[: k + 1]
    out = []
    for i, U0 in enumerate(speeds):
        xs = traj[:, i]
        dpsi = xs[:, 2] - xs[0, 2]
        at90 = int(np.argmax(dpsi >= math.pi / 2))
        at180 = int(np.argmax(dpsi >= math.pi))
        steady = (dpsi >= 2 * math.pi) & (dpsi <= 3 * math.pi)
        if not np.any(steady):  # never completed a circle: report the last tenth
            steady = np.arange(len(xs)) >= 0.9 * len(xs)
        u, v, r = xs[steady, 3], xs[steady, 4], xs[steady, 5]
        U = np.hypot(u, v)
        r_mean = float(np.mean(r))
        beta = np.arctan2(v, u)
        out.append(
            TurningCircle(
                speed_mps=float(U0),
                advance_m=float(xs[at90, 0]) if at90 else math.nan,
                transfer_m=float(xs[at90, 1]) if at90 else math.nan,
                tactical_diameter_m=float(xs[at180, 1]) if at180 else math.nan,
                steady_radius_m=float(np.mean(U) / abs(r_mean)) if r_mean else math.inf,
                speed_ratio=float(np.mean(U) / U0),
                drift_angle_deg=float(-np.sign(r_mean) * math.degrees(float(np.mean(beta)))),
                steady_yaw_rate_deg_s=math.degrees(r_mean),
                min_surge_mps=float(xs[:, 3].min()),
                path=xs[:, 0:2].copy(),
            )
        )
    return out


def zigzag(
    vessel: VesselParams, speed_mps: float, helm_deg: float, dt_s: float = 0.1, max_s: float = 200.0
) -> ZigZag:
    """Z-manoeuvre ``helm_deg``/``helm_deg`` from ``speed_mps`` (see module docstring)."""
    sim = _OpenLoop(vessel, dt_s, 1)
    x, thrust = sim.start(np.array([speed_mps]))
    switch = math.radians(helm_deg)
    side = 1.0
    executes: list[int] = []
    n = round(max_s / dt_s)
    psi = np.zeros(n + 1)
    helm = np.zeros(n + 1)
    dist = np.zeros(n + 1)
    k = 0
    while k < n and len(executes) < 3:
        helm[k] = side * helm_deg
        a = np.array([[thrust[0], helm_command(vessel.actuation, side * helm_deg)]])
        x_new = sim.step(x, a)
        dist[k + 1] = dist[k] + float(np.hypot(*(x_new[0, 0:2] - x[0, 0:2])))
        x = x_new
        k += 1
        psi[k] = x[0, 2]
        if side * psi[k] >= switch:  # heading reached ±ψ: reverse the helm (an execute)
            executes.append(k)
            side = -side
    helm[k] = side * helm_deg
    psi_deg = np.degrees(psi[: k + 1])
    first = second = math.nan
    if len(executes) >= 2:
        first = float(psi_deg[executes[0] : executes[1]].max() - helm_deg)
    if len(executes) >= 3:
        second = float(-psi_deg[executes[1] : executes[2]].min() - helm_deg)
    elif len(executes) == 2:
        second = float(-psi_deg[executes[1] :].min() - helm_deg)
    t: NDArray[np.float64] = dt_s * np.arange(k + 1, dtype=float)
    return ZigZag(
        helm_deg=helm_deg,
        first_overshoot_deg=first,
        second_overshoot_deg=second,
        time_to_second_execute_s=float(t[executes[0]]) if executes else math.nan,
        initial_turning_m=float(dist[executes[0]]) if executes else math.nan,
        t_s=t,
        heading_deg=psi_deg,
        helm_deg_t=helm[: k + 1],
    )


def stopping_trial(
    vessel: VesselParams, speed_mps: float, dt_s: float = 0.1, max_s: float = 600.0
) -> Stopping:
    """Crash stop: full astern (or zero thrust without astern), helm amidships."""
    act = vessel.actuation
    sim = _OpenLoop(vessel, dt_s, 1)
    x, _ = sim.start(np.array([speed_mps]))
    astern = act.a1_min < 0
    a = np.array([[act.a1_min if astern else max(act.a1_min, 0.0), helm_command(act, 0.0)]])
    stop_at = 0.0 if astern else 0.05 * speed_mps
    n = round(max_s / dt_s)
    surge = [float(x[0, 3])]
    track = 0.0
    k = 0
    while k < n and x[0, 3] > stop_at:
        x_new = sim.step(x, a)
        track += float(np.hypot(*(x_new[0, 0:2] - x[0, 0:2])))
        x = x_new
        surge.append(float(x[0, 3]))
        k += 1
    return Stopping(
        track_reach_m=track,
        head_reach_m=float(x[0, 0]),
        time_s=k * dt_s,
        astern=astern,
        t_s=np.asarray(dt_s * np.arange(k + 1), dtype=np.float64),
        surge_mps=np.asarray(surge),
    )


def run_trials(vessel: VesselParams, speed_mps: float | None = None) -> TrialReport:
    """All trials at ``speed_mps`` (default: the vessel's cruise speed)."""
    speed = vessel.cruise_speed_mps if speed_mps is None else float(speed_mps)
    return TrialReport(
        vessel=vessel.name,
        length_m=vessel.length_m,
        speed_mps=speed,
        turning=turning_circle(vessel, (speed,))[0],
        zigzag10=zigzag(vessel, speed, 10.0),
        zigzag20=zigzag(vessel, speed, 20.0),
        stopping=stopping_trial(vessel, speed),
    )


def trials_table(reports: list[TrialReport]) -> str:
    """Markdown table: one column per vessel, the IMO MSC.137(76) criterion as the last."""
    rows: list[tuple[str, list[str], str]] = []

    def row(name: str, values: list[float], fmt: str, imo: str) -> None:
        rows.append((name, [format(v, fmt) for v in values], imo))

    L = [r.length_m for r in reports]
    tc = [r.turning for r in reports]
    row("advance (L)", [t.advance_m / n for t, n in zip(tc, L, strict=True)], ".2f", "≤ 4.5")
    row("transfer (L)", [t.transfer_m / n for t, n in zip(tc, L, strict=True)], ".2f", "–")
    row(
        "tactical diameter (L)",
        [t.tactical_diameter_m / n for t, n in zip(tc, L, strict=True)],
        ".2f",
        "≤ 5",
    )
    row(
        "steady radius (L)", [t.steady_radius_m / n for t, n in zip(tc, L, strict=True)], ".2f", "–"
    )
    row("speed in turn / approach", [t.speed_ratio for t in tc], ".2f", "–")
    row("drift angle, bow-in (deg)", [t.drift_angle_deg for t in tc], ".1f", "–")
    row("r' = r L / U in turn", [_r_prime(r) for r in reports], ".2f", "–")
    row("min surge in turn (m/s)", [t.min_surge_mps for t in tc], ".2f", "> 0")
    z10 = [r.zigzag10 for r in reports]
    z20 = [r.zigzag20 for r in reports]
    row("10/10 first overshoot (deg)", [z.first_overshoot_deg for z in z10], ".1f", "≤ 10")
    row("10/10 second overshoot (deg)", [z.second_overshoot_deg for z in z10], ".1f", "≤ 25")
    row("10/10 time to 2nd execute (s)", [z.time_to_second_execute_s for z in z10], ".1f", "–")
    row(
        "initial turning (L)",
        [z.initial_turning_m / n for z, n in zip(z10, L, strict=True)],
        ".2f",
        "≤ 2.5",
    )
    row("20/20 first overshoot (deg)", [z.first_overshoot_deg for z in z20], ".1f", "≤ 25")
    row("20/20 second overshoot (deg)", [z.second_overshoot_deg for z in z20], ".1f", "–")
    row("20/20 time to 2nd execute (s)", [z.time_to_second_execute_s for z in z20], ".1f", "–")
    row(
        "stopping track reach (L)",
        [r.stopping.track_reach_m / r.length_m for r in reports],
        ".2f",
        "≤ 15",
    )
    row("stopping time (s)", [r.stopping.time_s for r in reports], ".1f", "–")
    head = ["trial"] + [f"{r.vessel} {r.speed_mps:g} m/s" for r in reports] + ["IMO MSC.137(76)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name, values, imo in rows:
        lines.append("| " + " | ".join([name, *values, imo]) + " |")
    astern = ", ".join(
        f"{r.vessel}: {'astern' if r.stopping.astern else 'coasting'}" for r in reports
    )
    lines.append("")
    lines.append(
        f"Stopping: {astern}. Helm for force actuators: δ/30° of the largest lateral force."
    )
    return "\n".join(lines)


def trials_summary(report: TrialReport) -> str:
    """One line: the headline figures of ``report`` (for ``usvsim demo``)."""
    L = report.length_m
    t, z = report.turning, report.zigzag10
    return (
        f"trials at {report.speed_mps:g} m/s: tactical diameter {t.tactical_diameter_m / L:.2f} L "
        f"(IMO ≤ 5), steady radius {t.steady_radius_m / L:.2f} L, speed in turn "
        f"{t.speed_ratio:.2f}, drift {t.drift_angle_deg:.0f}° bow-in; 10/10 overshoots "
        f"{z.first_overshoot_deg:.1f}° / {z.second_overshoot_deg:.1f}° (IMO ≤ 10 / 25); "
        f"stopping {report.stopping.track_reach_m / L:.2f} L (IMO ≤ 15)"
    )


def _r_prime(report: TrialReport) -> float:
    t = report.turning
    U = t.speed_ratio * t.speed_mps
    return abs(math.radians(t.steady_yaw_rate_deg_s)) * report.length_m / U
