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

**In wind and waves** (``weather``, :class:`TrialWeather`): the vessel model takes the wind and
wave drift loads of :mod:`usvsim.vessel.weather.loads` (usv105's windage and waterline, for
every vessel), the gusts and the first-order wave motion advance per step (seeded). The helm
executes on the *sensed* heading (true + wave yaw, what a compass shows); overshoots are read from
the true heading. The turning circle runs two full turns: the *circle drift* is the displacement
between the points where the heading change passes 360° and 720°, over the time between (the
speed and direction at which the circle's centre moves). :func:`wave_filter_activity` measures
the closed-loop nozzle activity with and without the autopilot's wave filter
(:mod:`usvsim.vessel.weather_plant`). Without weather every number is today's (same code path).

Why this module is long: the trials in calm water and in weather share one open-loop simulator,
one set of trial definitions and one table; splitting them would restate the trials.

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

from usvsim.common.angles import ssa
from usvsim.vessel.model import build_dynamics, build_rk4_step, rk4_expr, surge_trim
from usvsim.vessel.vessels import Actuation, VesselParams
from usvsim.vessel.weather.loads import USV105_HULL, environment_loads
from usvsim.vessel.weather.waves import (
    drift_pressure,
    sea_state_from_code,
    wave_displacement,
    wave_motion_init,
    wave_motion_step,
    wave_response,
)
from usvsim.vessel.weather.wind import GustParams, WindState, gust_step
from usvsim.vessel.weather_plant import SeaConditions

__all__ = [
    "IMO_LIMITS",
    "NozzleActivity",
    "Stopping",
    "TrialReport",
    "TrialWeather",
    "TurningCircle",
    "ZigZag",
    "helm_command",
    "run_trials",
    "stopping_trial",
    "trials_summary",
    "trials_table",
    "turning_circle",
    "wave_filter_activity",
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
    drift_mps: float = math.nan  # in weather: speed of the circle's centre (m/s)
    drift_towards_deg: float = math.nan  # in weather: its direction, clockwise from north


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
class TrialWeather:
    """Wind and sea of the trials; the approach course is north."""

    wind_speed_mps: float = 0.0  # m/s, mean
    wind_from_deg: float = 90.0  # deg, where the wind blows from, clockwise from north
    sea_state: int = 0  # WMO code 0-8 (Bales 1983 H_s, T_p); waves come from the wind's side
    gust_intensity: float = GustParams().intensity  # -, σ_g / V̄
    seed: int = 0  # gusts and wave motion

    @property
    def calm(self) -> bool:
        return self.wind_speed_mps == 0.0 and self.sea_state == 0

    def conditions(self, n: int) -> SeaConditions:
        """The weather of ``n`` boats (directions the wind and waves go *towards*, rad)."""
        towards = math.radians(self.wind_from_deg + 180.0)
        sea = sea_state_from_code(self.sea_state, towards)
        return SeaConditions.uniform(n, self.wind_speed_mps, towards, sea, self.gust_intensity)

    def label(self) -> str:
        return (
            f"wind {self.wind_speed_mps:g} m/s from {self.wind_from_deg:g}°, "
            f"sea state {self.sea_state}"
        )


@dataclass(frozen=True)
class NozzleActivity:
    """Closed-loop heading keeping in weather: the autopilot's nozzle and the heading it keeps."""

    rate_rms_deg_s: float  # RMS of the nozzle's rate (°/s)
    rms_deg: float  # RMS of the nozzle angle (°)
    heading_error_rms_deg: float  # RMS of the true heading's error (°)


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
    weather: TrialWeather | None = None
    nozzle_unfiltered: NozzleActivity | None = None  # in waves: without the wave filter
    nozzle_filtered: NozzleActivity | None = None  # and with it


def helm_command(act: Actuation, helm_deg: float) -> float:
    """Steering actuator value (rad or N) for helm ``helm_deg`` (positive: to starboard)."""
    if act.kind == "waterjet":
        return float(np.clip(math.radians(helm_deg), act.a2_min, act.a2_max))
    frac = float(np.clip(helm_deg / 30.0, -1.0, 1.0))
    return frac * act.a2_max * (1.0 if act.lever_m > 0 else -1.0)


class _OpenLoop:
    """The vessel ODE with RK4 over dt_s, N boats per call (F.map), actuator commands held;
    in ``weather``, the environmental loads at each step's start, gusts and wave motion."""

    def __init__(
        self, vessel: VesselParams, dt_s: float, n: int, weather: TrialWeather | None = None
    ) -> None:
        self.vessel = vessel
        self.dt_s = dt_s
        self.weather = None if weather is None or weather.calm else weather
        if self.weather is None:
            self.F = build_rk4_step(build_dynamics(vessel), dt_s).map(n)
        else:
            self._start_weather(self.weather, n)
        u = ca.SX.sym("u")
        self._trim = ca.Function("trim", [u], [surge_trim(vessel, u)])

    def _start_weather(self, weather: TrialWeather, n: int) -> None:
        x, a, q = ca.SX.sym("x", 8), ca.SX.sym("a", 2), ca.SX.sym("q", 4)
        tau = environment_loads(USV105_HULL, x[3:6], x[2], q[0], q[1], q[2], q[3])
        x_next = rk4_expr(
            build_dynamics(self.vessel, weather=True), x, a, ca.vertcat(0, 0, tau), self.dt_s
        )
        self.F = ca.Function("Fw", [x, a, q], [x_next]).map(n)
        cond = weather.conditions(n)
        self.rng = np.random.default_rng(weather.seed)
        self.gusts = GustParams(intensity=weather.gust_intensity)
        self.wind = WindState(cond.wind_speed_mps, cond.wind_dir_rad, np.zeros(n))
        self.wind = gust_step(self.wind, self.rng, 1e9, self.gusts)  # a stationary draw
        self.sea = cond
        self.waves = wave_response(cond.hs_m, cond.tp_s)
        self.xi = wave_motion_init(self.rng, self.waves)
        self.q = np.stack(
            [
                self.wind.speed_mps,
                cond.wind_dir_rad,
                np.where(cond.hs_m > 0, drift_pressure(cond.hs_m, cond.tp_s), 0.0),
                cond.wave_dir_rad,
            ]
        )

    def sensed_heading(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """The compass heading (N,): ψ plus the first-order wave yaw in waves."""
        if self.weather is None:
            return x[:, 2]
        dpsi = wave_displacement(self.xi, self.waves, self.sea.wave_dir_rad, x[:, 2])[:, 2]
        return np.asarray(x[:, 2] + dpsi)

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
        if self.weather is None:
            return np.asarray(self.F(x.T, a_cmd.T, np.zeros((2, x.shape[0])))).T
        x_next = np.asarray(self.F(x.T, a_cmd.T, self.q)).T
        self.wind = gust_step(self.wind, self.rng, self.dt_s, self.gusts)
        self.q[0] = self.wind.speed_mps
        self.xi = wave_motion_step(self.xi, self.rng, self.waves, self.dt_s)
        return x_next


def turning_circle(
    vessel: VesselParams,
    speeds_mps: tuple[float, ...],
    dt_s: float = 0.1,
    max_s: float = 600.0,
    weather: TrialWeather | None = None,
) -> list[TurningCircle]:
    """Turning circles at maximum starboard helm from each approach speed (one batch)."""
    speeds = np.asarray(speeds_mps, dtype=float)
    sim = _OpenLoop(vessel, dt_s, speeds.size, weather)
    turns = 540.0 if sim.weather is None else 720.0  # deg of heading change to run
    x, thrust = sim.start(speeds)
    a = np.stack([thrust, np.full(speeds.size, helm_command(vessel.actuation, 90.0))], axis=1)
    n = round(max_s / dt_s)
    traj = np.empty((n + 1, speeds.size, 8))
    traj[0] = x
    heading = np.zeros(speeds.size)
    k = 0
    while k < n and np.any(heading < math.radians(turns)):
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
        drift = _circle_drift(xs, dt_s) if sim.weather is not None else (math.nan, math.nan)
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
                drift_mps=drift[0],
                drift_towards_deg=drift[1],
            )
        )
    return out


def _circle_drift(xs: NDArray[np.float64], dt_s: float) -> tuple[float, float]:
    """Speed (m/s) and direction (deg, towards, clockwise from north) of the circle's centre:
    the displacement between the heading changes 360° and 720°, over the time between."""
    dpsi = xs[:, 2] - xs[0, 2]
    k1, k2 = int(np.argmax(dpsi >= 2 * math.pi)), int(np.argmax(dpsi >= 4 * math.pi))
    if not (k1 and k2):
        return math.nan, math.nan
    d = xs[k2, 0:2] - xs[k1, 0:2]
    return float(np.hypot(*d) / ((k2 - k1) * dt_s)), math.degrees(math.atan2(d[1], d[0])) % 360


def zigzag(
    vessel: VesselParams,
    speed_mps: float,
    helm_deg: float,
    dt_s: float = 0.1,
    max_s: float = 200.0,
    weather: TrialWeather | None = None,
) -> ZigZag:
    """Z-manoeuvre ``helm_deg``/``helm_deg`` from ``speed_mps`` (see module docstring)."""
    sim = _OpenLoop(vessel, dt_s, 1, weather)
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
        if side * sim.sensed_heading(x)[0] >= switch:  # heading reached ±ψ: reverse the helm
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
    vessel: VesselParams,
    speed_mps: float,
    dt_s: float = 0.1,
    max_s: float = 600.0,
    weather: TrialWeather | None = None,
) -> Stopping:
    """Crash stop: full astern (or zero thrust without astern), helm amidships."""
    act = vessel.actuation
    sim = _OpenLoop(vessel, dt_s, 1, weather)
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


def run_trials(
    vessel: VesselParams, speed_mps: float | None = None, weather: TrialWeather | None = None
) -> TrialReport:
    """All trials at ``speed_mps`` (default: the vessel's cruise speed), in ``weather``; in
    waves also the nozzle activity with and without the wave filter."""
    speed = vessel.cruise_speed_mps if speed_mps is None else float(speed_mps)
    activity: tuple[NozzleActivity | None, NozzleActivity | None] = (None, None)
    if weather is not None and weather.sea_state > 0:
        activity = wave_filter_activity(vessel, speed, weather)
    return TrialReport(
        vessel=vessel.name,
        length_m=vessel.length_m,
        speed_mps=speed,
        turning=turning_circle(vessel, (speed,), weather=weather)[0],
        zigzag10=zigzag(vessel, speed, 10.0, weather=weather),
        zigzag20=zigzag(vessel, speed, 20.0, weather=weather),
        stopping=stopping_trial(vessel, speed, weather=weather),
        weather=None if weather is None or weather.calm else weather,
        nozzle_unfiltered=activity[0],
        nozzle_filtered=activity[1],
    )


def wave_filter_activity(
    vessel: VesselParams,
    speed_mps: float,
    weather: TrialWeather,
    n: int = 16,
    seconds: float = 300.0,
) -> tuple[NozzleActivity, NozzleActivity]:
    """Heading keeping (PID autopilot) of ``n`` boats in ``weather`` for ``seconds`` after 30 s
    of settling, without and with the wave filter: (unfiltered, filtered). The course keeps the
    waves 45° off the quarter (going 135° to the course), where the first-order yaw
    sin 2(β − ψ) is largest; the heading error is the true heading's from that course. The
    nozzle figures are NaN for a vessel without a lagging waterjet nozzle."""
    from usvsim.vessel.autopilot import AutopilotConfig
    from usvsim.vessel.plant import Plant
    from usvsim.vessel.weather_plant import WeatherPlant

    plant = Plant(vessel, AutopilotConfig(cruise_speed_mps=speed_mps))
    cond = weather.conditions(n)
    course = float(ssa(cond.wave_dir_rad[0] - 0.75 * math.pi))
    eta = np.zeros((n, 3))
    eta[:, 2] = course
    out = []
    for on in (False, True):
        sim = WeatherPlant(plant, seed=weather.seed, wave_filter=on)
        state = sim.initial_state(eta, cond)
        state, _ = sim.step(state, course, n_steps=round(30.0 / plant.dt_s))
        _, traj = sim.step(state, course, n_steps=round(seconds / plant.dt_s))
        # the nozzle angle is in the state only for a waterjet whose steering lags (an
        # instantaneous actuator's state does not record the command, a force is not an angle)
        act = vessel.actuation
        nozzle = traj[:, :, 7] if act.kind == "waterjet" and act.lag_s[1] > 0 else np.nan
        rate = np.diff(nozzle, axis=1) / plant.dt_s if np.ndim(nozzle) else np.nan
        err = ssa(traj[:, :, 2] - course)
        out.append(
            NozzleActivity(
                *(math.degrees(float(np.sqrt(np.mean(v**2)))) for v in (rate, nozzle, err))
            )
        )
    return out[0], out[1]


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
    if any(r.weather is not None for r in reports):
        row("circle drift (m/s)", [t.drift_mps for t in tc], ".2f", "–")
        row("circle drift towards (deg)", [t.drift_towards_deg for t in tc], ".0f", "–")
    pairs = [(r.nozzle_unfiltered, r.nozzle_filtered) for r in reports]
    if any(off is not None for off, _ in pairs):
        for name, key, unit in (
            ("nozzle RMS", "rms_deg", "deg"),
            ("nozzle rate RMS", "rate_rms_deg_s", "deg/s"),
            ("heading error RMS", "heading_error_rms_deg", "deg"),
        ):
            for label, pick in (("without", 0), ("with", 1)):
                row(
                    f"{name}, {label} wave filter ({unit})",
                    [getattr(p[pick], key) if p[pick] else math.nan for p in pairs],
                    ".2f",
                    "–",
                )
    head = (
        ["trial"]
        + [f"{r.vessel} {r.speed_mps:g} m/s" + _weather_label(r) for r in reports]
        + ["IMO MSC.137(76)"]
    )
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


def _weather_label(report: TrialReport) -> str:
    return "" if report.weather is None else ", " + report.weather.label()


def _r_prime(report: TrialReport) -> float:
    t = report.turning
    U = t.speed_ratio * t.speed_mps
    return abs(math.radians(t.steady_yaw_rate_deg_s)) * report.length_m / U
