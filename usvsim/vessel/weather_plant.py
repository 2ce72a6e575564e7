"""The batched plant in wind and waves: one compiled step per boat and plant step, no Python loop.

:func:`build_weather_step` extends the closed-loop step of :mod:`usvsim.vessel.plant` with, per
boat (each boat its own weather, as per-boat inputs of the compiled kernel):

1. **Sensed heading and yaw rate** ψ_m = ψ + Δψ_w, r_m = r + Δr_w: the first-order wave-frequency
   yaw of :func:`usvsim.vessel.weather.waves.wave_displacement`, Δψ_w = c_ψ k₀ d sin 2(β_wv − ψ),
   d = ω₀ ξ₀ and Δr_w = c_ψ k₀ ω₀ ξ₁ sin 2(β_wv − ψ) (its rate, ψ̇ in the sine neglected);
2. **Wave filter**: a Kalman observer (:mod:`usvsim.vessel.weather.observer`, Fossen 2021
   §13.3) estimates the low-frequency ψ̂, r̂ from the compass ψ_m and the actuators' yaw moment;
   where a boat's filter is off (input ``wave_filter`` = 0) the autopilot gets ψ_m, r_m exactly;
3. the autopilot (:func:`usvsim.vessel.autopilot.control_law`) on the filtered ψ and r; where
   the filter is on in waves, with its PID's bandwidth at the encounter frequency (inputs
   ``pid_dk*``, :func:`usvsim.vessel.autopilot.wave_mode_gain_changes`; 0 in calm water);
4. one RK4 step of the vessel with current and the environmental load τ_env
   (:func:`usvsim.vessel.model.build_dynamics` with ``weather``): wind V_w = max(V̄ + g, 0) from
   β_w plus the wave drift (:func:`usvsim.vessel.weather.loads.environment_loads` on the
   :class:`usvsim.vessel.weather.loads.WeatherHull`), evaluated at the step's start and held over
   it like the actuator command (the loads change over seconds, the step is 0.1 s; a quarter of
   the cost of evaluating them at every RK4 stage);
5. the gust g (first-order Gauss–Markov, :mod:`usvsim.vessel.weather.wind`) and the wave motion
   state ξ (:func:`usvsim.vessel.weather.waves.wave_motion_discrete`) advanced exactly, driven by
   three innovations per boat and step, √12 (U − ½) of seeded uniforms U: unit variance, so the
   spectra are those of Gaussian noise exactly; the outputs average ≥ 100 innovations, so they
   are Gaussian to the central limit theorem. Uniforms cost a fifth of normals to draw.

No wind, a calm sea and the wave filter off give the plant and autopilot states of
:class:`usvsim.vessel.plant.Plant` bit for bit (tested): every weather term enters as an exact
zero. The wave motion runs at the encounter frequency of the sea's peak for each boat's initial
heading and speed, held for the episode (ASSUMED: a steady course; a turning boat meets a
changing frequency). The observer's wave model uses the same frequency (the autopilot is given
it, as an encounter-frequency estimator would).

Shapes (N boats, T steps): state ``s = [x (8), c (5), m (8)]`` per boat with ``m`` the weather
states :data:`WEATHER_STATES`; per-boat inputs ``w = [ψ_ref, U_ref, V_c, β_c, ...]`` of
:data:`WEATHER_INPUTS`; trajectory (N, T, 13) of [x, c] as the calm plant's, (N, T, 21) on request.

Why this module is long: the step's input layout (:data:`WEATHER_INPUTS`), the function that
fills it and those that read it (the kernel, the sensed offsets, the filter's design line) change
together; split, one layout would be spread over several modules.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.common.angles import ssa_casadi
from usvsim.common.errors import UserError
from usvsim.vessel.autopilot import (
    NG,
    AutopilotDesign,
    AutopilotKind,
    control_law,
    wave_mode_gain_changes,
)
from usvsim.vessel.codegen import BatchStepper
from usvsim.vessel.model import (
    NX,
    build_dynamics,
    generalized_forces,
    rk4_expr,
    saturate_command,
)
from usvsim.vessel.pcg64 import Pcg64Uniforms
from usvsim.vessel.plant import NS, Plant, PlantState
from usvsim.vessel.vessels import VesselParams
from usvsim.vessel.weather.loads import (
    USV105_HULL,
    WeatherHull,
    relative_drift_loads,
    relative_trig,
    relative_wind_loads,
)
from usvsim.vessel.weather.observer import (
    OBSERVER_STATES,
    ObserverNoise,
    observer_correct,
    observer_gains,
    observer_predict,
    wrap_difference,
)
from usvsim.vessel.weather.start_kernel import compiled_wave_start
from usvsim.vessel.weather.turning import steady_turn_damping
from usvsim.vessel.weather.waves import (
    HS_MAX_M,
    SeaState,
    WaveResponse,
    drift_pressure,
    encounter_response,
    wave_motion_discrete,
    wave_motion_init,
)
from usvsim.vessel.weather.wind import WIND_SPEED_MAX_MPS, GustParams

__all__ = [
    "WEATHER_INPUTS",
    "WEATHER_STATES",
    "SeaConditions",
    "WeatherPlant",
    "WeatherPlantState",
    "build_weather_step",
    "sensed_offsets",
    "sensed_offsets_expr",
    "wave_filter_design",
    "wave_offsets",
]

#: Per-boat inputs of the weather step, in order (the first four are the calm plant's).
WEATHER_INPUTS = (
    "psi_ref",  # rad
    "speed_ref",  # m/s
    "current_speed",  # m/s
    "current_dir",  # rad, towards
    "wind_mean",  # m/s, V̄
    "wind_dir",  # rad, towards
    "gust_a",  # -, exp(-Δt / T_g)
    "gust_gain",  # m/s, σ_g √(1 − a²)
    "drift_pressure",  # N/m, p_d
    "wave_dir",  # rad, towards
    "wave_omega",  # rad/s, ω₀ of the wave motion (encounter frequency)
    # cos and sin of wind_dir and wave_dir, once per episode: with cos ψ and sin ψ of the
    # vessel's kinematics they give the relative directions without a trigonometric call
    "wind_cos",
    "wind_sin",
    "wave_cos",
    "wave_sin",
    "phi00",  # Φ, exact transition of the wave motion filter
    "phi01",
    "phi10",
    "phi11",
    "l00",  # L, lower Cholesky factor of its process noise covariance
    "l10",
    "l11",
    "yaw_gain",  # -, c_ψ
    "wave_filter",  # 1: the autopilot gets the observer's estimate, 0: the compass and gyro
    # steady-state Kalman gains of the observer, per state (OBSERVER_STATES) and measurement
    *(f"gain_{k}_{y}" for k in OBSERVER_STATES for y in ("compass", "gyro")),
    # the PID's wave design minus its calm one (autopilot.wave_mode_gain_changes; 0: calm)
    "pid_dkp",  # N m/rad
    "pid_dkd",  # N m s/rad
    "pid_dki",  # N m/(rad s)
)
#: Weather states per boat, in order (after the calm plant's 13).
WEATHER_STATES = (
    "gust",  # m/s
    "xi0",  # wave motion filter state; d = ω₀ ξ₀ (m)
    "xi1",  # its derivative, the wave elevation (m)
    *(f"obs_{k}" for k in OBSERVER_STATES),  # the wave filter's prior (observer module)
)
NWI, NWS = len(WEATHER_INPUTS), len(WEATHER_STATES)
_I = {name: i for i, name in enumerate(WEATHER_INPUTS)}
#: Column of each weather input in the per-episode rows (:attr:`WeatherPlantState.inputs`,
#: the inputs from ``wind_mean`` on).
_COL = {name: i - 4 for name, i in _I.items()}
_S = {name: NS + i for i, name in enumerate(WEATHER_STATES)}
G = 9.81  # m/s², as usvsim.vessel.weather.waves


def build_weather_step(
    vessel: VesselParams,
    kind: AutopilotKind,
    dt_s: float,
    yaw_model: tuple[float, float],
    hull: WeatherHull = USV105_HULL,
    innovations: Literal["uniform", "normal"] = "uniform",
    turn_damping: float = 0.0,
) -> ca.Function:
    """``step(s[21], w[37], g[NG], e[3]) -> s_next[21]`` (module docstring); ``e`` three
    uniforms in [0, 1) (gust, wave motion ×2), or standard normals with ``innovations``
    "normal" (a caller whose per-boat streams draw normals); ``yaw_model`` (m kg m²,
    d N m s/rad) the autopilot's design model and ``turn_damping`` d₂ (N m s²/rad²) the
    observer's (:func:`usvsim.vessel.weather.observer.observer_predict`)."""
    f = build_dynamics(vessel, weather=True)
    s = ca.SX.sym("s", NS + NWS)
    w = ca.SX.sym("w", NWI)
    g = ca.SX.sym("g", NG)
    e = ca.SX.sym("e", 3)
    x, c = s[:NX], s[NX:NS]
    psi, r = x[2], x[5]
    # 1. sensed heading and yaw rate: true + first-order wave yaw
    offsets = sensed_offsets_expr(s, w)
    psi_m = psi + offsets[2]
    r_m = r + offsets[3]
    # 2. wave filter: the observer on the compass and gyro
    m_yaw, d_yaw = yaw_model
    prior = [s[_S[f"obs_{k}"]] for k in OBSERVER_STATES]
    gains = [w[_I[f"gain_{k}_{y}"]] for k in OBSERVER_STATES for y in ("compass", "gyro")]
    phi = [w[_I[k]] for k in ("phi00", "phi01", "phi10", "phi11")]
    on = w[_I["wave_filter"]]  # 0: exactly the sensed values
    # off: the prior restarts from the sensors at every step, so it stays finite (0 × finite)
    prior = [on * z for z in prior]
    prior[2] = prior[2] + (1.0 - on) * psi_m
    prior[3] = prior[3] + (1.0 - on) * r
    psi_hat, r_hat, z = observer_correct(prior, psi_m, r_m, gains)
    psi_f = psi_m + on * wrap_difference(psi_hat - psi_m)
    r_f = r_m + on * (r_hat - r_m)
    # 3. autopilot on what it senses
    x_sensed = ca.vertcat(x[0], x[1], psi_f, x[3], x[4], r_f, x[6], x[7])
    dg = [w[_I[f"pid_d{k}"]] for k in ("kp", "kd", "ki")]  # 0 keeps the calm gains exactly
    g_boat = ca.vertcat(g[0] + dg[0], g[1] + dg[1], g[2] + dg[2], g[3:])
    a_cmd, c_next = control_law(vessel, kind, x_sensed, c, w[0:2], g_boat, dt_s)
    # the observer predicts with the yaw moment the actuators give over the step: their state
    # where they lag, the saturated command where they are instantaneous (model.build_dynamics)
    act = vessel.actuation
    sat = saturate_command(act, a_cmd)
    applied = ca.vertcat(*(x[6 + i] if act.lag_s[i] > 0 else sat[i] for i in range(2)))
    tau_n = generalized_forces(act, applied, x[3])[2]
    prior_next = observer_predict(z, tau_n, phi, m_yaw, d_yaw, dt_s, turn_damping)
    # 4. vessel in current, wind and wave drift
    wind = ca.fmax(w[_I["wind_mean"]] + s[_S["gust"]], 0.0)
    cos_psi, sin_psi = ca.cos(psi), ca.sin(psi)  # shared with RK4's first stage
    wind_rel = relative_trig(w[_I["wind_cos"]], w[_I["wind_sin"]], cos_psi, sin_psi)
    wave_rel = relative_trig(w[_I["wave_cos"]], w[_I["wave_sin"]], cos_psi, sin_psi)
    tau_env = relative_wind_loads(hull, x[3:6], wind, *wind_rel) + relative_drift_loads(
        hull, w[_I["drift_pressure"]], *wave_rel
    )
    p = ca.vertcat(w[2], w[3], tau_env)
    x_next = rk4_expr(f, x, a_cmd, p, dt_s)
    x_next[2] = ssa_casadi(x_next[2])
    # 5. gust and wave motion, exact discretisations; innovations of zero mean, unit variance
    xi = math.sqrt(12.0) * (e - 0.5) if innovations == "uniform" else e
    gust = w[_I["gust_a"]] * s[_S["gust"]] + w[_I["gust_gain"]] * xi[0]
    xi0, xi1 = s[_S["xi0"]], s[_S["xi1"]]
    xi0_next = w[_I["phi00"]] * xi0 + w[_I["phi01"]] * xi1 + w[_I["l00"]] * xi[1]
    xi1_next = (
        w[_I["phi10"]] * xi0 + w[_I["phi11"]] * xi1 + w[_I["l10"]] * xi[1] + w[_I["l11"]] * xi[2]
    )
    m_next = ca.vertcat(gust, xi0_next, xi1_next, *prior_next)
    return ca.Function(
        "usv_wx_step",
        [s, w, g, e],
        [ca.vertcat(x_next, c_next, m_next)],
        ["s", "w", "g", "e"],
        ["s_next"],
    )


@dataclass(frozen=True)
class SeaConditions:
    """Weather of N boats, each field (N,): wind and sea state (module docstring).

    Directions are those the wind blows and the waves travel *towards* (rad, NED), as the
    current's. ``hs_m`` = 0 is a calm sea; ``wind_speed_mps`` = 0 no wind.
    """

    wind_speed_mps: NDArray[np.float64]  # m/s, mean V̄
    wind_dir_rad: NDArray[np.float64]  # rad
    gust_intensity: NDArray[np.float64]  # -, σ_g / V̄
    hs_m: NDArray[np.float64]  # m, significant wave height
    tp_s: NDArray[np.float64]  # s, peak period (any value where hs_m = 0)
    wave_dir_rad: NDArray[np.float64]  # rad

    @classmethod
    def uniform(
        cls,
        n: int,
        wind_speed_mps: float = 0.0,
        wind_dir_rad: float = 0.0,
        sea: SeaState | None = None,
        gust_intensity: float = GustParams().intensity,
    ) -> SeaConditions:
        """The same weather for ``n`` boats (``sea`` None: calm)."""
        sea = sea or SeaState(0.0, 0.0)

        def full(v: float) -> NDArray[np.float64]:
            return np.full(n, float(v))

        return cls(
            full(wind_speed_mps),
            full(wind_dir_rad),
            full(gust_intensity),
            full(sea.hs_m),
            full(sea.tp_s if sea.hs_m > 0 else 10.0),
            full(sea.direction_rad),
        )

    def check(self, n: int) -> None:
        """Raise :class:`UserError` (one line) on a shape or value out of range."""
        for name in self.__dataclass_fields__:
            arr = np.asarray(getattr(self, name), dtype=float)
            if arr.shape != (n,) or not np.isfinite(arr).all():
                raise UserError(f"SeaConditions.{name} must be {n} finite numbers")
        wind, gust, hs = self.wind_speed_mps, self.gust_intensity, self.hs_m
        if not ((wind >= 0) & (wind <= WIND_SPEED_MAX_MPS)).all():
            raise UserError(f"wind speed must lie in [0, {WIND_SPEED_MAX_MPS:g}] m/s")
        if not ((gust >= 0) & (gust <= 0.5)).all():
            raise UserError("gust intensity must lie in [0, 0.5]")
        if not ((hs >= 0) & (hs <= HS_MAX_M)).all():
            raise UserError(f"significant wave height must lie in [0, {HS_MAX_M:g}] m")
        if ((hs > 0) & ((self.tp_s < 1.0) | (self.tp_s > 25.0))).any():
            raise UserError("peak period must lie in [1, 25] s")


@dataclass(frozen=True)
class WeatherPlantState:
    """N boats: plant ``x`` (N, 8), autopilot ``c`` (N, 5), weather states ``m`` (N, 8) and
    the per-episode weather inputs ``inputs`` (N, 33) (:data:`WEATHER_INPUTS` from wind_mean)."""

    x: NDArray[np.float64]
    c: NDArray[np.float64]
    m: NDArray[np.float64]
    inputs: NDArray[np.float64]

    @property
    def plant(self) -> PlantState:
        return PlantState(x=self.x, c=self.c)


def weather_inputs(
    cond: SeaConditions,
    speed_mps: NDArray[np.float64],
    heading_rad: NDArray[np.float64],
    dt_s: float,
    gusts: GustParams,
    wave_filter: ObserverNoise | None,
    yaw_model: tuple[float, float],
    yaw_gain: float = 1.0,
    autopilot: AutopilotDesign | None = None,
    compiled: bool = True,
) -> tuple[NDArray[np.float64], WaveResponse]:
    """Per-boat weather inputs (N, 33) (:data:`WEATHER_INPUTS` from ``wind_mean``) and the
    wave response they were built from; ``wave_filter`` None: the filter off for every boat,
    else its tuning (calm boats keep it off: nothing to filter, and no estimator lag).
    ``autopilot``: where the filter is on, its PID takes the wave design
    (:func:`usvsim.vessel.autopilot.wave_mode_gain_changes`); None: the calm gains.
    ``compiled``: the wave pieces by :mod:`usvsim.vessel.weather.start_kernel` (the same
    arithmetic in C, equal to rounding) where it builds; False: the NumPy functions."""
    n = cond.hs_m.size
    relative = cond.wave_dir_rad - heading_rad
    fast = None
    if compiled:
        fast = compiled_wave_start(cond.hs_m, cond.tp_s, relative, speed_mps, dt_s, wave_filter,
                                   yaw_model, yaw_gain, autopilot)  # fmt: skip
    if fast is not None:
        resp = WaveResponse(fast.omega0, fast.damping, fast.gain)
        phi, chol, drift = fast.phi, fast.chol, fast.drift
    else:
        resp = encounter_response(cond.hs_m, cond.tp_s, relative, speed_mps, dt_s)
        phi, chol = wave_motion_discrete(resp, dt_s)
        drift = np.where(cond.hs_m > 0, drift_pressure(cond.hs_m, cond.tp_s), 0)
    a = math.exp(-dt_s / gusts.time_constant_s)
    out = np.zeros((n, NWI - 4))
    col = _COL
    out[:, col["wind_mean"]] = cond.wind_speed_mps
    out[:, col["wind_dir"]] = cond.wind_dir_rad
    out[:, col["gust_a"]] = a
    out[:, col["gust_gain"]] = cond.gust_intensity * cond.wind_speed_mps * math.sqrt(1 - a * a)
    out[:, col["drift_pressure"]] = drift
    out[:, col["wave_dir"]] = cond.wave_dir_rad
    out[:, col["wave_omega"]] = resp.omega0
    for name, angle in (("wind", cond.wind_dir_rad), ("wave", cond.wave_dir_rad)):
        out[:, col[f"{name}_cos"]], out[:, col[f"{name}_sin"]] = np.cos(angle), np.sin(angle)
    out[:, col["phi00"] : col["phi11"] + 1] = phi.reshape(n, 4)  # Φ row-major
    for name in ("l00", "l10", "l11"):
        out[:, col[name]] = chol[:, int(name[1]), int(name[2])]
    out[:, col["yaw_gain"]] = yaw_gain
    if wave_filter is None:
        return out, resp
    # only boats in waves get a filter (their Riccati equations alone: each boat's gains
    # do not depend on the others, observer.solve_filter_riccati); calm ones keep zeros
    wavy = cond.hs_m > 0
    out[:, col["wave_filter"]] = wavy
    first = col[f"gain_{OBSERVER_STATES[0]}_compass"]  # the ten gains, row-major
    gains = slice(first, first + 2 * len(OBSERVER_STATES))
    pid = slice(col["pid_dkp"], col["pid_dki"] + 1)
    if fast is not None:
        out[:, gains], out[:, pid] = fast.gains, fast.pid
    elif wavy.any():
        scale = yaw_gain * resp.omega0[wavy] ** 3 / G * np.sin(2.0 * relative[wavy])
        l = observer_gains(phi[wavy], chol[wavy], scale, *yaw_model, dt_s, wave_filter)
        out[wavy, gains] = l.reshape(-1, 10)
        if autopilot is not None:
            out[wavy, pid] = wave_mode_gain_changes(autopilot, resp.omega0[wavy], cond.hs_m[wavy])
    return out, resp


def sensed_offsets_expr(s: ca.SX, w: ca.SX) -> ca.SX:
    """What the sensors add to the true state (CasADi): [Δn (m), Δe (m), Δψ (rad), Δr (rad/s)]
    of the first-order wave motion, from a weather step's state ``s`` and inputs ``w``
    (:func:`usvsim.vessel.weather.waves.wave_displacement`; Δr its rate, ψ̇ in the sine
    neglected). The GNSS velocity is not displaced (the orbital velocity is left out)."""
    omega, cos_beta, sin_beta = w[_I["wave_omega"]], w[_I["wave_cos"]], w[_I["wave_sin"]]
    # sin 2(β − ψ) = 2 sin(β − ψ) cos(β − ψ), from the episode's cos β, sin β and the
    # kinematics' cos ψ, sin ψ (no trigonometric call: relative_trig)
    cos_rel, sin_rel = relative_trig(cos_beta, sin_beta, ca.cos(s[2]), ca.sin(s[2]))
    shape = w[_I["yaw_gain"]] * omega**2 / G * (2.0 * sin_rel * cos_rel)
    d = omega * s[_S["xi0"]]
    return ca.vertcat(d * cos_beta, d * sin_beta, shape * d, shape * (omega * s[_S["xi1"]]))


def sensed_offsets(
    x: NDArray[np.float64], m: NDArray[np.float64], inputs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """:func:`sensed_offsets_expr` in NumPy: plant states ``x`` (..., 8), weather states ``m``
    (..., 8), weather inputs ``inputs`` (..., 33) → (..., 4)."""
    col = _COL
    omega, beta = inputs[..., col["wave_omega"]], inputs[..., col["wave_dir"]]
    shape = inputs[..., col["yaw_gain"]] * omega**2 / G * np.sin(2.0 * (beta - x[..., 2]))
    d = omega * m[..., 1]
    return np.stack(
        [d * np.cos(beta), d * np.sin(beta), shape * d, shape * (omega * m[..., 2])], -1
    )


def wave_offsets(state: WeatherPlantState) -> NDArray[np.float64]:
    """First-order wave motion [Δn (m), Δe (m), Δψ (rad)] (N, 3) the sensors add to the true η
    (:func:`usvsim.vessel.weather.waves.wave_displacement`, with the kernel's numbers)."""
    return sensed_offsets(state.x, state.m, state.inputs)[:, :3]


def wave_filter_design(state: WeatherPlantState, autopilot: AutopilotDesign | None = None) -> str:
    """One line per boat kind: the wave filter's design for the first boat of ``state`` (the
    encounter frequency, the wave motion's damping and the observer's steady-state gains);
    with ``autopilot`` (the plant's design) a second line, its PID's natural frequency there."""
    col = _COL
    row = state.inputs[0]
    if row[col["wave_filter"]] == 0:
        return "wave filter: off (calm sea or switched off)"
    gains = ", ".join(
        f"{k} {row[col[f'gain_{k}_compass']]:.3g}/{row[col[f'gain_{k}_gyro']]:.3g}"
        for k in OBSERVER_STATES
    )
    line = (
        f"wave filter: Kalman observer (Fossen 2021 §13.3) at the encounter frequency "
        f"{row[col['wave_omega']]:.3f} rad/s; steady-state gains (compass/gyro): {gains}"
    )
    if autopilot is None or autopilot.config.kind != "pid":
        return line
    omega_n = math.sqrt((autopilot.Kp + row[col["pid_dkp"]]) / autopilot.nomoto.m)
    return (
        f"{line}\n  PID with the filter: ω_n = {omega_n:.3f} rad/s (calm "
        f"{autopilot.config.omega_n:g}), its closed-loop bandwidth at the encounter frequency "
        "(autopilot.wave_mode_gain_changes; Fossen 2021 §13.3, §15.3)"
    )


class WeatherPlant:
    """N boats of ``plant``'s vessel and autopilot in wind and waves, stepped together.

    Parameters
    ----------
    plant : Plant
        The calm plant: its vessel, autopilot design, step and current are reused.
    seed : int
        Seeds the gusts and the wave motion (same seed, same conditions: same trajectories).
    gusts : GustParams, optional
        Gust time constant (the intensity is per boat, in :class:`SeaConditions`).
    wave_filter : bool
        The autopilot gets the wave filter's heading and yaw rate (boats in waves), or the
        compass and gyro's (False).
    hull : WeatherHull
        Windage and waterline (default usv105's).
    observer : ObserverNoise, optional
        The wave filter's tuning (default :class:`ObserverNoise`).
    innovations : "uniform" or "normal"
        What drives the gusts and wave motion (module docstring): uniforms (cheap to draw) or
        standard normals (for callers whose per-boat streams draw normals).
    turn_damping : float, optional
        The observer's d₂ (N m s²/rad²); default fitted to the hull's steady turns.
    """

    def __init__(
        self,
        plant: Plant,
        seed: int = 0,
        gusts: GustParams | None = None,
        wave_filter: bool = True,
        hull: WeatherHull = USV105_HULL,
        observer: ObserverNoise | None = None,
        innovations: Literal["uniform", "normal"] = "uniform",
        turn_damping: float | None = None,
    ) -> None:
        self.plant = plant
        self.gusts = gusts or GustParams()
        self.observer = observer or ObserverNoise()
        self.wave_filter = self.observer if wave_filter else None
        self.yaw_model = (float(plant.design.nomoto.m), float(plant.design.nomoto.d))
        self.rng = np.random.default_rng(seed)
        self.innovations = innovations
        self.turn_damping = (  # N m s²/rad², the observer's d₂
            steady_turn_damping(plant) if turn_damping is None else float(turn_damping)
        )
        step = (plant.vessel, plant.kind, plant.dt_s, self.yaw_model, hull, innovations)
        self.step_function = build_weather_step(*step, self.turn_damping)
        # 16 boats per vector block: this kernel (~1,050 operations) runs 5-6 % faster in blocks
        # of 16 than in the calm plant's 8 (measured 2026-12-06, N = 1024: 8.5 -> 8.0 ms per
        # 100 steps; the calm kernel is 3-5 % slower in 16); the same numbers (tested)
        self._stepper = BatchStepper(
            self.step_function,
            plant.kernel,  # type: ignore[arg-type]
            record=NS,
            block=16,
        )

    @property
    def kernel(self) -> str:
        """The kernel in use (the calm plant's kind): ``soa``, ``scalar`` or ``casadi``."""
        return self._stepper.kernel

    def initial_state(
        self,
        eta: ArrayLike,
        conditions: SeaConditions,
        speed_mps: ArrayLike | None = None,
        *,
        rng: np.random.Generator | None = None,
        wave_filter: bool | None = None,
        calm: PlantState | None = None,
    ) -> WeatherPlantState:
        """Boats as :meth:`Plant.initial_state`, their weather from ``conditions``; gusts and wave
        motion start in their stationary distributions (no transient).

        ``rng`` (anything with ``standard_normal``) draws them instead of the plant's generator;
        ``wave_filter`` sets these boats' filter instead of the plant's setting; ``calm`` is
        ``Plant.initial_state(eta, speed_mps)`` where the caller has it already (not recomputed:
        its trim is a CasADi call)."""
        calm = self.plant.initial_state(eta, speed_mps) if calm is None else calm
        n = calm.n_boats
        conditions.check(n)
        draw = self.rng if rng is None else rng
        if wave_filter is None:
            observer = self.wave_filter
        else:
            observer = self.observer if wave_filter else None
        inputs, resp = weather_inputs(
            conditions,
            calm.x[:, 3],
            calm.x[:, 2],
            self.plant.dt_s,
            self.gusts,
            observer,
            self.yaw_model,
            autopilot=self.plant.design,
        )
        m = np.zeros((n, NWS))
        sigma = conditions.gust_intensity * conditions.wind_speed_mps
        m[:, 0] = sigma * draw.standard_normal(n)
        m[:, 1:3] = wave_motion_init(draw, resp)
        state = WeatherPlantState(calm.x, calm.c, m, inputs)
        obs = {k: 3 + i for i, k in enumerate(OBSERVER_STATES)}
        m[:, obs["psi"]] = calm.x[:, 2] + wave_offsets(state)[:, 2]  # starts on the compass
        m[:, obs["r"]] = calm.x[:, 5]
        return state

    def step(
        self,
        state: WeatherPlantState,
        psi_ref_rad: ArrayLike,
        speed_ref_mps: ArrayLike | None = None,
        n_steps: int = 1,
        *,
        weather_states: bool = False,
    ) -> tuple[WeatherPlantState, NDArray[np.float64]]:
        """Advance all boats ``n_steps`` plant steps, references held; returns the new state and
        the trajectory (N, n_steps, 13) of [x, c] after each step (the calm plant's), or
        (N, n_steps, 21) of [x, c, m] with ``weather_states``.

        The uniform innovations are the generator's ``random((N, n_steps, 3))``; on NumPy's
        PCG64 (the default) the compiled kernel generates them itself
        (:class:`usvsim.vessel.pcg64.Pcg64Uniforms`: the same numbers, no array drawn and
        gathered) and the generator moves past them."""
        n = state.x.shape[0]
        speed = self.plant.cruise_speed_mps if speed_ref_mps is None else speed_ref_mps
        w = np.empty((n, NWI))
        w[:, 4:] = state.inputs
        w[:, 0] = np.broadcast_to(np.asarray(psi_ref_rad, dtype=float), (n,))
        w[:, 1] = np.broadcast_to(np.asarray(speed, dtype=float), (n,))
        w[:, 2:4] = self.plant.current
        if not np.isfinite(w[:, :2]).all():
            raise ValueError("psi_ref_rad / speed_ref_mps contain NaN or inf")
        s0 = np.concatenate([state.x, state.c, state.m], axis=1)
        shape = (n, int(n_steps), 3)
        draws: NDArray[np.float64] | Pcg64Uniforms | None = None
        if self.innovations == "uniform":
            draws = Pcg64Uniforms.take(self.rng, n * int(n_steps) * 3)
            if draws is None:
                draws = self.rng.random(shape)
        else:
            draws = self.rng.standard_normal(shape)
        record = NS + NWS if weather_states else NS
        traj, last = self._stepper.run_recorded(
            s0, w, self.plant.gains, int(n_steps), draws, record
        )
        new = WeatherPlantState(
            last[:, :NX].copy(), last[:, NX:NS].copy(), last[:, NS:].copy(), state.inputs
        )
        return new, traj
