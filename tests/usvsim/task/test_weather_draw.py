"""Per-episode weather draws (usvsim.task.weather_draw, issue 38): seeded, within the ranges,
beam wind on the beam, calm by default, bad ranges one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.common.errors import UserError
from usvsim.task.weather_draw import (
    CALM,
    WEATHER_SETS,
    WeatherRanges,
    draw_weather,
    sea_conditions,
)
from usvsim.vessel.weather.waves import SEA_STATES


def _draws(name: str, n: int = 200, seed: int = 7, course: float = 0.4) -> list:
    return [draw_weather(WEATHER_SETS[name], seed, k, course) for k in range(n)]


def test_same_episode_same_weather_other_episode_other_weather() -> None:
    a = draw_weather(WEATHER_SETS["gusts"], 11, 3, 0.0)
    assert a == draw_weather(WEATHER_SETS["gusts"], 11, 3, 0.0)
    assert a != draw_weather(WEATHER_SETS["gusts"], 11, 4, 0.0)
    assert a != draw_weather(WEATHER_SETS["gusts"], 12, 3, 0.0)


def test_wind_beam_blows_8_to_12_m_s_across_the_course_from_either_side() -> None:
    draws = _draws("wind-beam")
    speeds = np.array([w.wind_speed_mps for w in draws])
    rel = np.array([(w.wind_dir_rad - 0.4 + math.pi) % (2 * math.pi) - math.pi for w in draws])
    assert speeds.min() >= 8.0 and speeds.max() <= 12.0
    assert np.all((np.abs(rel) >= math.radians(80) - 1e-12) & (np.abs(rel) <= math.radians(100)))
    assert 0.3 < np.mean(rel > 0) < 0.7  # both sides
    assert all(w.hs_m == 0.0 for w in draws)


def test_sea_states_have_their_wmo_heights_and_bales_periods() -> None:
    for name, (lo, hi), code in (("sea-state-3", (0.5, 1.25), 3), ("sea-state-4", (1.25, 2.5), 4)):
        draws = _draws(name)
        hs = np.array([w.hs_m for w in draws])
        assert hs.min() >= lo and hs.max() <= hi
        # T_p interpolated in Bales' table: at the code's mean H_s, its T_p
        near = [w for w in draws if abs(w.hs_m - SEA_STATES[code][0]) < 0.02]
        assert near and all(abs(w.tp_s - SEA_STATES[code][1]) < 0.2 for w in near)
        spread = [abs((w.wave_dir_rad - w.wind_dir_rad + math.pi) % (2 * math.pi) - math.pi)
                  for w in draws]  # fmt: skip
        assert max(spread) <= math.radians(30) + 1e-12


def test_default_ranges_are_calm_and_make_calm_sea_conditions() -> None:
    draws = [draw_weather(WeatherRanges(), 1, k, 0.0) for k in range(5)]
    assert all(w.calm for w in draws) and CALM.calm
    cond = sea_conditions(draws)
    assert np.all(cond.wind_speed_mps == 0) and np.all(cond.hs_m == 0)
    cond.check(5)


def test_bad_ranges_raise_one_line() -> None:
    with pytest.raises(UserError, match="wind_speed_range_mps"):
        WeatherRanges(wind_speed_range_mps=(5.0, 50.0))
    with pytest.raises(UserError, match="hs_range_m"):
        WeatherRanges(hs_range_m=(2.0, 1.0))
