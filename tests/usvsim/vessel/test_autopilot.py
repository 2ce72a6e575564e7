"""Control properties of the heading autopilots on the NONLINEAR default vessel at 3 m/s."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.vessel.autopilot import AutopilotConfig, design_autopilot, design_report, loop_transfer
from usvsim.vessel.plant import Plant
from usvsim.vessel.vessels import DEFAULT_VESSEL


def step_response(plant: Plant, step_deg: float, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    state = plant.initial_state(np.zeros((1, 3)))
    n = round(seconds / plant.dt_s)
    _, traj = plant.step(state, math.radians(step_deg), n_steps=n)
    t = plant.dt_s * np.arange(1, n + 1)
    return t, np.degrees(traj[0, :, 2])


def settling_time(t: np.ndarray, y: np.ndarray, target: float, band: float) -> float:
    """First time after which |y - target| stays within band."""
    outside = np.nonzero(np.abs(y - target) > band)[0]
    return 0.0 if outside.size == 0 else float(t[outside[-1]])


@pytest.fixture(scope="module")
def pid_plant() -> Plant:
    return Plant("default")


def test_10_degree_step_within_1_degree_by_3_s_overshoot_below_10_percent(pid_plant):
    t, psi = step_response(pid_plant, 10.0, 20.0)
    assert settling_time(t, psi, 10.0, 1.0) <= 3.0  # measured 1.5 s (usv105, 3 m/s)
    assert (psi.max() - 10.0) / 10.0 <= 0.10  # measured 8.1 %
    assert abs(psi[-1] - 10.0) < 0.1  # no steady-state error (integral action)


def test_30_degree_step_within_1_degree_by_10_s_overshoot_below_10_percent(pid_plant):
    t, psi = step_response(pid_plant, 30.0, 20.0)
    # measured 8.0 s: the 15 °/s reference reaches 30° at 2 s, then the straight-line unstable
    # hull's slow mode and the integrator take the 1.7° overshoot back into the band
    assert settling_time(t, psi, 30.0, 1.0) <= 10.0
    assert (psi.max() - 30.0) / 30.0 <= 0.10  # measured 5.5 %
    assert abs(psi[-1] - 30.0) < 0.1


def test_step_across_north_takes_the_short_way(pid_plant):
    state = pid_plant.initial_state(np.array([[0.0, 0.0, math.radians(175.0)]]))
    _, traj = pid_plant.step(state, math.radians(-175.0), n_steps=50)
    psi = np.degrees(np.unwrap(traj[0, :, 2]))
    assert psi.min() >= 174.9  # turns to starboard through 180°, never back through 0°
    assert psi[-1] == pytest.approx(185.0, abs=0.5)


def test_hard_random_helm_does_not_run_away_with_the_speed(pid_plant):
    # a waterjet steers harder only with more thrust; the thrust cap keeps the speed near cruise
    rng = np.random.default_rng(0)
    state = pid_plant.initial_state(np.zeros((32, 3)))
    speeds = []
    for _ in range(75):  # 150 s of ±30° helm every 2 s
        psi_ref = state.x[:, 2] + rng.uniform(-1, 1, 32) * math.radians(30.0)
        state, traj = pid_plant.step(state, psi_ref, n_steps=20)
        speeds.append(traj[:, :, 3])
    u = np.concatenate(speeds, axis=1)
    # m/s; usv105 measured mean 3.7, max 4.03 (loe-default 3.6 / 3.9; uncapped 5.8 / 7.3)
    assert u.max() < 4.25
    assert u.min() > 2.5


def test_speed_controller_holds_cruise_speed(pid_plant):
    state = pid_plant.initial_state(np.zeros((1, 3)), speed_mps=1.5)
    _, traj = pid_plant.step(state, 0.0, speed_ref_mps=3.0, n_steps=400)
    assert traj[0, -1, 3] == pytest.approx(3.0, abs=0.01)


def test_pid_gains_follow_pole_placement_formulas():
    cfg = AutopilotConfig()
    d = design_autopilot(DEFAULT_VESSEL, cfg)
    m, dd, wn = d.nomoto.m, d.nomoto.d, cfg.omega_n
    assert d.Kp == pytest.approx(m * wn**2)
    assert d.Kd == pytest.approx(2 * cfg.zeta * wn * m - dd)
    assert d.Ki == pytest.approx(wn / 10 * d.Kp)


def test_design_has_stable_poles_and_margins():
    import control

    d = design_autopilot(DEFAULT_VESSEL)
    loop = loop_transfer(DEFAULT_VESSEL, d)
    gm, pm, _, _ = control.margin(loop)
    assert 20 * math.log10(gm) > 6.0  # dB
    assert pm > 30.0  # degrees
    assert np.all(control.poles(control.feedback(loop, 1)).real < 0)
    report = design_report(DEFAULT_VESSEL, d)
    assert "phase margin" in report and "closed-loop poles" in report


def test_rover_cascade_tuned_reaches_heading():
    plant = Plant("default", autopilot=AutopilotConfig.rover_tuned())
    t, psi = step_response(plant, 30.0, 40.0)
    assert abs(psi[-1] - 30.0) < 0.5
    assert settling_time(t, psi, 30.0, 1.0) < 10.0  # measured 8.5 s (derived parameters)
    assert (psi.max() - 30.0) / 30.0 < 0.1  # measured 3.5 %


def test_rover_cascade_with_ardupilot_defaults_does_not_settle_on_this_hull():
    # documented behaviour (AutopilotConfig.rover_tuned): defaults tuned for light rovers
    plant = Plant("default", autopilot=AutopilotConfig(kind="rover"))
    t, psi = step_response(plant, 30.0, 30.0)
    assert settling_time(t, psi, 30.0, 1.0) > 20.0


def test_rover_control_law_matches_ardupilot_formula():
    """One update by hand: r_des = P_ang·ψ̃ (limited), steer = FF·r_des + P·(r_des − r) + I."""
    import casadi as ca

    from usvsim.vessel.autopilot import control_law

    cfg = AutopilotConfig(kind="rover")
    d = design_autopilot(DEFAULT_VESSEL, cfg)
    x = np.array([0, 0, 0.0, 3.0, 0, 0.05, 2000.0, 0.0])
    c = np.array([0, 0.0, 0, 0.0, 0.0])
    a_cmd, c_next = control_law(
        DEFAULT_VESSEL,
        "rover",
        ca.DM(x),
        ca.DM(c),
        ca.DM([math.radians(5.0), 3.0]),
        ca.DM(d.gains_vector()),
        0.1,
    )
    r_des = min(2.0 * math.radians(5.0), math.radians(120.0) * 0.1)  # ACC_MAX limits the change
    integ = 0.2 * (r_des - 0.05) * 0.1
    steer = 0.2 * r_des + 0.2 * (r_des - 0.05) + integ
    assert float(c_next[1]) == pytest.approx(r_des)
    assert float(c_next[3]) == pytest.approx(integ)
    assert float(a_cmd[1]) == pytest.approx(steer * DEFAULT_VESSEL.actuation.a2_max)


def test_bad_autopilot_config_raises():
    with pytest.raises(ValueError, match="kind must be 'pid' or 'rover'"):
        AutopilotConfig(kind="bangbang")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="omega_n must be finite and > 0"):
        AutopilotConfig(omega_n=-1.0)
