"""Physics of the CasADi vessel model: analytic properties and a second implementation."""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from usvsim.vessel.model import (
    build_dynamics,
    build_force_dynamics,
    build_rk4_step,
    damping_forces,
    linearize,
    mass_matrix,
    nomoto_from_linear,
)
from usvsim.vessel.vessels import CYBERSHIP2, LOE_DEFAULT, VIKNES830, get_vessel

NO_CURRENT = np.zeros(2)


def simulate(F: ca.Function, x0: np.ndarray, u: np.ndarray, n: int, p=NO_CURRENT) -> np.ndarray:
    xs = np.empty((n, x0.size))
    x = x0
    for k in range(n):
        x = np.asarray(F(x, u, p)).ravel()
        xs[k] = x
    return xs


def surge_drag(v, u: float) -> float:
    return float(damping_forces(v, ca.DM([u, 0.0, 0.0]))[0])


@pytest.mark.parametrize("vessel", [LOE_DEFAULT, VIKNES830, CYBERSHIP2], ids=lambda v: v.name)
def test_steady_surge_speed_is_root_of_thrust_equals_drag(vessel):
    act = vessel.actuation
    thrust = 0.3 * act.a1_max
    # analytic: X_thrust = d(u) u  ->  root of drag(u) - thrust
    u_expected = brentq(lambda u: surge_drag(vessel, u) - thrust, 1e-6, 50.0)
    F = build_rk4_step(build_dynamics(vessel), 0.1)
    x0 = np.zeros(8)
    xs = simulate(F, x0, np.array([thrust, 0.0]), 6000)
    assert xs[-1, 3] == pytest.approx(u_expected, rel=1e-6)
    assert abs(xs[-1, 4]) < 1e-9 and abs(xs[-1, 5]) < 1e-9  # straight: no sway, no yaw


@pytest.mark.parametrize("vessel", [LOE_DEFAULT, VIKNES830], ids=lambda v: v.name)
def test_kinetic_energy_never_increases_without_thrust(vessel):
    # With τ = 0 and no current: dE/dt = -νᵀ D(ν) ν ≤ 0 (C(ν) is skew-symmetric).
    F = build_rk4_step(build_dynamics(vessel), 0.1)
    M = mass_matrix(vessel)
    rng = np.random.default_rng(0)
    for _ in range(5):
        x0 = np.zeros(8)
        x0[3:6] = rng.normal(size=3) * [3.0, 1.0, 0.3]
        x0[2] = rng.uniform(-np.pi, np.pi)
        zero = np.array([max(0.0, vessel.actuation.a1_min), 0.0])
        xs = simulate(F, x0, zero, 600)
        nu = np.vstack([x0[3:6], xs[:, 3:6]])
        energy = 0.5 * np.einsum("ti,ij,tj->t", nu, M, nu)
        assert np.all(np.diff(energy) <= 1e-9 * energy[0])
        assert energy[-1] < 0.05 * energy[0]


@pytest.mark.parametrize("vessel", [LOE_DEFAULT, VIKNES830], ids=lambda v: v.name)
def test_turning_circle_matches_yaw_moment_balance(vessel):
    """Hard-over turn at cruise thrust.

    Expected range (documented): the Loe (2008) hull has no sway-yaw coupling (Y_r = N_v = 0,
    x_g = 0), so the steady yaw rate solves the moment balance -N_r r - N_rrr r³ = τ_N alone and
    the radius is U / r. This hull is known to turn much tighter than a real one (no hull lift):
    about 0.6-0.8 m radius at full steering from 3 m/s; see docs/guide/limitations.md.
    """
    act = vessel.actuation
    cruise_thrust = surge_drag(vessel, 3.0)
    if act.kind == "waterjet":
        command = np.array([cruise_thrust, act.a2_max])
        tau_n = act.lever_m * cruise_thrust * math.sin(act.a2_max)
    else:
        command = np.array([cruise_thrust, act.a2_max])
        tau_n = act.lever_m * act.a2_max
    F = build_rk4_step(build_dynamics(vessel), 0.1)
    x0 = np.zeros(8)
    x0[3] = 3.0
    xs = simulate(F, x0, command, 4000)[2000:]
    r_expected = brentq(lambda r: -vessel.N_r * r - vessel.N_rrr * r**3 - tau_n, 0.0, 10.0)
    assert np.mean(xs[:, 5]) == pytest.approx(r_expected, rel=1e-3)
    centre = xs[:, 0:2].mean(axis=0)
    radius = np.hypot(*(xs[:, 0:2] - centre).T)
    speed = np.hypot(xs[:, 3], xs[:, 4]).mean()
    assert radius.mean() == pytest.approx(speed / r_expected, rel=0.02)
    assert 0.3 < radius.mean() < 1.0  # the documented range for this hull, m


def test_casadi_jacobian_equals_finite_differences():
    f = build_dynamics(CYBERSHIP2)  # added mass, coupled and cubic damping: every term active
    x = ca.SX.sym("x", 8)
    u = ca.SX.sym("u", 2)
    p = ca.SX.sym("p", 2)
    J = ca.Function("J", [x, u, p], [ca.jacobian(f(x, u, p), ca.vertcat(x, u))])
    x0 = np.array([1.0, -2.0, 0.4, 0.6, 0.1, 0.2, 1.0, 0.5])
    u0 = np.array([2.0, 0.5])
    p0 = np.array([0.1, 0.3])
    jac = np.asarray(J(x0, u0, p0))
    z0 = np.concatenate([x0, u0])
    h = 1e-6
    fd = np.empty_like(jac)
    for i in range(z0.size):
        dz = np.zeros_like(z0)
        dz[i] = h
        fp = np.asarray(f(*np.split(z0 + dz, [8]), p0)).ravel()
        fm = np.asarray(f(*np.split(z0 - dz, [8]), p0)).ravel()
        fd[:, i] = (fp - fm) / (2 * h)
    np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-7)


def test_model_matches_second_numpy_implementation():
    """Cross-implementation: M ν̇ = τ - C(ν)ν - D(ν)ν written in NumPy from Fossen (2021)."""
    v = CYBERSHIP2
    f = build_force_dynamics(v)
    nu = np.array([0.5, -0.1, 0.3])
    tau = np.array([1.0, 0.2, -0.3])
    u, vv, r = nu
    m, xg = v.m, v.xg
    C_RB = np.array([[0, 0, -m * (xg * r + vv)], [0, 0, m * u], [m * (xg * r + vv), -m * u, 0]])
    C_A = np.array(
        [
            [0, 0, v.Y_vdot * vv + v.Y_rdot * r],
            [0, 0, -v.X_udot * u],
            [-v.Y_vdot * vv - v.Y_rdot * r, v.X_udot * u, 0],
        ]
    )
    D = -np.array(
        [
            v.X_u * u + v.X_uu * abs(u) * u + v.X_uuu * u**3,
            v.Y_v * vv
            + v.Y_r * r
            + v.Y_vv * abs(vv) * vv
            + v.Y_rv * abs(r) * vv
            + v.Y_vr * abs(vv) * r
            + v.Y_rr * abs(r) * r,
            v.N_v * vv
            + v.N_r * r
            + v.N_vv * abs(vv) * vv
            + v.N_rv * abs(r) * vv
            + v.N_vr * abs(vv) * r
            + v.N_rr * abs(r) * r,
        ]
    )
    nu_dot = np.linalg.solve(mass_matrix(v), tau - (C_RB + C_A) @ nu - D)
    x = np.array([0.0, 0.0, 0.7, *nu])
    out = np.asarray(f(x, tau, [0.0, 0.0])).ravel()
    np.testing.assert_allclose(out[3:6], nu_dot, rtol=1e-12)
    c, s = math.cos(0.7), math.sin(0.7)
    np.testing.assert_allclose(out[0:3], [c * u - s * vv, s * u + c * vv, r], rtol=1e-12)


def test_irrotational_current_drifts_an_unpowered_boat_with_the_water():
    # A boat at rest relative to the water moves with the current: ν_r = 0 stays 0.
    v = LOE_DEFAULT
    F = build_rk4_step(build_dynamics(v), 0.1)
    current = np.array([0.5, math.radians(60.0)])
    x0 = np.zeros(8)
    x0[2] = 0.3
    c, s = math.cos(0.3), math.sin(0.3)
    vc = 0.5 * np.array([math.cos(current[1]), math.sin(current[1])])
    x0[3:5] = [c * vc[0] + s * vc[1], -s * vc[0] + c * vc[1]]
    xs = simulate(F, x0, np.zeros(2), 100, p=current)
    np.testing.assert_allclose(xs[-1, 0:2], vc * 10.0, rtol=1e-9)


def test_rk4_at_100ms_is_accurate_against_fine_reference():
    v = LOE_DEFAULT
    f = build_dynamics(v)
    F = build_rk4_step(f, 0.1)
    cmd = lambda t: np.array([6000.0, math.radians(20.0) * math.sin(0.3 * t)])  # noqa: E731
    x = np.zeros(8)
    x[3] = 3.0
    ref = x.copy()
    for k in range(600):  # 60 s of a weaving manoeuvre, command held per 0.1 s
        u = cmd(0.1 * k)
        x = np.asarray(F(x, u, NO_CURRENT)).ravel()
        sol = solve_ivp(
            lambda t, y, u=u: np.asarray(f(y, u, NO_CURRENT)).ravel(),
            (0, 0.1),
            ref,
            rtol=1e-11,
            atol=1e-11,
            method="DOP853",
        )
        ref = sol.y[:, -1]
    # measured: 0.49 mm and 1.0e-5 rad after 60 s, against 1.5 m GPS noise: 0.1 s is plenty
    assert np.hypot(*(x[0:2] - ref[0:2])) < 5e-3
    assert abs(x[2] - ref[2]) < 1e-4


def test_linear_and_nonlinear_agree_for_small_steps():
    v = LOE_DEFAULT
    A, B = linearize(v, 3.0)
    f_tau = build_force_dynamics(v)
    tau_x = surge_drag(v, 3.0)
    step = 200.0  # N m, small yaw-moment step
    dt, n = 0.01, 500
    x = np.array([0.0, 0.0, 0.0, 3.0, 0.0, 0.0])
    z = np.zeros(2)
    r_nl, r_lin = [], []
    for _ in range(n):
        x = x + dt * np.asarray(f_tau(x, [tau_x, 0.0, step], [0, 0])).ravel()
        z = z + dt * (A @ z + B[:, 0] * step)
        r_nl.append(x[5])
        r_lin.append(z[1])
    np.testing.assert_allclose(r_nl, r_lin, rtol=0.01, atol=1e-3 * max(abs(np.array(r_lin))))


def test_nomoto_of_decoupled_hull_is_inertia_over_damping():
    v = LOE_DEFAULT  # no sway-yaw coupling: r/τ_N = 1/(Iz s - N_r) exactly
    nomoto = nomoto_from_linear(*linearize(v, 3.0))
    assert nomoto.T == pytest.approx((v.Iz - v.N_rdot) / -v.N_r, rel=1e-9)
    assert nomoto.K == pytest.approx(1.0 / -v.N_r, rel=1e-9)


def test_froude_scaled_loe_default_keeps_froude_similarity():
    lam = LOE_DEFAULT.length_m / VIKNES830.length_m
    assert LOE_DEFAULT.m == pytest.approx(VIKNES830.m * lam**3)
    assert LOE_DEFAULT.Iz == pytest.approx(VIKNES830.Iz * lam**5)
    # the Nomoto time constant is a time: it scales with λ^0.5
    t_default = LOE_DEFAULT.Iz / -LOE_DEFAULT.N_r
    t_viknes = VIKNES830.Iz / -VIKNES830.N_r
    assert t_default == pytest.approx(t_viknes * lam**0.5)


def test_unknown_vessel_and_bad_parameters_raise():
    with pytest.raises(ValueError, match=r"unknown vessel 'titanic'.*default"):
        get_vessel("titanic")
    with pytest.raises(ValueError, match="m must be > 0"):
        dataclasses.replace(VIKNES830, m=-1.0)
    with pytest.raises(ValueError, match="X_u must be <= 0"):
        dataclasses.replace(VIKNES830, X_u=5.0)
    with pytest.raises(ValueError, match="finite"):
        dataclasses.replace(VIKNES830, Iz=float("nan"))
    with pytest.raises(ValueError, match="min < max"):
        dataclasses.replace(VIKNES830.actuation, a1_min=10.0, a1_max=1.0)
