"""ArduPilot Rover parameters for a usvsim vessel, derived from its model (``--write-params``).

ArduPilot's defaults (``rover.parm``: ATC_STR_RAT_FF 0.75, P = I = 0.2, ANG_P 2, MOT_SPD_SCA_BASE
1 m/s) assume a light, well-damped rover: on the usv105 hull a 60° heading step overshot by 77°
and then oscillated ±50-70° (real Rover 4.7.0-dev SITL). The parameters here are derived for the
hull from the vessel model, for the controller structure of ``AR_AttitudeControl.cpp``, which
usvsim's ``rover`` autopilot reproduces (:func:`usvsim.vessel.autopilot.control_law`):

    r_des = ATC_STR_ANG_P ψ̃, at most √(2 |ψ̃| ATC_STR_ACC_MAX), changing by ≤ ACC_MAX dt,
            at most ATC_STR_RAT_MAX;
    steer = ATC_STR_RAT_FF r_des + ATC_STR_RAT_P (r_des − r) + I-term,   |steer| ≤ 1.

Derivation (cruise speed U of the vessel, plant step dt = 0.1 s):

1. **Steering gain** K_δ = ∂N/∂steer: waterjet l_x · X_drag(U) · δ_max (the thrust that holds U,
   small nozzle angle), lateral-force actuators |l_x| F_y,max. Hull r/N: the sway–yaw
   linearisation :func:`usvsim.vessel.model.linearize_steering` (unstable on usv105); actuator
   lag 1/(1 + T_δ s) and the half-sample delay (2nd-order Padé), as :mod:`usvsim.vessel.loop`.
2. **ATC_STR_RAT_FF** = 0.5 / r_ss(0.5): the steer per turn rate of a steady turn of the
   *nonlinear* model at half steer with the speed held at U (the linear static gain of a
   straight-line-unstable hull is negative, meaningless for feed-forward).
3. **ATC_STR_RAT_P** puts the rate loop's crossover at ω_r = 1 / (4 (T_δ + dt/2)), a quarter
   of the actuator-and-sampling bandwidth (python-control; margins reported).
4. **ATC_STR_ANG_P**: the largest of a grid whose heading loop, ψ/ψ_ref = ANG_P T_r(s)/s with
   T_r the closed rate loop (FF included), keeps a phase margin ≥ 60° (little overshoot).
5. **ATC_STR_RAT_MAX** = 0.8 r_ss(1): the steady full-steer turn rate less 20 % for the rate
   loop's own authority. **ATC_STR_ACC_MAX** = ω_r · RAT_MAX: the fastest ramp of r_des the
   rate loop follows.
6. **ATC_STR_RAT_I = 0** and **MOT_SPD_SCA_BASE = 0**: Rover scales steering by
   MOT_SPD_SCA_BASE / speed above that speed (at 3 m/s and the default 1 m/s: a third of the
   nozzle range, never full); with 0 it does not scale, but then it flags the steering as
   limited on every loop (``AP_MotorsUGV::output_regular``), which stops the rate I-term from
   growing, so I = 0 says what ArduPilot will do. usvsim's model uses I = 1e-6 (its config
   needs a positive value), i.e. none.
7. **Speed loop** (``AR_AttitudeControl::get_throttle_out_speed``: throttle = CRUISE_THROTTLE ·
   v/CRUISE_SPEED + PI): CRUISE_THROTTLE = the thrust command that holds U as % of full;
   ATC_SPEED_P/I by pole placement (ω = 0.5 rad/s, ζ = 1, usvsim's own speed-loop bandwidth)
   on the linearised surge dynamics m₁₁ u̇ = η(u) t T_max − X(u); ATC_ACCEL_MAX half the
   full-throttle acceleration at U; ATC_BRAKE 1 where the waterjet has a reversing bucket.

Frame and outputs: FRAME_CLASS 2 (boat), SERVO1 = GroundSteering (26), SERVO3 = Throttle (70),
1000 / 1500 / 2000 µs (what ``usvsim sitl-physics`` reads by default); WP_SPEED = CRUISE_SPEED
= U. The ``tests/usvsim/mavlink/test_rover_params.py`` Must-show: the shipped usv105 file, in
usvsim's Rover-cascade model of the loop closed through ``sitl-physics``, turns 60° within 5° in
≤ 10 s with < 2° of oscillation afterwards.

Run ArduPilot with it (ArduPilot source tree; nothing of ArduPilot is shipped here)::

    usvsim sitl-physics --write-params usv105.parm
    usvsim sitl-physics &
    sim_vehicle.py -v Rover -f motorboat --model JSON:127.0.0.1 --add-param-file=usv105.parm
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from usvsim.vessel.autopilot import AutopilotConfig
from usvsim.vessel.model import (
    build_dynamics,
    build_rk4_step,
    damping_forces,
    linearize_steering,
    mass_matrix,
    surge_trim,
    thrust_factor,
)
from usvsim.vessel.vessels import VesselParams, get_vessel

__all__ = [
    "RoverTuning",
    "autopilot_config",
    "derive_rover_tuning",
    "parameter_file",
    "read_parameter_file",
    "shipped_parameter_file",
]

DT_S = 0.1  # s, the plant's controller step
PHASE_MARGIN_DEG = 60.0  # deg, heading-loop phase margin asked of ANG_P
ANG_P_GRID = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0)  # 1/s, candidates (ArduPilot: 1-10)
SPEED_OMEGA = 0.5  # rad/s, speed-loop bandwidth (AutopilotConfig.speed_omega)
RATE_I_MODEL = 1e-6  # 1/rad, usvsim's stand-in for ArduPilot's ATC_STR_RAT_I = 0


@dataclass(frozen=True)
class RoverTuning:
    """The derived parameters (ArduPilot units) and the design figures behind them."""

    vessel: str
    speed_mps: float  # m/s, design speed = WP_SPEED = CRUISE_SPEED
    ang_p: float  # 1/s, ATC_STR_ANG_P
    rate_ff: float  # -, ATC_STR_RAT_FF (steer per rad/s)
    rate_p: float  # -, ATC_STR_RAT_P (steer per rad/s)
    rate_max_dps: float  # deg/s, ATC_STR_RAT_MAX
    acc_max_dps2: float  # deg/s², ATC_STR_ACC_MAX
    cruise_throttle_pct: float  # %, CRUISE_THROTTLE
    speed_p: float  # -, ATC_SPEED_P (throttle per m/s)
    speed_i: float  # -, ATC_SPEED_I (throttle per m)
    accel_max_mps2: float  # m/s², ATC_ACCEL_MAX
    brake: bool  # ATC_BRAKE: astern thrust available
    rate_crossover_radps: float  # rad/s, ω_r
    rate_phase_margin_deg: float  # deg
    heading_phase_margin_deg: float  # deg, with ang_p


def _steady_turn_rate(vessel: VesselParams, speed: float, steer: float) -> float:
    """Steady turn rate (rad/s) at ``steer`` ∈ (0, 1] with the speed held at ``speed``."""
    act = vessel.actuation
    step = build_rk4_step(build_dynamics(vessel), DT_S)
    m11 = float(mass_matrix(vessel)[0, 0])
    trim = float(surge_trim(vessel, speed))
    side = steer * act.a2_max * (1.0 if act.kind != "forces" or act.lever_m > 0 else -1.0)
    x = np.array([0.0, 0.0, 0.0, speed, 0.0, 0.0, trim, 0.0])
    integral = 0.0
    for _ in range(round(200.0 / DT_S)):  # 200 s: the slow mode of usv105 settles in ~60 s
        err = x[3] - speed
        integral += err * DT_S
        thrust = min(max(trim - m11 * (1.0 * err + 0.25 * integral), 0.0), act.a1_max)
        x = np.asarray(step(x, [thrust, side], [0.0, 0.0])).ravel()
    return abs(float(x[5]))


def _loops(vessel: VesselParams, speed: float) -> tuple[Any, Any]:
    """(rate plant steer → r with lag and delay, s) as python-control transfer functions."""
    import control

    act = vessel.actuation
    if act.kind == "forces":
        k_delta = abs(act.lever_m) * act.a2_max
    else:
        drag = float(damping_forces(vessel, ca.DM([speed, 0.0, 0.0]))[0])
        k_delta = act.lever_m * drag * act.a2_max
    A, b = linearize_steering(vessel, speed)
    g_r = control.ss2tf(control.ss(A, b, np.array([[0.0, 1.0]]), np.zeros((1, 1))))
    s = control.tf("s")
    num, den = control.pade(DT_S / 2, 2)
    lag = max(act.lag_s[1], 1e-6)
    return k_delta * g_r / (1 + lag * s) * control.tf(num, den), s


def derive_rover_tuning(vessel: str | VesselParams = "default") -> RoverTuning:
    """Rover steering and speed parameters for ``vessel`` at its cruise speed (module docstring)."""
    import control

    v = get_vessel(vessel) if isinstance(vessel, str) else vessel
    act = v.actuation
    speed = v.cruise_speed_mps
    plant, s = _loops(v, speed)
    rate_ff = 0.5 / _steady_turn_rate(v, speed, 0.5)
    w_r = 1.0 / (4.0 * (act.lag_s[1] + DT_S / 2))
    rate_p = 1.0 / abs(complex(control.evalfr(plant, 1j * w_r)))
    _, rate_pm, _, _ = control.margin(rate_p * plant)
    closed = (rate_ff + rate_p) * plant / (1 + rate_p * plant)
    ang_p, heading_pm = ANG_P_GRID[0], math.nan
    for candidate in ANG_P_GRID:
        _, pm, _, _ = control.margin(candidate * closed / s)
        if pm >= PHASE_MARGIN_DEG or candidate == ANG_P_GRID[0]:
            ang_p, heading_pm = candidate, float(pm)
    rate_max = 0.8 * _steady_turn_rate(v, speed, 1.0)
    # speed loop: m11 u' = eta(u) t T_max - X(u), linearised at U (thrust loss included)
    m11 = float(mass_matrix(v)[0, 0])
    u = ca.SX.sym("u")
    drag_fn = ca.Function("X", [u], [damping_forces(v, ca.vertcat(u, 0, 0))[0]])
    d_drag = float(ca.Function("dX", [u], [ca.jacobian(drag_fn(u), u)])(speed))
    eta = float(thrust_factor(act, speed))
    trim = float(surge_trim(v, speed))
    jet = act.jet_speed_mps
    damping = d_drag + (trim / jet if math.isfinite(jet) else 0.0)  # N s/m, incl. thrust loss
    gain, tau = eta * act.a1_max / damping, m11 / damping  # m/s per throttle, s
    speed_i = SPEED_OMEGA**2 * tau / gain
    speed_p = max(0.0, (2.0 * SPEED_OMEGA * tau - 1.0) / gain)
    drag_u = float(drag_fn(speed))
    return RoverTuning(
        vessel=v.name,
        speed_mps=speed,
        ang_p=ang_p,
        rate_ff=round(rate_ff, 3),
        rate_p=round(rate_p, 3),
        rate_max_dps=round(math.degrees(rate_max), 1),
        acc_max_dps2=round(math.degrees(w_r * rate_max), 1),
        cruise_throttle_pct=round(100.0 * trim / act.a1_max, 1),
        speed_p=round(speed_p, 3),
        speed_i=round(speed_i, 3),
        accel_max_mps2=round(0.5 * (eta * act.a1_max - drag_u) / m11, 2),
        brake=act.a1_min < 0,
        rate_crossover_radps=w_r,
        rate_phase_margin_deg=float(rate_pm),
        heading_phase_margin_deg=heading_pm,
    )


def autopilot_config(t: RoverTuning) -> AutopilotConfig:
    """usvsim's ``rover`` autopilot with these parameters (the same controller structure)."""
    return AutopilotConfig(
        kind="rover",
        cruise_speed_mps=t.speed_mps,
        rover_ang_p=t.ang_p,
        rover_rate_ff=t.rate_ff,
        rover_rate_p=t.rate_p,
        rover_rate_i=RATE_I_MODEL,
        rover_rate_imax=1.0,
        rover_rate_max=math.radians(t.rate_max_dps),
        rover_acc_max=math.radians(t.acc_max_dps2),
    )


def parameter_file(t: RoverTuning) -> str:
    """The ``.parm`` text (``NAME VALUE`` lines, ``#`` comments) ArduPilot loads."""
    rows: list[tuple[str, float | int, str]] = [
        ("FRAME_CLASS", 2, "boat"),
        ("SERVO1_FUNCTION", 26, "GroundSteering (usvsim sitl-physics --steering-channel 1)"),
        ("SERVO1_MIN", 1000, "µs, full port"),
        ("SERVO1_TRIM", 1500, "µs"),
        ("SERVO1_MAX", 2000, "µs, full starboard"),
        ("SERVO3_FUNCTION", 70, "Throttle (usvsim sitl-physics --throttle-channel 3)"),
        ("SERVO3_MIN", 1000, "µs, full astern"),
        ("SERVO3_TRIM", 1500, "µs"),
        ("SERVO3_MAX", 2000, "µs, full ahead"),
        ("MOT_SPD_SCA_BASE", 0, "no steering scaling with speed (derivation, step 6)"),
        ("CRUISE_SPEED", t.speed_mps, "m/s"),
        ("CRUISE_THROTTLE", t.cruise_throttle_pct, "%, holds CRUISE_SPEED"),
        ("WP_SPEED", t.speed_mps, "m/s (usvsim bridge --attitude-target reads it)"),
        ("ATC_STR_ANG_P", t.ang_p, f"1/s, heading PM {t.heading_phase_margin_deg:.0f}°"),
        ("ATC_STR_RAT_FF", t.rate_ff, "steer per rad/s, steady half-steer turn"),
        (
            "ATC_STR_RAT_P",
            t.rate_p,
            f"crossover {t.rate_crossover_radps:.2f} rad/s, PM {t.rate_phase_margin_deg:.0f}°",
        ),
        ("ATC_STR_RAT_I", 0, "frozen by ArduPilot when MOT_SPD_SCA_BASE is 0"),
        ("ATC_STR_RAT_D", 0, ""),
        ("ATC_STR_RAT_IMAX", 1, ""),
        ("ATC_STR_RAT_MAX", t.rate_max_dps, "deg/s, 80 % of the full-steer turn"),
        ("ATC_STR_ACC_MAX", t.acc_max_dps2, "deg/s², crossover x RAT_MAX"),
        ("ATC_SPEED_P", t.speed_p, "throttle per m/s (0.5 rad/s speed loop)"),
        ("ATC_SPEED_I", t.speed_i, "throttle per m"),
        ("ATC_ACCEL_MAX", t.accel_max_mps2, "m/s², half the full-throttle acceleration"),
        ("ATC_BRAKE", int(t.brake), "reverse thrust to slow down (reversing bucket)"),
    ]
    head = [
        f"# ArduPilot Rover parameters for the usvsim vessel {t.vessel} at {t.speed_mps:g} m/s,",
        "# derived by usvsim.mavlink.rover_params (usvsim sitl-physics --write-params FILE).",
        "# sim_vehicle.py -v Rover -f motorboat --model JSON:127.0.0.1 --add-param-file=FILE",
    ]
    body = [f"{name:<17} {value:g}" + (f"  # {note}" if note else "") for name, value, note in rows]
    return "\n".join(head + body) + "\n"


def read_parameter_file(text: str) -> dict[str, float]:
    """``NAME VALUE`` pairs of a ``.parm`` text (comments and blank lines skipped).

    Raises
    ------
    ValueError
        On a line that is not ``NAME VALUE``; the message gives its number.
    """
    values: dict[str, float] = {}
    for number, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.replace(",", " ").split()
        if len(parts) != 2:
            raise ValueError(f"line {number}: expected 'NAME VALUE', got {line!r}")
        values[parts[0]] = float(parts[1])
    return values


def shipped_parameter_file(vessel: str = "default") -> str:
    """The shipped ``usvsim/mavlink/params/<vessel>.parm`` text."""
    name = get_vessel(vessel).name
    path = resources.files("usvsim.mavlink") / "params" / f"{name}.parm"
    return Path(str(path)).read_text(encoding="utf-8")
