"""The coupled usv105 hull: Clarke (1983) derivatives, waterjet actuators, and the autopilot
designed on its true linearisation, checked on the full loop and the nonlinear plant.

The "Must show" bars of issue 12 (a boat that turns like a boat); measured values in comments.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

from usvsim.vessel.autopilot import analyse_design, design_autopilot, sway_yaw_design_model
from usvsim.vessel.loop import analyse_loop, full_loop_transfer, rate_limiter_df
from usvsim.vessel.model import (
    build_dynamics,
    build_rk4_step,
    damping_forces,
    linearize,
    linearize_steering,
    mass_matrix,
)
from usvsim.vessel.plant import Plant
from usvsim.vessel.vessels import (
    LOE_DEFAULT,
    USV105,
    VESSELS,
    clarke83_derivatives,
    without_added_mass_coriolis,
)


def test_clarke83_matches_the_regression_by_hand():
    # L = 10.5, B = 3.5, T = 0.55, Cb = 0.36, U = 3: S = π (T/L)², ½ρL³ = 593,283 kg
    d = clarke83_derivatives(10.5, 3.5, 0.55, 0.36, 3.0)
    S = math.pi * (0.55 / 10.5) ** 2
    q = 0.5 * 1025.0
    assert d["Y_vdot"] == pytest.approx(-S * (1 + 0.16 * 0.36 * 3.5 / 0.55 - 5.1 / 9) * q * 10.5**3)
    assert d["Y_v"] == pytest.approx(-S * (1 + 0.4 * 0.36 * 3.5 / 0.55) * q * 10.5**2 * 3.0)
    # the hull audit's figures (from Fossen's clarke83)
    assert d["Y_vdot"] == pytest.approx(-4088, rel=0.002)
    assert d["Y_rdot"] == pytest.approx(-4816, rel=0.002)
    assert d["N_vdot"] == pytest.approx(-5679, rel=0.002)
    assert d["Y_v"] == pytest.approx(-2799, rel=0.002)


def test_added_mass_coriolis_is_not_counted_twice():
    """The model's linearised C_A ν plus the reduced derivatives give Clarke's totals back."""
    totals = clarke83_derivatives(10.5, 3.5, 0.55, 0.36, 3.0)
    reduced = without_added_mass_coriolis(totals, USV105.X_udot, 3.0)
    v = dataclasses.replace(USV105, **reduced, linear_ref_speed_mps=0.0)
    # with no hull damping but Clarke's (no cross-flow), the linearised yaw/sway rows are the
    # totals: -M⁻¹ [[Y_v, Y_r - m U], [N_v, N_r]] (rigid-body m U r kept, as in Fossen's model)
    v = dataclasses.replace(v, Y_vv=0.0, Y_rv=0.0, N_vr=0.0, N_rr=0.0)
    A, _ = linearize(v, 3.0)
    M = mass_matrix(v)[1:, 1:]
    N_tot = np.array([[totals["Y_v"], totals["Y_r"] - v.m * 3.0], [totals["N_v"], totals["N_r"]]])
    assert np.allclose(A, np.linalg.solve(M, N_tot), rtol=1e-9)
    assert reduced["N_v"] == pytest.approx(437, abs=10)  # Munk moment removed: -9.6e3 -> +437


def test_linear_derivatives_scale_with_speed():
    v = USV105
    nu = ca.DM([6.0, -0.1, 0.05])
    lin = damping_forces(dataclasses.replace(v, Y_vv=0, Y_rv=0, N_vr=0, N_rr=0, X_u=0, X_uu=0), nu)
    U = math.hypot(6.0, -0.1)
    assert float(lin[1]) == pytest.approx(-(v.Y_v * -0.1 + v.Y_r * 0.05) * U / 3.0)
    assert float(lin[2]) == pytest.approx(-(v.N_v * -0.1 + v.N_r * 0.05) * U / 3.0)


def test_thrust_falls_with_speed_and_the_reversing_bucket_gives_astern():
    act = USV105.actuation
    F = build_rk4_step(build_dynamics(USV105), 0.1)
    thrust = 0.5 * act.a1_max

    def drag(u: float) -> float:
        return float(damping_forces(USV105, ca.DM([u, 0.0, 0.0]))[0])

    # steady speed: drag(u) = T (1 - u / V_j)   (momentum theory at constant flow)
    u_expected = brentq(lambda u: drag(u) - thrust * (1 - u / act.jet_speed_mps), 0.1, 20.0)
    x = np.zeros(8)
    for _ in range(4000):
        x = np.asarray(F(x, [thrust, 0.0], [0.0, 0.0])).ravel()
    assert x[3] == pytest.approx(u_expected, rel=1e-6)  # 8.25 m/s at 12 kN
    assert u_expected < brentq(lambda u: drag(u) - thrust, 0.1, 20.0)  # slower than no loss
    x = np.zeros(8)
    x[3] = 3.0
    x = np.asarray(F(x, [act.a1_min, 0.0], [0.0, 0.0])).ravel()
    assert x[6] < 0  # astern thrust builds up


def test_nozzle_slew_rate_is_limited():
    act = USV105.actuation
    F = build_rk4_step(build_dynamics(USV105), 0.1)
    x = np.zeros(8)
    x[3], x[6] = 3.0, 2500.0
    path = []
    for _ in range(10):
        x = np.asarray(F(x, [2500.0, act.a2_max], [0.0, 0.0])).ravel()
        path.append(x[7])
    rates = np.diff(np.concatenate([[0.0], path])) / 0.1
    assert rates.max() <= act.a2_rate_max * (1 + 1e-9)  # 60 °/s
    assert rates[0] == pytest.approx(act.a2_rate_max)  # a first-order lag alone: 180 °/s


def test_design_model_comes_from_the_true_linearisation():
    d = design_autopilot(USV105)
    assert d.design_model == "sway-yaw"
    A, b = linearize_steering(USV105, 3.0)
    assert d.nomoto.m == pytest.approx(1.0 / b[1, 0])  # 5.46e4 kg m² (Nomoto reduction: 2.7e5)
    assert d.nomoto.d == pytest.approx(1.0 / float(-np.linalg.solve(A, b)[1, 0]))
    assert d.nomoto.d < 0  # straight-line unstable hull (eigenvalue +0.052 /s)
    assert d.feedforward_damping == 0.0
    # a decoupled hull keeps the exact Nomoto design (bit-identical gains for `loe-default`)
    assert design_autopilot(LOE_DEFAULT).design_model == "nomoto"


def test_design_with_no_linear_sway_damping_does_not_fail():
    # Otter-style ratios with Y_v = 0 made the Nomoto route return NaN (hull audit)
    v = dataclasses.replace(USV105, Y_v=0.0, Y_vv=-1325.0)
    model = sway_yaw_design_model(v, 3.0)
    assert math.isfinite(model.m) and math.isfinite(model.d)
    assert analyse_design(v, design_autopilot(v)).stable


def test_full_loop_of_a_decoupled_hull_is_the_nomoto_loop():
    """Second implementation: for `loe-default` L(jω) equals K/(jω(1+Tjω)) · PID · lag · Padé."""
    import control

    d = design_autopilot(LOE_DEFAULT)
    L = full_loop_transfer(LOE_DEFAULT, 3.0, d.Kp, d.Kd, d.Ki, 0.1)
    s = control.tf("s")
    n = d.nomoto
    num, den = control.pade(0.05, 2)
    ref = (d.Kp + d.Ki / s + d.Kd * s) * n.K / (s * (1 + n.T * s)) / (1 + 0.15 * s)
    ref = ref * control.tf(num, den)
    w = np.array([0.1, 1.0, 3.0, 10.0])
    assert np.allclose(L(1j * w), ref(1j * w), rtol=1e-6)


def test_slew_limit_costs_phase_margin_only_above_its_linear_amplitude():
    d = design_autopilot(USV105)
    a = {amp: analyse_loop(USV105, 3.0, d.Kp, d.Kd, d.Ki, 0.1, amp) for amp in (10.0, 27.0)}
    assert a[10.0].rate_linear_amplitude_deg == pytest.approx(16.6, abs=0.2)  # 60 °/s / ω_c
    assert a[10.0].phase_margin_rate_limited_deg == pytest.approx(a[10.0].phase_margin_deg, abs=0.5)
    assert a[27.0].phase_margin_rate_limited_deg < a[10.0].phase_margin_deg - 5  # 33.4°


def test_rate_limiter_describing_function_matches_the_triangle_wave():
    # for small ρ the output is a triangle wave: |N| = 4ρ/π, lag arccos(πρ/2)
    for rho in (0.2, 0.4):
        N = complex(rate_limiter_df(rho)[0])
        assert abs(N) == pytest.approx(4 * rho / math.pi, rel=0.01)
        assert -np.angle(N) == pytest.approx(math.acos(math.pi * rho / 2), abs=0.02)
    assert complex(rate_limiter_df(1.5)[0]) == 1.0


# --- the Must-show bars of the autopilot, every preset at its own cruise speed ------------------


@pytest.mark.parametrize("name", sorted(VESSELS))
def test_full_loop_margins_and_poles(name):
    v = VESSELS[name]
    a = analyse_design(v, design_autopilot(v))
    # measured (GM dB / PM deg): usv105 13.4 / 43.3, default 13.1 / 36.5, cybership2 9.1 / 39.1,
    # viknes830 17.9 / 65.0, viknes830_nr3224 18.2 / 66.1
    assert a.gain_margin_db >= 6.0
    assert a.phase_margin_deg >= 35.0
    assert a.stable
    if math.isfinite(v.actuation.a2_rate_max):  # usv105: 40.7° with the slew limit at 20°
        assert a.phase_margin_rate_limited_deg >= 35.0


def _step(plant: Plant, deg: float, seconds: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    n = round(seconds / plant.dt_s)
    _, traj = plant.step(plant.initial_state(np.zeros((1, 3))), math.radians(deg), n_steps=n)
    return np.degrees(traj[0, :, 2]), traj[0, :, 7]


def _settled_after(psi: np.ndarray, target: float, dt_s: float) -> float:
    outside = np.nonzero(np.abs(psi - target) > 1.0)[0]
    return 0.0 if outside.size == 0 else float((outside[-1] + 1) * dt_s)


def _helm_deg(v, a2: np.ndarray) -> np.ndarray:
    """Steering actuator in degrees (waterjet) or its share of 30° (force actuators)."""
    if v.actuation.kind == "waterjet":
        return np.degrees(a2)
    return a2 / v.actuation.a2_max * 30.0


@pytest.fixture(scope="module", params=sorted(VESSELS))
def plant(request) -> Plant:
    return Plant(request.param)


def test_10_degree_step_within_1_degree_by_3_s(plant):
    psi, _ = _step(plant, 10.0)
    # usv105 1.5 s, default 1.5 s, cybership2 1.8 s, viknes830 2.2 s
    assert _settled_after(psi, 10.0, plant.dt_s) <= 3.0
    assert abs(psi[-1] - 10.0) < 0.1


def test_30_degree_step_overshoot_at_most_10_percent_and_no_limit_cycle(plant):
    psi, a2 = _step(plant, 30.0)
    assert (psi.max() - 30.0) / 30.0 <= 0.10  # usv105 5.5 %, cybership2 5.8 %, default 2.0 %
    steady = _helm_deg(plant.vessel, a2[-100:])  # the last 10 s
    assert steady.max() - steady.min() < 1.0  # usv105 0.02°, cybership2 0.13° equivalent


def test_usv105_heading_after_2_s_of_a_30_degree_step():
    psi, _ = _step(Plant("usv105"), 30.0, 2.0)
    # reported: 15.7° after 2 s (the reference model's 15 °/s limit gives ψ_d = 22°); the task
    # changes its reference by up to 30° every 2 s, so a full 30° change takes two decisions
    assert psi[-1] == pytest.approx(15.7, abs=0.5)


def test_usv105_hard_random_helm_keeps_the_speed_near_cruise():
    p = Plant("usv105")
    rng = np.random.default_rng(0)
    state = p.initial_state(np.zeros((16, 3)))
    speeds = []
    for _ in range(40):  # 80 s of ±30° helm every 2 s
        psi_ref = state.x[:, 2] + rng.uniform(-1, 1, 16) * math.radians(30.0)
        state, traj = p.step(state, psi_ref, n_steps=20)
        speeds.append(traj[:, :, 3])
    u = np.concatenate(speeds, axis=1)
    assert 2.8 < u.min() and u.max() < 4.2  # measured 2.96 .. 4.03 m/s (mean 3.7)
