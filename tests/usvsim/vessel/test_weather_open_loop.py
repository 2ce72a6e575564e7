"""The open-loop vessel step in wind and waves (usvsim.vessel.weather_open_loop, issue 38): in
calm weather it is the calm model's RK4 step; a boat at rest in beam wind settles at the drift
speed of the wind/damping balance; its gust follows the weather plant's statistics."""

from __future__ import annotations

import math

import numpy as np

from usvsim.vessel.model import build_dynamics, build_rk4_step
from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.wind import GustParams
from usvsim.vessel.weather_open_loop import OpenLoopWeather
from usvsim.vessel.weather_plant import NWS, SeaConditions, weather_inputs


def _inputs(cond: SeaConditions, dt_s: float) -> np.ndarray:
    n = cond.hs_m.size
    inputs, _ = weather_inputs(cond, np.zeros(n), np.zeros(n), dt_s, GustParams(), None, (1, 0))
    return inputs


def test_calm_weather_is_the_calm_rk4_step() -> None:
    """No wind, calm sea: the calm model's step to 1e-12 (every load is an exact zero; the
    compiled forms differ), weather states stay zero but for the filter's restart."""
    vessel = Plant("default").vessel
    rng = np.random.default_rng(0)
    pose, surge = rng.normal(0, 10, (5, 2)), rng.uniform(0, 3, (5, 1))
    actuators = np.c_[rng.uniform(0, 2e4, 5), rng.uniform(-0.3, 0.3, 5)]
    x = np.c_[pose, rng.uniform(-3, 3, 5), surge, rng.normal(0, 0.2, (5, 2)), actuators]
    a = np.c_[rng.uniform(0, 2e4, 5), rng.uniform(-0.3, 0.3, 5)]
    step = OpenLoopWeather(vessel, 0.1)
    calm_inputs = _inputs(SeaConditions.uniform(5), 0.1)
    x1, m1 = step.step(x, a, (0.5, 1.0), np.zeros((5, NWS)), calm_inputs, rng)
    calm = build_rk4_step(build_dynamics(vessel), 0.1).map(5)
    reference = np.asarray(calm(x.T, a.T, np.tile([[0.5], [1.0]], 5))).T
    np.testing.assert_allclose(x1, reference, rtol=0, atol=1e-12)
    assert np.all(m1[:, 0:3] == 0.0)


def test_boat_at_rest_drifts_at_the_beam_wind_balance() -> None:
    """10 m/s on the beam, no gusts, 400 s at 0.1 s: the hand balance of the weather tests,
    ½ρ_a c_y A_L (V − v)² = 2258.4 v², gives 0.5728 m/s; bound 3 %."""
    vessel = Plant("default").vessel
    cond = SeaConditions.uniform(1, 10.0, math.pi / 2, gust_intensity=0.0)
    inputs, step = _inputs(cond, 0.1), OpenLoopWeather(vessel, 0.1)
    x, m = np.zeros((1, 8)), np.zeros((1, NWS))
    rng = np.random.default_rng(1)
    for _ in range(4000):
        x, m = step.step(x, np.zeros((1, 2)), (0.0, 0.0), m, inputs, rng)
    speed = math.hypot(x[0, 3], x[0, 4])
    assert abs(speed - 0.5728) < 0.03 * 0.5728


def test_gust_has_the_weather_plants_spread() -> None:
    """σ_g = 10 % of 10 m/s, 256 boats × 60 s from the stationary start: std within 5 % of 1.0
    m/s (the weather plant's kernel test bound)."""
    vessel = Plant("default").vessel
    n = 256
    cond = SeaConditions.uniform(n, 10.0, 0.0)
    inputs, step = _inputs(cond, 0.1), OpenLoopWeather(vessel, 0.1)
    rng = np.random.default_rng(2)
    x, m = np.zeros((n, 8)), np.zeros((n, NWS))
    m[:, 0] = rng.standard_normal(n)  # stationary start, σ = 1 m/s
    gusts = []
    for _ in range(600):
        x, m = step.step(x, np.zeros((n, 2)), (0.0, 0.0), m, inputs, rng)
        gusts.append(m[:, 0].copy())
    assert abs(np.std(gusts) - 1.0) < 0.05
