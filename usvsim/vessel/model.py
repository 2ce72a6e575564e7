"""The vessel model as pure CasADi functions, and the operations on it.

State and input layout (one boat; the batched code uses arrays of shape (N, ·)):

=========  =====================================================  =====================
symbol     meaning                                                 units
=========  =====================================================  =====================
x[0:3]     η = [x_N, y_E, ψ]: NED position and heading            m, m, rad
x[3:6]     ν = [u, v, r]: body velocities over ground              m/s, m/s, rad/s
x[6:8]     a: actual actuator values (see ``vessels.Actuation``)  N, N | N, rad
u[0:2]     a_cmd: commanded actuator values (saturated here)      as a
p[0:2]     ocean current: speed V_c and direction β_c (going to)  m/s, rad
p[2:5]     weather only: environmental load τ_env = [X, Y, N]    N, N, N m
=========  =====================================================  =====================

Equations (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed.):

* kinematics η̇ = R(ψ) ν (§2.2; 3-DOF rotation about z);
* kinetics with an irrotational, constant current (§10.3, Property 10.1): with ν_r = ν − ν_c and
  ν_c = R(ψ)ᵀ [V_c cos β_c, V_c sin β_c, 0]ᵀ,
  M ν̇_r + C_RB(ν_r) ν_r + C_A(ν_r) ν_r + D(ν_r) ν_r = τ, and ν̇ = ν̇_r − S(r) ν_c;
* M = M_RB + M_A (eq. 6.54), C_RB and C_A the 3-DOF Coriolis–centripetal matrices (eqs. 6.43,
  6.44), D(ν_r) linear + modulus-quadratic + cubic damping;
* first-order actuators ȧ = (sat(a_cmd) − a) / T_a; with T_a = 0 the actuator is instantaneous;
  the steering actuator's rate optionally limited, |ȧ2| ≤ a2_rate_max; a waterjet's delivered
  thrust optionally falls with speed (:func:`thrust_factor`);
* with ``weather`` (:func:`build_dynamics`), an environmental load τ_env (wind and wave drift,
  :mod:`usvsim.vessel.weather.loads`, held over the step by the caller) enters as
  ν̇ += M⁻¹ τ_env, added last, so that τ_env = 0 leaves every other operation as it was.

Hulls whose linear derivatives come from captive-model tests (e.g. Clarke et al. 1983) already
contain the linearised added-mass Coriolis terms (Munk moment); this model adds C_A(ν_r) ν_r
itself, so such derivatives must be given without it
(:func:`usvsim.vessel.vessels.without_added_mass_coriolis`), or they count twice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.vessel.vessels import Actuation, VesselParams

__all__ = [
    "NP_WEATHER",
    "NX",
    "NomotoModel",
    "build_dynamics",
    "build_rk4_step",
    "damping_forces",
    "generalized_forces",
    "linearize",
    "linearize_steering",
    "mass_matrix",
    "nomoto_from_linear",
    "steering_direction",
    "surge_trim",
    "thrust_factor",
]

NX = 8  # plant state size
NU = 2  # actuator command size
NP = 2  # parameter size: current speed (m/s) and direction (rad)
NP_WEATHER = 5  # with weather: current, then the environmental load [X, Y, N] (N, N, N m)


def mass_matrix(v: VesselParams) -> NDArray[np.float64]:
    """System inertia matrix M = M_RB + M_A (3×3), Fossen (2021) eq. (6.54) for 3 DOF."""
    M_RB = np.array([[v.m, 0.0, 0.0], [0.0, v.m, v.m * v.xg], [0.0, v.m * v.xg, v.Iz]])
    M_A = -np.array([[v.X_udot, 0.0, 0.0], [0.0, v.Y_vdot, v.Y_rdot], [0.0, v.N_vdot, v.N_rdot]])
    return M_RB + M_A


def _coriolis(v: VesselParams, nu_r: Any) -> Any:
    """C_RB(ν_r) ν_r + C_A(ν_r) ν_r (3-vector), Fossen (2021) eqs. (6.43)-(6.44), 3 DOF."""
    u, vv, r = nu_r[0], nu_r[1], nu_r[2]
    # rigid body (CO not at CG: xg)
    c_rb = ca.vertcat(
        -v.m * (v.xg * r + vv) * r,
        v.m * u * r,
        v.m * (v.xg * r + vv) * u - v.m * u * vv,
    )
    # added mass (Y_rdot = N_vdot assumed symmetric in C_A, Fossen 2021 eq. 6.44)
    a_y = v.Y_vdot * vv + 0.5 * (v.Y_rdot + v.N_vdot) * r
    c_a = ca.vertcat(
        a_y * r,
        -v.X_udot * u * r,
        -a_y * u + v.X_udot * u * vv,
    )
    return c_rb + c_a


def damping_forces(v: VesselParams, nu_r: Any) -> Any:
    """Damping D(ν_r) ν_r (3-vector of positive-opposing forces, N and N m)."""
    u, vv, r = nu_r[0], nu_r[1], nu_r[2]
    au, av, ar = ca.fabs(u), ca.fabs(vv), ca.fabs(r)
    X = v.X_u * u + v.X_uu * au * u + v.X_uuu * u**3
    # linear sway/yaw derivatives ∝ U_r (prime system, Fossen 2021 App. D) when the vessel says so
    Y_lin, N_lin = v.Y_v * vv + v.Y_r * r, v.N_v * vv + v.N_r * r
    if v.linear_ref_speed_mps > 0:
        scale = ca.sqrt(u**2 + vv**2) / v.linear_ref_speed_mps
        Y_lin, N_lin = scale * Y_lin, scale * N_lin
    Y = (
        Y_lin
        + v.Y_vv * av * vv
        + v.Y_rv * ar * vv
        + v.Y_vr * av * r
        + v.Y_rr * ar * r
        + v.Y_vvv * vv**3
    )
    N = (
        N_lin
        + v.N_vv * av * vv
        + v.N_rv * ar * vv
        + v.N_vr * av * r
        + v.N_rr * ar * r
        + v.N_rrr * r**3
    )
    return -ca.vertcat(X, Y, N)


def thrust_factor(act: Actuation, u_r: Any) -> Any:
    """Delivered / bollard waterjet thrust at relative surge speed u_r: 1 - u_r / V_j, in [0, 1].

    Ahead thrust only (a1 >= 0); astern (reversing bucket) thrust is taken as speed-independent
    (ASSUMED). Returns 1.0 when the vessel has no thrust-loss model.
    """
    if not math.isfinite(act.jet_speed_mps):
        return 1.0
    return ca.fmin(ca.fmax(1.0 - u_r / act.jet_speed_mps, 0.0), 1.0)


def generalized_forces(act: Actuation, a: Any, u_r: Any = 0.0) -> Any:
    """τ = [X, Y, N] (N, N, N m) produced by the actuator values ``a`` (see module docstring).

    ``u_r`` (m/s) is the relative surge speed, used only by a waterjet with thrust loss.
    """
    if act.kind == "forces":
        return ca.vertcat(a[0], a[1], act.lever_m * a[1])
    thrust, nozzle = a[0], a[1]
    if math.isfinite(act.jet_speed_mps):
        thrust = ca.if_else(thrust > 0, thrust * thrust_factor(act, u_r), thrust)
    side = thrust * ca.sin(nozzle)
    return ca.vertcat(thrust * ca.cos(nozzle), -side, act.lever_m * side)


def surge_trim(v: VesselParams, speed_mps: Any) -> Any:
    """Actuator a1 (N) that holds ``speed_mps`` (m/s) straight ahead: the surge drag, as bollard
    thrust when the waterjet loses thrust with speed (drag / (1 - u / V_j)). Not clipped.
    """
    drag = damping_forces(v, ca.vertcat(speed_mps, 0, 0))[0]
    if math.isfinite(v.actuation.jet_speed_mps):
        drag = drag / ca.fmax(thrust_factor(v.actuation, speed_mps), 0.05)
    return drag


def saturate_command(act: Actuation, a_cmd: Any) -> Any:
    """Clip the actuator command to its limits (element-wise)."""
    return ca.vertcat(
        ca.fmin(ca.fmax(a_cmd[0], act.a1_min), act.a1_max),
        ca.fmin(ca.fmax(a_cmd[1], act.a2_min), act.a2_max),
    )


def _current_body(x: Any, p: Any) -> Any:
    """ν_c: the irrotational NED current p = [V_c, β_c] in body axes (3-vector)."""
    c, s = ca.cos(x[2]), ca.sin(x[2])
    vc_n = p[0] * ca.cos(p[1])
    vc_e = p[0] * ca.sin(p[1])
    return ca.vertcat(c * vc_n + s * vc_e, -s * vc_n + c * vc_e, 0.0)


def _rigid_body_rates(
    v: VesselParams, x: Any, tau: Any, p: Any, weather: bool = False
) -> tuple[Any, Any]:
    """Return (η̇, ν̇) for state ``x`` (≥ 6 entries) under generalised force ``tau``; with
    ``weather``, plus the environmental load ``p[2:5]``."""
    psi = x[2]
    nu = x[3:6]
    c, s = ca.cos(psi), ca.sin(psi)
    # current in NED -> body (irrotational, constant in NED)
    nu_c = _current_body(x, p)
    nu_r = nu - nu_c
    Minv = np.linalg.inv(mass_matrix(v))
    nu_r_dot = ca.mtimes(ca.DM(Minv), tau - _coriolis(v, nu_r) - damping_forces(v, nu_r))
    r = nu[2]
    nu_c_dot = ca.vertcat(r * nu_c[1], -r * nu_c[0], 0.0)  # -S(r) ν_c
    eta_dot = ca.vertcat(c * nu[0] - s * nu[1], s * nu[0] + c * nu[1], nu[2])
    nu_dot = nu_r_dot + nu_c_dot
    if weather:  # last, so that τ_env = 0 leaves every other operation as it was
        nu_dot = nu_dot + ca.mtimes(ca.DM(Minv), p[2:5])
    return eta_dot, nu_dot


def build_dynamics(v: VesselParams, weather: bool = False) -> ca.Function:
    """The plant as one pure CasADi Function ``f(x[8], u[2], p[2]) -> xdot[8]``.

    Inputs named ``x``, ``u``, ``p``; output ``xdot``. See the module docstring for the layout.
    With ``weather``, ``p`` has :data:`NP_WEATHER` entries: the current and an environmental
    load τ_env (wind, wave drift); with τ_env = 0 it gives the numbers of the function without
    weather (bit for bit in CasADi's virtual machine, tested).
    """
    x = ca.SX.sym("x", NX)
    u = ca.SX.sym("u", NU)
    p = ca.SX.sym("p", NP_WEATHER if weather else NP)
    act = v.actuation
    a_cmd = saturate_command(act, u)
    a_dot = []
    a_eff = []
    for i in range(2):
        lag = act.lag_s[i]
        if lag > 0:
            rate = (a_cmd[i] - x[6 + i]) / lag
            if i == 1 and math.isfinite(act.a2_rate_max):  # slew-rate limit of the steering
                rate = ca.fmin(ca.fmax(rate, -act.a2_rate_max), act.a2_rate_max)
            a_dot.append(rate)
            a_eff.append(x[6 + i])
        else:  # instantaneous actuator: the state just records the applied command
            a_dot.append(ca.SX(0.0))
            a_eff.append(a_cmd[i])
    u_r = x[3] - _current_body(x, p)[0] if math.isfinite(act.jet_speed_mps) else 0.0
    tau = generalized_forces(act, ca.vertcat(*a_eff), u_r)
    eta_dot, nu_dot = _rigid_body_rates(v, x, tau, p, weather)
    xdot = ca.vertcat(eta_dot, nu_dot, *a_dot)
    return ca.Function("f", [x, u, p], [xdot], ["x", "u", "p"], ["xdot"])


def build_force_dynamics(v: VesselParams) -> ca.Function:
    """Rigid-body model with generalised force input: ``f_tau(x[6], tau[3], p[2]) -> xdot[6]``.

    Used for linearisation and autopilot design (the actuator is a separate, allocated layer).
    """
    x = ca.SX.sym("x", 6)
    tau = ca.SX.sym("tau", 3)
    p = ca.SX.sym("p", NP)
    eta_dot, nu_dot = _rigid_body_rates(v, x, tau, p)
    return ca.Function(
        "f_tau", [x, tau, p], [ca.vertcat(eta_dot, nu_dot)], ["x", "tau", "p"], ["xdot"]
    )


def rk4_expr(f: ca.Function, x: Any, u: Any, p: Any, dt_s: float) -> Any:
    """One classical Runge–Kutta-4 step of ``f`` with ``u`` held (zero-order hold) over dt_s."""
    k1 = f(x, u, p)
    k2 = f(x + 0.5 * dt_s * k1, u, p)
    k3 = f(x + 0.5 * dt_s * k2, u, p)
    k4 = f(x + dt_s * k3, u, p)
    return x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def build_rk4_step(f: ca.Function, dt_s: float = 0.1, n_sub: int = 1) -> ca.Function:
    """Discrete plant ``F(x, u, p) -> x_next`` over dt_s, with ``n_sub`` RK4 sub-steps."""
    if dt_s <= 0 or n_sub < 1:
        raise ValueError("dt_s must be > 0 and n_sub >= 1")
    x = ca.SX.sym("x", f.size1_in(0))
    u = ca.SX.sym("u", f.size1_in(1))
    p = ca.SX.sym("p", f.size1_in(2))
    xn = x
    h = dt_s / n_sub
    for _ in range(n_sub):
        xn = rk4_expr(f, xn, u, p, h)
    return ca.Function("F", [x, u, p], [xn], ["x", "u", "p"], ["x_next"])


@dataclass(frozen=True)
class NomotoModel:
    """First-order Nomoto model r/τ_N(s) = K / (1 + T s) (Fossen 2021, §7.2).

    Equivalent mass–damper form used by the PID design: ``m ṙ + d r = τ_N`` with m = T/K
    (kg m²) and d = 1/K (N m s/rad).
    """

    K: float  # rad/s per N m
    T: float  # s

    @property
    def m(self) -> float:
        return self.T / self.K

    @property
    def d(self) -> float:
        return 1.0 / self.K


def linearize(
    v: VesselParams, speed_mps: float, current: tuple[float, float] = (0.0, 0.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Linearise the sway–yaw dynamics at straight-line cruise with CasADi Jacobians.

    Returns (A, B) with state [v, r] (m/s, rad/s) and input τ_N (N m), evaluated at
    ν = [speed_mps, 0, 0], ψ = 0 and the given current (V_c m/s, β_c rad).
    """
    f_tau = build_force_dynamics(v)
    x = ca.SX.sym("x", 6)
    tau = ca.SX.sym("tau", 3)
    p = ca.DM(list(current))
    xdot = f_tau(x, tau, p)
    A_full = ca.Function("A", [x, tau], [ca.jacobian(xdot, x)])
    B_full = ca.Function("B", [x, tau], [ca.jacobian(xdot, tau)])
    x0 = ca.DM([0.0, 0.0, 0.0, speed_mps, 0.0, 0.0])
    # τ_X balancing surge drag at the operating point; τ_Y = τ_N = 0
    drag = damping_forces(v, ca.DM([speed_mps, 0.0, 0.0]))
    tau0 = ca.vertcat(drag[0], 0.0, 0.0)
    A = np.array(A_full(x0, tau0))[np.ix_([4, 5], [4, 5])]
    B = np.array(B_full(x0, tau0))[np.ix_([4, 5], [2])]
    return A, B


def steering_direction(act: Actuation) -> NDArray[np.float64]:
    """Generalised force [X, Y, N] per unit yaw moment of the steering actuator (1/m, 1/m, 1).

    Forces: F_y gives Y = F_y, N = l F_y; waterjet: the nozzle's side force -T sin δ acts at the
    transom, Y = -N / l. The sway force matters on a coupled hull (it excites v, which turns).
    """
    sign = 1.0 if act.kind == "forces" else -1.0
    return np.array([0.0, sign / act.lever_m, 1.0])


def linearize_steering(
    v: VesselParams, speed_mps: float, current: tuple[float, float] = (0.0, 0.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sway–yaw (A, b) at straight-line cruise with the actuator's own force direction.

    Like :func:`linearize` (state [v, r]) but the input is the steering actuator's yaw moment
    τ_N (N m), which also pushes sideways (:func:`steering_direction`): b = B_τ [Y/τ_N, 1].
    """
    A, _ = linearize(v, speed_mps, current)
    f_tau = build_force_dynamics(v)
    x = ca.SX.sym("x", 6)
    tau = ca.SX.sym("tau", 3)
    jac = ca.Function("B", [x, tau], [ca.jacobian(f_tau(x, tau, ca.DM(list(current))), tau)])
    B_tau = np.array(jac(ca.DM([0.0, 0.0, 0.0, speed_mps, 0.0, 0.0]), ca.DM.zeros(3)))
    b = B_tau[np.ix_([4, 5], [0, 1, 2])] @ steering_direction(v.actuation)
    return A, b.reshape(2, 1)


def nomoto_from_linear(A: NDArray[np.float64], B: NDArray[np.float64]) -> NomotoModel:
    """First-order Nomoto (K, T) from the sway–yaw (A, B) (Fossen 2021, §7.2).

    The second-order model r/τ_N = K (1 + T3 s) / ((1 + T1 s)(1 + T2 s)) is reduced to first order
    with T = T1 + T2 − T3 and the same static gain K. Handles the decoupled case (B's sway row 0
    and A's coupling 0) where the model already is first order.
    """
    import control

    sys = control.ss(A, B, np.array([[0.0, 1.0]]), np.zeros((1, 1)))
    tf = control.ss2tf(sys)
    num = np.trim_zeros(np.asarray(tf.num[0][0], dtype=float), "f")
    den = np.trim_zeros(np.asarray(tf.den[0][0], dtype=float), "f")
    K = float(num[-1] / den[-1])
    # time constants from roots: den = c (1 + T1 s)(1 + T2 s) -> T_i = -1/p_i
    poles = np.roots(den)
    zeros = np.roots(num) if len(num) > 1 else np.array([])
    T_sum = float(np.sum(-1.0 / poles.real))
    T3 = float(np.sum(-1.0 / zeros.real)) if len(zeros) else 0.0
    # cancel a pole–zero pair that lies on top of each other (decoupled sway)
    return NomotoModel(K=K, T=T_sum - T3)
