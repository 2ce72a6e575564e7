"""Heading autopilots and surge-speed control: design (python-control) and the CasADi control law.

Two heading autopilots, both discrete at the plant step dt_s (a 10 Hz digital autopilot):

``pid``    Fossen (2021, ch. 15.3) PID by pole placement on the first-order Nomoto model
           m ṙ + d r = τ_N:  K_p = m ω_n², K_d = 2 ζ ω_n m − d, K_i = ω_n/10 · K_p, with a
           third-order, rate- and acceleration-limited reference model (MSS ``refModel``)
           giving ψ_d, r_d, a_d, feed-forward τ_N = m a_d + d r_d, conditional-integration
           anti-windup and allocation to the actuators with saturation.
``rover``  an ArduPilot-Rover-like cascade (AR_AttitudeControl): heading P (ATC_STR_ANG_P = 2.0)
           → desired turn rate (limited by ATC_STR_RAT_MAX) → turn-rate PID with feed-forward
           (ATC_STR_RAT_FF = P = I = 0.2, IMAX = 1) → normalised steering in [-1, 1] → nozzle
           angle or lateral force as a fraction of its limit.

Both use the same surge-speed PI controller with drag feed-forward:
τ_X = X_drag(U_ref) − m_11 (k_p,u (u − U_ref) + k_i,u ∫(u − U_ref) dt).

Controller state c (5 entries, per boat): ``pid``: [ψ_d, r_d, a_d, ∫ψ̃ dt, ∫ũ dt];
``rover``: [0, r_des, 0, rate-I term, ∫ũ dt]. Command: [ψ_ref (rad), U_ref (m/s)].

Why this module is long: both autopilots share one config, one controller state layout, the
speed loop and the thrust allocation; the design (gains) and the CasADi control law of each must
change together, so they stay in one file.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa_casadi
from usvsim.vessel.loop import LoopAnalysis, analyse_loop, full_loop_transfer
from usvsim.vessel.model import (
    NomotoModel,
    damping_forces,
    linearize,
    linearize_steering,
    mass_matrix,
    nomoto_from_linear,
    thrust_factor,
)
from usvsim.vessel.vessels import Actuation, VesselParams

__all__ = [
    "NC",
    "WAVE_BANDWIDTH_RATIO",
    "WAVE_DESIGN_MIN_HS_M",
    "AutopilotConfig",
    "AutopilotDesign",
    "YawModel",
    "analyse_design",
    "control_law",
    "design_autopilot",
    "design_report",
    "natural_per_bandwidth",
    "sway_yaw_design_model",
    "wave_mode_gain_changes",
]

NC = 5  # controller state size
IDLE_THRUST_FRACTION = 0.05  # -, waterjet idle thrust as a fraction of the maximum (ASSUMED)
# -, idle thrust at most this fraction of the drag at the speed reference (ASSUMED), so a slow
# reference stays reachable (usv105: 5 % of the maximum is the drag at 2.2 m/s); at 3 m/s
# 0.6 drag = 5.2 % of the maximum, above the 5 %: the idle thrust there is unchanged
IDLE_DRAG_FRACTION = 0.6
AutopilotKind = Literal["pid", "rover"]


@dataclass(frozen=True)
class AutopilotConfig:
    """Design choices of the heading autopilot and speed controller (defaults: default vessel)."""

    kind: AutopilotKind = "pid"
    # m/s, linearisation point and default speed reference; None: the vessel's cruise speed
    cruise_speed_mps: float | None = None
    omega_n: float = 2.0  # rad/s, PID closed-loop natural frequency (Fossen 2021, §15.3)
    zeta: float = 1.0  # -, PID closed-loop relative damping
    ref_omega: float = 3.5  # rad/s, reference-model natural frequency
    ref_zeta: float = 1.0  # -, reference-model relative damping
    ref_rate_max: float = math.radians(15.0)  # rad/s, reference-model turn-rate limit
    ref_acc_max: float = math.radians(60.0)  # rad/s², reference-model angular acceleration limit
    integral_max: float = math.radians(20.0)  # rad s, heading-integral clamp (anti-windup)
    speed_omega: float = 0.5  # rad/s, speed-loop bandwidth: k_p,u = 2 ω, k_i,u = ω²
    speed_integral_max: float = 2.0  # m, clamp of the speed-error integral (anti-windup)
    # Waterjets steer harder only with more thrust, which speeds the boat up. The thrust the
    # heading loop may raise is capped at drag(U_ref) + m11 k_cap (U_ref + ΔU - u): full authority
    # at cruise, none above U_ref + ΔU. Measured with random ±30° helm every 2 s at 3 m/s on
    # loe-default: mean speed 3.6 m/s (max 3.9) instead of 5.8 m/s (max 7.3) uncapped; on usv105
    # (the default) mean 3.7 m/s, max 4.03, and 10°/30° steps settle within 1° in 1.5 s / 8.0 s
    thrust_cap_gain: float = 2.0  # 1/s, k_cap
    speed_margin_mps: float = 0.75  # m/s, ΔU
    # -, cap multiplier for moments that stop a turn; None: 2.0 on a hull whose yaw is decoupled
    # from sway, 4.0 on a coupled one (stopping the turn must also stop the sway drift whose
    # Munk moment keeps it turning; with 2.0 the usv105's 10° step overshoots 12 %, with 4.0 7 %)
    brake_cap_factor: float | None = None
    # ArduPilot Rover defaults (ardupilot/libraries/APM_Control/AR_AttitudeControl.cpp)
    rover_ang_p: float = 2.0  # 1/s, ATC_STR_ANG_P
    rover_rate_max: float = math.radians(120.0)  # rad/s, ATC_STR_RAT_MAX
    rover_rate_ff: float = 0.2  # s/rad, ATC_STR_RAT_FF
    rover_rate_p: float = 0.2  # s/rad, ATC_STR_RAT_P
    rover_rate_i: float = 0.2  # 1/rad, ATC_STR_RAT_I
    rover_rate_imax: float = 1.0  # -, ATC_STR_RAT_IMAX
    rover_acc_max: float = math.radians(120.0)  # rad/s², ATC_STR_ACC_MAX

    @classmethod
    def from_name(cls, name: str) -> AutopilotConfig:
        """The named preset: ``pid`` (default), ``rover`` (ArduPilot defaults), ``rover-tuned``."""
        if name == "pid":
            return cls()
        if name == "rover":
            return cls(kind="rover")
        if name == "rover-tuned":
            return cls.rover_tuned()
        raise ValueError(f"unknown autopilot {name!r}; choose pid, rover, rover-tuned")

    @classmethod
    def rover_tuned(cls) -> AutopilotConfig:
        """Rover cascade derived for usv105 at 3 m/s: ``usvsim/mavlink/params/usv105.parm``.

        Derived from the vessel model by :func:`usvsim.mavlink.rover_params.derive_rover_tuning`
        (a test checks they are equal); ArduPilot's defaults give a limit cycle on this hull.
        60° step: within 5° in 7.3 s, 1.3° overshoot; 30°: within 1° in 8.5 s (3.5 %).
        """
        return cls(
            kind="rover",
            rover_ang_p=0.75,
            rover_rate_ff=3.528,
            rover_rate_p=18.527,
            rover_rate_i=1e-6,  # ArduPilot's 0 (see the derivation)
            rover_rate_max=math.radians(12.3),
            rover_acc_max=math.radians(15.4),
        )

    def __post_init__(self) -> None:
        if self.kind not in ("pid", "rover"):
            raise ValueError(f"autopilot kind must be 'pid' or 'rover', got {self.kind!r}")
        for name, value in asdict(self).items():
            if name == "kind" or (
                name in ("cruise_speed_mps", "brake_cap_factor") and value is None
            ):
                continue
            if not math.isfinite(value) or value <= 0:
                raise ValueError(f"AutopilotConfig.{name} must be finite and > 0, got {value}")


@dataclass(frozen=True)
class AutopilotDesign:
    """Numbers the control law needs, plus the design's diagnostics."""

    config: AutopilotConfig
    nomoto: (
        NomotoModel | YawModel
    )  # design model m ṙ + d r = τ_N (m = T/K, d = 1/K), see design_autopilot
    Kp: float  # N m/rad
    Kd: float  # N m s/rad
    Ki: float  # N m/(rad s)
    m11: float  # kg, surge inertia incl. added mass
    tau_n_max: float  # N m, largest yaw moment the actuators can give (for anti-windup)
    cruise_speed_mps: float = 3.0  # m/s, the design speed (config's, else the vessel's)
    design_model: str = "nomoto"  # "nomoto" (first-order hull) or "sway-yaw" (coupled hull)
    brake_cap_factor: float = 2.0  # -, the config's, else by design model (AutopilotConfig)

    @property
    def feedforward_damping(self) -> float:
        """d of the feed-forward τ_N = m a_d + d r_d (N m s/rad): the design d, but not below 0.

        A negative d (a straight-line-unstable hull) is a small-signal property; at the turn
        rates the reference model asks for, the cross-flow drag makes the moment a turn needs
        positive, and a negative feed-forward fights the turn (cybership2: 10° step within 1°
        after 8.5 s instead of 1.8 s).
        """
        return max(self.nomoto.d, 0.0)

    def gains_vector(self) -> NDArray[np.float64]:
        """Parameters fed to the compiled control law (layout: see :func:`control_law`)."""
        c = self.config
        return np.array(
            [
                self.Kp,
                self.Kd,
                self.Ki,
                self.nomoto.m,
                self.feedforward_damping,
                c.ref_omega,
                c.ref_zeta,
                c.ref_rate_max,
                c.ref_acc_max,
                c.integral_max,
                2.0 * c.speed_omega,
                c.speed_omega**2,
                self.m11,
                self.tau_n_max,
                c.rover_ang_p,
                c.rover_rate_max,
                c.rover_rate_ff,
                c.rover_rate_p,
                c.rover_rate_i,
                c.rover_rate_imax,
                c.rover_acc_max,
                c.thrust_cap_gain,
                c.speed_margin_mps,
                c.speed_integral_max,
                self.brake_cap_factor,
            ],
            dtype=float,
        )


NG = 25  # gains vector size


def _max_yaw_moment(act: Actuation, speed_mps: float) -> float:
    if act.kind == "forces":
        return abs(act.lever_m) * min(abs(act.a2_min), abs(act.a2_max))
    if math.isfinite(act.jet_speed_mps):  # delivered thrust at the design speed
        return (
            act.lever_m * act.a1_max * float(thrust_factor(act, speed_mps)) * math.sin(act.a2_max)
        )
    return act.lever_m * act.a1_max * math.sin(act.a2_max)


@dataclass(frozen=True)
class YawModel:
    """Design model m ṙ + d r = τ_N given by its inertia and damping (K = 1/d, T = m/d)."""

    m: float  # kg m², effective yaw inertia
    d: float  # N m s/rad, effective yaw damping (0: none; < 0: straight-line unstable)

    @property
    def K(self) -> float:
        return 1.0 / self.d if self.d != 0 else math.inf

    @property
    def T(self) -> float:
        return self.m / self.d if self.d != 0 else math.inf


def sway_yaw_design_model(vessel: VesselParams, speed_mps: float) -> YawModel:
    """Design model m ṙ + d r = τ_N of a coupled hull, from its true sway–yaw linearisation.

    The first-order Nomoto reduction (T = T1 + T2 - T3) is meaningless on a coupled hull: its
    time constants come out with the wrong sign, and it designs for the wrong inertia (4.2× on
    the usv105 hull, an unstable loop; hull audit). The mass–damper is instead fitted to the two
    asymptotes of the true r / τ_N, G_r(s) = c (sI - A)⁻¹ b (c = [0, 1]; A, b from
    :func:`usvsim.vessel.model.linearize_steering`: sway coupling through M⁻¹, the actuator's
    side force and the hull's own instability included):

    * m = 1 / (c b), the high-frequency inertia (G_r → 1 / (m s) for ω ≫ the hull's poles, the
      range the PID's crossover lies in), so K_p = m ω_n² puts the crossover where intended;
      on usv105 m = 5.46e4 kg m² (I_z - N_ṙ = 6.29e4: the actuator's side force helps);
    * d = 1 / K, K = -c A⁻¹ b the static gain (steady turn rate per moment); negative on a
      straight-line-unstable hull (usv105: d = -6.8e3 N m s), which raises the derivative gain
      K_d = 2 ζ ω_n m - d that stabilises it; d = 0 when A is singular (e.g. Y_v = 0).

    On a decoupled hull both equal the exact first-order Nomoto model (m = I_z - N_ṙ, d = -N_r).
    Chosen over matching the impedance 1/G_r(jω_n) (which gives d = +2.5e4 on usv105, the same
    linear margins, and a 24 % overshoot on the 10° step of the rate-limited nonlinear plant
    instead of 5.5 %). Margins and poles are checked on the full loop (:mod:`usvsim.vessel.loop`).
    """
    A, b = linearize_steering(vessel, speed_mps)
    m = 1.0 / float(b[1, 0])
    if abs(np.linalg.det(A)) < 1e-12 * max(1.0, float(np.abs(A).max()) ** 2):
        d = 0.0
    else:
        d = 1.0 / float(-(np.linalg.solve(A, b))[1, 0])
    return YawModel(m=m, d=d)


def _decoupled(A: NDArray[np.float64], vessel: VesselParams) -> bool:
    """True when yaw does not see sway: the first-order Nomoto model is then exact."""
    M = mass_matrix(vessel)
    return bool(A[1, 0] == 0.0 and M[1, 2] == 0.0 and M[2, 1] == 0.0)


def design_autopilot(
    vessel: VesselParams, config: AutopilotConfig | None = None
) -> AutopilotDesign:
    """Design the heading PID by pole placement (Fossen 2021, §15.3) on the hull at cruise speed.

    The design model m ṙ + d r = τ_N is the first-order Nomoto model when the hull's yaw is
    decoupled from sway (exact there; the Loe presets, the ``default`` vessel) and
    :func:`sway_yaw_design_model` otherwise. The cruise speed is the config's, else the vessel's.
    """
    config = config or AutopilotConfig()
    speed = vessel.cruise_speed_mps if config.cruise_speed_mps is None else config.cruise_speed_mps
    A, B = linearize(vessel, speed)
    nomoto: NomotoModel | YawModel
    if _decoupled(A, vessel):
        nomoto, model = nomoto_from_linear(A, B), "nomoto"
    else:
        nomoto, model = sway_yaw_design_model(vessel, speed), "sway-yaw"
    Kp, Kd, Ki = _pid_gains(nomoto.m, nomoto.d, config.omega_n, config.zeta)
    return AutopilotDesign(
        config=config,
        nomoto=nomoto,
        Kp=Kp,
        Kd=Kd,
        Ki=Ki,
        m11=float(mass_matrix(vessel)[0, 0]),
        tau_n_max=_max_yaw_moment(vessel.actuation, speed),
        cruise_speed_mps=speed,
        design_model=model,
        brake_cap_factor=(
            (2.0 if model == "nomoto" else 4.0)
            if config.brake_cap_factor is None
            else config.brake_cap_factor
        ),
    )


def _pid_gains(m: float, d: float, wn: Any, z: float) -> tuple[Any, Any, Any]:
    """K_p, K_d, K_i by pole placement on m ṙ + d r = τ_N (``wn`` a float or an array)."""
    Kp = m * wn**2  # Fossen (2021) eq. (15.85), no restoring term (k = 0)
    Kd = 2.0 * z * wn * m - d  # eq. (15.86)
    Ki = wn / 10.0 * Kp  # eq. (15.87)
    return Kp, Kd, Ki


#: -, the heading loop's closed-loop bandwidth in waves over the wave encounter frequency,
#: ω_b = ratio × ω_e. Chosen on heading-keeping validation seed 11 (sea states 3 and 4, waves
#: 45° off the quarter) from 1.25, 1, 0.75, 0.5: the largest whose wave filter cuts the nozzle
#: rate by half in both (1.25: sea state 3 cut 48 %); docs/guide/weather.md, *Wave filter*.
WAVE_BANDWIDTH_RATIO = 1.0
#: m, the significant wave height from which the PID takes its wave design: the lower limit of
#: WMO sea state code 2, "smooth (wavelets)", 0.1-0.5 m (code 1, "calm (rippled)", is below).
WAVE_DESIGN_MIN_HS_M = 0.1


def natural_per_bandwidth(zeta: float) -> float:
    """ω_n / ω_b of a second-order closed loop of relative damping ``zeta``: 1 / √(1 − 2ζ² +
    √(4ζ⁴ − 4ζ² + 2)) (Fossen 2021, §15.3; 1.55 at ζ = 1)."""
    z2 = zeta**2
    return 1.0 / math.sqrt(1.0 - 2.0 * z2 + math.sqrt(4.0 * z2 * z2 - 4.0 * z2 + 2.0))


def wave_mode_gain_changes(
    design: AutopilotDesign, omega_e_rad_s: NDArray[np.float64], hs_m: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Changes (N, 3) of [K_p, K_d, K_i] for N boats whose wave filter is on: the PID placed
    with its closed-loop bandwidth at ``WAVE_BANDWIDTH_RATIO`` × the encounter frequency
    ``omega_e_rad_s`` (N,) where that is below the calm design's, in waves of significant
    height ``hs_m`` (N,) of at least ``WAVE_DESIGN_MIN_HS_M``; zero elsewhere and for the
    ``rover`` autopilot.

    With a wave filter the heading loop's bandwidth belongs below the wave band, or it reacts
    to what the filter lets through at wave frequency (Fossen 2021, §13.3 on wave filtering).
    ω_n = min(ω_n, ω_b / √(1 − 2ζ² + √(4ζ⁴ − 4ζ² + 2))), the natural frequency whose
    second-order closed loop has bandwidth ω_b (Fossen 2021, §15.3; 1.55 ω_b at ζ = 1), then
    the gains of :func:`design_autopilot` (eqs. 15.85-15.87) on the same design model.
    """
    c = design.config
    omega_e = np.asarray(omega_e_rad_s, dtype=float)
    out = np.zeros((omega_e.size, 3))
    if c.kind != "pid":
        return out
    wn = np.minimum(c.omega_n, WAVE_BANDWIDTH_RATIO * omega_e * natural_per_bandwidth(c.zeta))
    lower = (np.asarray(hs_m, dtype=float) >= WAVE_DESIGN_MIN_HS_M) & (wn < c.omega_n)
    gains = np.stack(_pid_gains(design.nomoto.m, design.nomoto.d, wn, c.zeta), axis=-1)
    return np.where(lower[:, None], gains - [design.Kp, design.Kd, design.Ki], 0.0)


def _sat(x: Any, lim: Any) -> Any:
    return ca.fmin(ca.fmax(x, -lim), lim)


def _allocate(
    act: Actuation, tau_x: Any, tau_n: Any, thrust_cap: Any, u: Any = None, drag: Any = None
) -> tuple[Any, Any]:
    """Map desired surge force and yaw moment to (actuator command, yaw moment it gives).

    Waterjet: yaw has priority (a waterjet gets more yaw moment only by more thrust), but the
    thrust raised for yaw alone is limited to ``thrust_cap`` (N), which the speed loop lowers
    as the boat runs faster than its reference, so that hard steering does not speed it up.
    With thrust loss (finite ``jet_speed_mps``) the allocation works in delivered thrust and
    commands delivered / (1 - u / V_j) (the jet curve is known to the controller), ``u`` the
    measured surge speed (m/s).
    """
    if act.kind == "forces":
        return ca.vertcat(tau_x, tau_n / act.lever_m), tau_n
    side = tau_n / act.lever_m  # T sin δ needed
    # T cos δ needed; no reverse thrust, and at least idle thrust (5 % of max, ASSUMED) so that
    # the nozzle keeps steering authority and does not chatter when the speed loop asks for less;
    # never more than IDLE_DRAG_FRACTION of the drag at the reference (``drag``, N), which would
    # push the boat above a slow reference
    idle = IDLE_THRUST_FRACTION * act.a1_max
    if drag is not None:
        idle = ca.fmin(idle, IDLE_DRAG_FRACTION * drag)
    fwd = ca.fmax(tau_x, idle)
    nozzle = _sat(ca.atan2(side, fwd), act.a2_max)
    surge_thrust = fwd / ca.cos(nozzle)
    # T = max(fwd / cos δ, |side| / sin δ_max): exact when unsaturated, yaw first when saturated
    yaw_thrust = ca.fabs(side) / math.sin(act.a2_max)
    if math.isfinite(act.jet_speed_mps):
        eta = ca.fmax(thrust_factor(act, u), 0.05)  # never divide by a vanishing jet
        thrust = ca.fmin(ca.fmax(surge_thrust, ca.fmin(yaw_thrust, thrust_cap)), act.a1_max * eta)
        return ca.vertcat(thrust / eta, nozzle), act.lever_m * thrust * ca.sin(nozzle)
    thrust = ca.fmin(ca.fmax(surge_thrust, ca.fmin(yaw_thrust, thrust_cap)), act.a1_max)
    return ca.vertcat(thrust, nozzle), act.lever_m * thrust * ca.sin(nozzle)


def _rover_steering(act: Actuation, steer: Any, tau_x: Any, u: Any) -> Any:
    if act.kind == "forces":  # steer > 0 turns to starboard whichever end the force acts at
        return ca.vertcat(tau_x, (steer if act.lever_m > 0 else -steer) * act.a2_max)
    if math.isfinite(act.jet_speed_mps):
        eta = ca.fmax(thrust_factor(act, u), 0.05)
        return ca.vertcat(ca.fmax(tau_x, 0.0) / eta, steer * act.a2_max)
    return ca.vertcat(ca.fmax(tau_x, 0.0), steer * act.a2_max)


def control_law(
    vessel: VesselParams, kind: AutopilotKind, x: Any, c: Any, cmd: Any, g: Any, dt_s: float
) -> tuple[Any, Any]:
    """One controller update: returns (actuator command a_cmd[2], next controller state c[5]).

    ``x`` plant state [8], ``c`` controller state [5], ``cmd`` = [ψ_ref, U_ref], ``g`` the gains
    vector of :meth:`AutopilotDesign.gains_vector`. The autopilot uses the true ψ, r, u: it stands
    for an inner loop with its own high-rate sensors.
    """
    (
        Kp,
        Kd,
        Ki,
        m_ff,
        d_ff,
        w,
        zr,
        r_max,
        a_max,
        z_max,
        kpu,
        kiu,
        m11,
        tau_n_max,
        ang_p,
        rr_max,
        r_ff,
        r_p,
        r_i,
        r_imax,
        r_acc,
        cap_gain,
        du_allow,
        speed_int_max,
        brake_factor,
    ) = (g[i] for i in range(NG))
    psi, u, r = x[2], x[3], x[5]
    psi_ref, u_ref = cmd[0], cmd[1]

    # surge speed: PI with drag feed-forward (common to both autopilots)
    drag = damping_forces(vessel, ca.vertcat(u_ref, 0.0, 0.0))[0]
    u_err = u - u_ref
    tau_x = drag - m11 * (kpu * u_err + kiu * c[4])
    z_u = _sat(c[4] + dt_s * u_err, speed_int_max)
    # thrust the heading loop may use, falling to the trim thrust at u = u_ref + du_allow
    thrust_cap = drag + m11 * cap_gain * (u_ref + du_allow - u)

    if kind == "pid":
        psi_d, r_d, a_d, z_psi = c[0], c[1], c[2], c[3]
        err = ssa_casadi(psi - psi_d)
        tau_n_des = m_ff * a_d + d_ff * r_d - Kp * err - Kd * (r - r_d) - Ki * z_psi
        tau_n = _sat(tau_n_des, tau_n_max)
        # moments that stop a turn may use brake_factor × the cap (stopping must not be starved)
        cap = ca.if_else(tau_n * r < 0, brake_factor * thrust_cap, thrust_cap)
        a_cmd, tau_n_given = _allocate(vessel.actuation, tau_x, tau_n, cap, u, drag)
        # conditional integration: freeze the integral while the yaw moment saturates
        unsaturated = ca.fabs(tau_n_given - tau_n_des) < 0.01 * tau_n_max
        z_next = _sat(ca.if_else(unsaturated, z_psi + dt_s * err, z_psi), z_max)
        # 3rd-order reference model, Euler-discretised with velocity/acceleration limits
        jerk = (
            w**3 * ssa_casadi(psi_ref - psi_d) - (2 * zr + 1) * w * a_d - (2 * zr + 1) * w**2 * r_d
        )
        a_next = _sat(a_d + dt_s * jerk, a_max)
        r_next = _sat(r_d + dt_s * a_d, r_max)
        psi_next = ssa_casadi(psi_d + dt_s * r_d)
        c_next = ca.vertcat(psi_next, r_next, a_next, z_next, z_u)
    else:
        # AR_AttitudeControl: P, ≤ √(2 |ψ̃| acc_max) (stops in time), ±acc_max dt, ≤ RAT_MAX
        err_psi = ssa_casadi(psi_ref - psi)
        r_des = _sat(ang_p * err_psi, ca.sqrt(2.0 * ca.fabs(err_psi) * r_acc))
        r_des = ca.fmin(ca.fmax(r_des, c[1] - r_acc * dt_s), c[1] + r_acc * dt_s)
        r_des = _sat(r_des, rr_max)
        r_err = r_des - r
        integ = _sat(c[3] + r_i * r_err * dt_s, r_imax)
        steer = _sat(r_ff * r_des + r_p * r_err + integ, 1.0)
        a_cmd = _rover_steering(vessel.actuation, steer, tau_x, u)
        c_next = ca.vertcat(0.0, r_des, 0.0, integ, z_u)
    return a_cmd, c_next


def initial_controller_state(
    kind: AutopilotKind, psi: NDArray[np.float64], r: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Controller state (N, 5) for boats starting at heading psi (rad) and yaw rate r (rad/s)."""
    psi = np.asarray(psi, dtype=float)
    c = np.zeros((psi.shape[0], NC))
    if kind == "pid":
        c[:, 0] = psi
        c[:, 1] = r
    return c


def design_report(vessel: VesselParams, design: AutopilotDesign, dt_s: float = 0.1) -> str:
    """Human-readable design summary: design model, gains, closed-loop poles and margins.

    Poles and margins are those of the FULL linear loop (:mod:`usvsim.vessel.loop`: sway–yaw
    hull, actuator lag, half-sample delay; the slew-rate limit by its describing function), not
    of the model the gains were placed on.
    """
    lines = [
        f"vessel {vessel.name}: L = {vessel.length_m:.2f} m, B = {vessel.beam_m:.2f} m, "
        f"m = {vessel.m:.0f} kg, Iz = {vessel.Iz:.0f} kg m²"
    ]
    n = design.nomoto
    c = design.config
    lines.append(
        f"design model ({design.design_model}) at {design.cruise_speed_mps:.2f} m/s: "
        f"K = {n.K:.4g} rad/(s N m), T = {n.T:.3f} s  (m = {n.m:.4g} kg m², d = {n.d:.4g} N m s)"
    )
    lines.append(
        f"PID ({c.kind} selected): ω_n = {c.omega_n} rad/s, ζ = {c.zeta}: "
        f"K_p = {design.Kp:.4g} N m/rad, K_d = {design.Kd:.4g} N m s/rad, "
        f"K_i = {design.Ki:.4g} N m/(rad s)"
    )
    a = analyse_design(vessel, design, dt_s)
    lines.append(
        "closed-loop poles (full loop): "
        + ", ".join(f"{p.real:.3f}{p.imag:+.3f}j" for p in a.poles)
    )
    lines.append(
        f"full loop: gain margin {a.gain_margin_db:.1f} dB at {a.phase_crossover_rad_s:.2f} rad/s, "
        f"phase margin {a.phase_margin_deg:.1f}° at {a.gain_crossover_rad_s:.2f} rad/s"
    )
    if math.isfinite(vessel.actuation.a2_rate_max):
        lines.append(
            f"slew-rate limit {math.degrees(vessel.actuation.a2_rate_max):.0f} °/s: inactive "
            f"below {a.rate_linear_amplitude_deg:.1f}° amplitude at crossover; phase margin "
            f"{a.phase_margin_rate_limited_deg:.1f}° at {a.rate_check_amplitude_deg:.0f}° "
            "(describing function)"
        )
    lines.append(
        f"reference model: ω = {c.ref_omega} rad/s, ζ = {c.ref_zeta}, "
        f"r_max = {math.degrees(c.ref_rate_max):.1f}°/s, "
        f"a_max = {math.degrees(c.ref_acc_max):.1f}°/s²; "
        f"max yaw moment {design.tau_n_max:.4g} N m"
    )
    return "\n".join(lines)


def analyse_design(
    vessel: VesselParams, design: AutopilotDesign, dt_s: float = 0.1
) -> LoopAnalysis:
    """Margins and poles of the PID of ``design`` on the full linear loop at its design speed."""
    return analyse_loop(vessel, design.cruise_speed_mps, design.Kp, design.Kd, design.Ki, dt_s)


def loop_transfer(vessel: VesselParams, design: AutopilotDesign, dt_s: float = 0.1) -> Any:
    """Open-loop L(s) of the full linear loop (:func:`usvsim.vessel.loop.full_loop_transfer`)."""
    return full_loop_transfer(
        vessel, design.cruise_speed_mps, design.Kp, design.Kd, design.Ki, dt_s
    )
