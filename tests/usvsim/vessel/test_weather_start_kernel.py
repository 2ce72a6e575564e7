"""The weather start's C twin (usvsim.vessel.weather.start_kernel, issue 38): its episode rows
equal the NumPy functions' (weather_inputs with compiled=False) to rounding for calm and wavy
boats, following seas at the encounter frequency's clip, the filter off, no autopilot and the
rover autopilot; a boat's rows do not depend on its batch."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.vessel.autopilot import AutopilotConfig
from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.observer import ObserverNoise
from usvsim.vessel.weather.start_kernel import wave_start
from usvsim.vessel.weather.wind import GustParams
from usvsim.vessel.weather_plant import (
    WEATHER_INPUTS,
    SeaConditions,
    WeatherPlant,
    weather_inputs,
)

pytestmark = pytest.mark.skipif(
    wave_start(*(np.zeros(0),) * 4, np.zeros(26), np.zeros((5, 5)), np.zeros(2), np.zeros((4, 1)))
    is None,
    reason="no C compiler: the NumPy path is the only one",
)


def _seas(n: int, seed: int) -> tuple[SeaConditions, np.ndarray, np.ndarray]:
    """n boats: a quarter calm, H_s 0.05-4 m (some below the PID's wave design), T_p 3-14 s,
    any direction and heading, 0-6 m/s; the last four in following seas at the waves' speed
    (ω_e clipped to 0.1 rad/s)."""
    rng = np.random.default_rng(seed)
    hs = rng.uniform(0.05, 4.0, n)
    hs[: n // 4] = 0.0
    heading = rng.uniform(-math.pi, math.pi, n)
    wave_dir = rng.uniform(-math.pi, math.pi, n)
    speed = rng.uniform(0.0, 6.0, n)
    tp = rng.uniform(3.0, 14.0, n)
    # following seas at the waves' phase speed g / ω_p: ω_e = ω_p |1 - ω_p U / g| ~ 0
    wave_dir[-4:], tp[-4:] = heading[-4:], rng.uniform(3.0, 3.5, 4)
    speed[-4:] = 9.81 * tp[-4:] / (2.0 * math.pi)
    cond = SeaConditions(
        rng.uniform(0.0, 12.0, n),
        rng.uniform(-math.pi, math.pi, n),
        rng.uniform(0.0, 0.3, n),
        hs,
        tp,
        wave_dir,
    )
    return cond, speed, heading


@pytest.mark.parametrize("autopilot", ["pid", "rover", None])
@pytest.mark.parametrize("filter_on", [True, False])
def test_compiled_rows_equal_numpy_rows(autopilot: str | None, filter_on: bool) -> None:
    plant = Plant(autopilot=AutopilotConfig(kind=autopilot) if autopilot else None)
    weather = WeatherPlant(plant)
    cond, speed, heading = _seas(64, 3)
    args = (cond, speed, heading, plant.dt_s, GustParams(), ObserverNoise() if filter_on else None,
            weather.yaw_model)  # fmt: skip
    design = plant.design if autopilot else None
    fast, fast_resp = weather_inputs(*args, yaw_gain=0.8, autopilot=design)
    slow, slow_resp = weather_inputs(*args, yaw_gain=0.8, autopilot=design, compiled=False)
    # rounding, amplified where L L^T = P∞ - Φ P∞ Φ^T cancels (over Δt = 0.1 s Φ P∞ Φ^T is
    # within ~1e-4 of P∞, so L₁₁ and the gains it feeds keep ~4 fewer digits: 2.5e-11 seen)
    np.testing.assert_allclose(fast, slow, rtol=1e-10, atol=1e-14)
    for name in ("omega0", "damping", "gain"):
        np.testing.assert_allclose(getattr(fast_resp, name), getattr(slow_resp, name), rtol=1e-13)
    assert np.all(fast_resp.omega0[-4:] == 0.1)  # following seas: the clip
    # the rows are not trivially equal: wavy boats have gains, calm ones none
    wavy = cond.hs_m > 0
    first = WEATHER_INPUTS.index("gain_psi_w_compass") - 4  # the rows start at wind_mean
    assert np.abs(fast[wavy]).sum() > 0 and np.all(fast[~wavy, first : first + 10] == 0)


def test_a_boats_rows_do_not_depend_on_its_batch() -> None:
    plant = Plant()
    weather = WeatherPlant(plant)
    cond, speed, heading = _seas(16, 5)
    args = (plant.dt_s, GustParams(), ObserverNoise(), weather.yaw_model)
    full, _ = weather_inputs(cond, speed, heading, *args, autopilot=plant.design)
    for b in (0, 7, 15):
        one = SeaConditions(*(getattr(cond, f)[b : b + 1] for f in cond.__dataclass_fields__))
        row, _ = weather_inputs(one, speed[b : b + 1], heading[b : b + 1], *args,
                                autopilot=plant.design)  # fmt: skip
        np.testing.assert_array_equal(row[0], full[b])


def test_a_peak_period_outside_the_spline_takes_the_numpy_path() -> None:
    """T_p beyond the drift spline's 1-25 s (weather_inputs called without SeaConditions.check):
    the direct integral, as the NumPy path gives."""
    plant = Plant()
    weather = WeatherPlant(plant)
    cond, speed, heading = _seas(8, 9)
    cond = SeaConditions(cond.wind_speed_mps, cond.wind_dir_rad, cond.gust_intensity,
                         np.full(8, 1.0), np.full(8, 27.0), cond.wave_dir_rad)  # fmt: skip
    args = (cond, speed, heading, plant.dt_s, GustParams(), ObserverNoise(), weather.yaw_model)
    fast, _ = weather_inputs(*args, autopilot=plant.design)
    slow, _ = weather_inputs(*args, autopilot=plant.design, compiled=False)
    np.testing.assert_array_equal(fast, slow)
