"""The heading wave filter (usvsim.vessel.weather.observer in WeatherPlant, issue 38): the
autopilot chases the waves less with it, and its heading step response stays near today's.

Heading keeping at 3 m/s, heading north, waves travelling towards 135° (45° off the quarter,
where the first-order yaw sin 2(β − ψ) is largest); 32 boats, 30 s settling then 300 s measured.
"Nozzle activity" is the RMS of the nozzle angle about zero and of its rate; "heading error" the
RMS of the true (low-frequency) heading, which the sensed wave yaw does not move.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.vessel.autopilot import (
    WAVE_BANDWIDTH_RATIO,
    AutopilotConfig,
    wave_mode_gain_changes,
)
from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.waves import SeaState, sea_state_from_code
from usvsim.vessel.weather_plant import SeaConditions, WeatherPlant

N = 32


def _keep_heading(
    code: int, wave_filter: bool, vessel: str = "default"
) -> tuple[float, float, float]:
    """(nozzle rate RMS °/s, nozzle RMS °, heading error RMS °)."""
    plant = Plant(vessel)
    weather = WeatherPlant(plant, seed=4, wave_filter=wave_filter)
    cond = SeaConditions.uniform(N, sea=sea_state_from_code(code, 0.75 * math.pi))
    state, _ = weather.step(weather.initial_state(np.zeros((N, 3)), cond), 0.0, n_steps=300)
    _, traj = weather.step(state, 0.0, n_steps=3000)
    nozzle, psi = traj[:, :, 7], traj[:, :, 2]
    rate = np.diff(nozzle, axis=1) / plant.dt_s
    return tuple(  # type: ignore[return-value]
        math.degrees(float(np.sqrt(np.mean(v**2)))) for v in (rate, nozzle, psi)
    )


@pytest.mark.parametrize("code", [3, 4])
def test_wave_filter_cuts_nozzle_activity_without_losing_the_heading(code: int) -> None:
    """The filter with the PID's wave design (bandwidth at the encounter frequency,
    autopilot.wave_mode_gain_changes). Measured (seed 4): sea state 4, nozzle 13.7° → 3.4° RMS,
    rate 38.8 → 12.0 °/s, heading error 2.17° → 0.62°; sea state 3: 12.8° → 3.2°,
    36.9 → 12.2 °/s, 1.51° → 0.40° (with the calm gains the rate fell only to 27.9 and 20.6 °/s).
    Asserted, the issue's bar: nozzle RMS and rate at least halved, the heading error not larger.
    """
    rate_off, nozzle_off, err_off = _keep_heading(code, wave_filter=False)
    rate_on, nozzle_on, err_on = _keep_heading(code, wave_filter=True)
    assert nozzle_on <= 0.5 * nozzle_off
    assert rate_on <= 0.5 * rate_off
    assert err_on <= err_off


def test_wave_design_places_the_bandwidth_at_the_encounter_frequency() -> None:
    """The design model's closed loop with the wave gains, ω_n² / (s² + 2ζω_n s + ω_n²)
    (K_p = m ω_n², K_d = 2ζω_n m − d), has |T(jω)| = 1/√2 at ω = WAVE_BANDWIDTH_RATIO × ω_e;
    no change where that is above the calm design, below WAVE_DESIGN_MIN_HS_M, or for rover."""
    design = Plant("default").design
    m, d = design.nomoto.m, design.nomoto.d
    omega_e = np.array([0.5, 0.824, 0.99, 1.5])
    dg = wave_mode_gain_changes(design, omega_e, np.full(4, 1.9))
    kp, kd = design.Kp + dg[:, 0], design.Kd + dg[:, 1]
    wn, two_zeta_wn = np.sqrt(kp / m), (kd + d) / m
    w_b = WAVE_BANDWIDTH_RATIO * omega_e[:3]
    t = wn[:3] ** 2 / np.abs(wn[:3] ** 2 - w_b**2 + 1j * two_zeta_wn[:3] * w_b)
    np.testing.assert_allclose(t, 1.0 / math.sqrt(2.0), rtol=1e-12)
    np.testing.assert_allclose(two_zeta_wn / wn, 2.0 * design.config.zeta, rtol=1e-12)
    np.testing.assert_allclose(design.Ki + dg[:, 2], wn / 10.0 * kp, rtol=1e-12)
    assert np.all(dg[3] == 0.0)  # 1.55 × 1.5 rad/s is above the calm ω_n = 2 rad/s
    assert np.all(wave_mode_gain_changes(design, omega_e, np.full(4, 0.05)) == 0.0)
    rover = Plant("default", AutopilotConfig(kind="rover")).design
    assert np.all(wave_mode_gain_changes(rover, omega_e, np.full(4, 1.9)) == 0.0)


def test_wave_filter_with_instantaneous_force_actuators() -> None:
    """viknes830 (lateral force, no actuator lag: the observer takes the applied command's yaw
    moment, not the actuator state, which does not record it): sea state 4 heading error
    1.85° → 0.65° (measured, 8 boats × 120 s in usvsim demo); asserted: it falls."""
    err_off = _keep_heading(4, False, "viknes830")[2]
    err_on = _keep_heading(4, True, "viknes830")[2]
    assert err_on < 0.7 * err_off


def _step_30(weather: WeatherPlant | None) -> tuple[float, float]:
    """(overshoot °, time until the heading stays within 1° of 30° (s)) of a 30° step."""
    plant = Plant("default")
    if weather is None:
        _, traj = plant.step(plant.initial_state(np.zeros((1, 3))), math.radians(30), n_steps=400)
    else:
        # H_s = 1 mm, T_p 8.8 s: the filter is designed and on, the waves negligible
        cond = SeaConditions.uniform(1, sea=SeaState(0.001, 8.8, 0.75 * math.pi))
        start = weather.initial_state(np.zeros((1, 3)), cond)
        _, traj = weather.step(start, math.radians(30), n_steps=400)
    psi = np.degrees(traj[0, :, 2])
    outside = np.flatnonzero(np.abs(psi - 30.0) > 1.0)
    return float(psi.max() - 30.0), (outside[-1] + 1) * plant.dt_s


def test_step_response_with_the_filter_stays_near_todays() -> None:
    """Today (no filter): 1.7° overshoot, within 1° after 8.0 s. With the filter: 3.0°, 10.3 s
    (the observer's design model is the autopilot's first-order yaw model with the hull's turn
    damping d₂ r|r|, not the hull). H_s 1 mm is below WAVE_DESIGN_MIN_HS_M: the PID keeps its
    calm gains (its wave design in flat water, ω_n 1.28 rad/s: 3.7°, 22.6 s; weather.md).
    Tolerance: overshoot at most 2° more, settling at most 8 s later."""
    today = _step_30(None)
    filtered = _step_30(WeatherPlant(Plant("default"), seed=0, wave_filter=True))
    assert today[0] == pytest.approx(1.66, abs=0.05)
    assert filtered[0] <= today[0] + 2.0
    assert filtered[1] <= today[1] + 8.0
