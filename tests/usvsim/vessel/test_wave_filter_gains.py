"""The wave filter's steady-state gains (usvsim.vessel.weather.observer, issue 38): the batched
Riccati doubling equals scipy's Schur solution boat by boat, and WeatherPlant.initial_state
takes the generator and the filter switch as arguments."""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_discrete_are

from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.observer import ObserverNoise, observer_gains, solve_filter_riccati
from usvsim.vessel.weather.waves import sea_state_from_code, wave_motion_discrete
from usvsim.vessel.weather.wind import GustParams
from usvsim.vessel.weather_plant import (
    WEATHER_INPUTS,
    SeaConditions,
    WeatherPlant,
    weather_inputs,
)

H = np.array([[1.0, 0.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 1.0, 0.0]])


def _random_seas(n: int, seed: int) -> tuple[SeaConditions, np.ndarray, np.ndarray]:
    """n boats with H_s 0-3 m (the first 8 calm), T_p 5-12 s, any wave direction, heading and
    speed 0-4 m/s."""
    rng = np.random.default_rng(seed)
    hs = rng.uniform(0.0, 3.0, n)
    hs[:8] = 0.0
    cond = SeaConditions(
        rng.uniform(0.0, 12.0, n),
        rng.uniform(-math.pi, math.pi, n),
        np.full(n, 0.1),
        hs,
        rng.uniform(5.0, 12.0, n),
        rng.uniform(-math.pi, math.pi, n),
    )
    return cond, rng.uniform(0.0, 4.0, n), rng.uniform(-math.pi, math.pi, n)


def _scipy_gains(a, q, r):
    """The reference: one scipy DARE per boat (the dual control form), L = P Hᵀ (H P Hᵀ + R)⁻¹."""
    out = []
    for ai, qi in zip(a, q, strict=True):
        p = solve_discrete_are(ai.T, H.T, qi, r)
        out.append(p @ H.T @ np.linalg.inv(H @ p @ H.T + r))
    return np.stack(out)


def test_doubling_equals_scipy_for_random_seas_and_both_autopilot_kinds() -> None:
    """200 boats per vessel (usv105's waterjet PID, viknes830's force actuators). Measured:
    gains within 5e-12 of each boat's largest gain (elementwise 6e-8 on entries ~1e-9 of it);
    Riccati residual 1.9e-15 (scipy's 2.7e-14). Asserted: 1e-10 relative to the largest gain."""
    noise = ObserverNoise()
    r = np.diag([noise.compass_rad**2, noise.gyro_rad_s**2])
    for vessel in ("default", "viknes830"):
        plant = Plant(vessel)
        weather = WeatherPlant(plant)
        cond, speed, heading = _random_seas(200, seed=7)
        _, resp = weather_inputs(
            cond, speed, heading, plant.dt_s, GustParams(), noise, weather.yaw_model
        )
        phi, chol = wave_motion_discrete(resp, plant.dt_s)
        scale = resp.omega0**3 / 9.81 * np.sin(2.0 * (cond.wave_dir_rad - heading))
        gains = observer_gains(phi, chol, scale, *weather.yaw_model, plant.dt_s, noise)
        m, d = weather.yaw_model
        a = np.zeros((200, 5, 5))
        a[:, 0:2, 0:2] = phi
        a[:, 2, 2], a[:, 2, 3], a[:, 3, 3] = 1.0, plant.dt_s, 1.0 - plant.dt_s * d / m
        a[:, 3, 4], a[:, 4, 4] = plant.dt_s / m, 1.0
        q = np.zeros((200, 5, 5))
        q[:, 0:2, 0:2] = scale[:, None, None] ** 2 * chol @ np.swapaxes(chol, 1, 2)
        q[:, 0:2, 0:2] += 1e-12 * np.eye(2)
        q[:, 2, 2], q[:, 3, 3] = noise.psi_rad**2, (plant.dt_s * noise.rate_rad_s2) ** 2
        q[:, 4, 4] = noise.bias_nm_per_step**2
        reference = _scipy_gains(a, q, r)
        error = np.abs(gains - reference).max(axis=(1, 2)) / np.abs(reference).max(axis=(1, 2))
        assert error.max() < 1e-10, vessel
        p = solve_filter_riccati(a, H, q, r)
        at = np.swapaxes(a, 1, 2)
        rhs = a @ p @ at - a @ p @ H.T @ np.linalg.solve(H @ p @ H.T + r, H @ p @ at) + q
        residual = np.abs(rhs - p).max(axis=(1, 2)) / np.abs(p).max(axis=(1, 2))
        assert residual.max() < 1e-13, vessel


def test_initial_state_takes_the_generator_and_the_filter_switch() -> None:
    """rng= draws the gust and wave starts (equal to the plant's own generator with that seed);
    wave_filter=False zeroes these boats' filter inputs, the plant's setting unchanged."""
    plant = Plant("default")
    cond = SeaConditions.uniform(4, wind_speed_mps=10.0, sea=sea_state_from_code(4, 0.5))
    own = WeatherPlant(plant, seed=3).initial_state(np.zeros((4, 3)), cond)
    lent = WeatherPlant(plant, seed=99)
    given = lent.initial_state(np.zeros((4, 3)), cond, rng=np.random.default_rng(3))
    np.testing.assert_array_equal(given.m, own.m)
    off = lent.initial_state(np.zeros((4, 3)), cond, wave_filter=False)
    col = WEATHER_INPUTS.index("wave_filter") - 4  # inputs hold the rows after the calm four
    assert np.all(off.inputs[:, col:] == 0.0)  # the switch and the ten gains
    assert np.all(own.inputs[:, col] == 1.0) and np.all(own.inputs[:, col + 1 :] != 0.0)
    assert lent.wave_filter is not None
