"""Per-episode weather of the open-water family (issue 38): a :class:`Weather` drawn from a
:class:`WeatherRanges` and the episode's own seed, and the named ranges of the weather stress
sets.

Episode k of a set with seed s draws its geometry from ``default_rng([s, k])``
(:func:`usvsim.task.openwater.draw_open_water`); its weather comes from a separate stream,
``default_rng([s, k, WEATHER_STREAM])``, so that giving a set weather moves none of its other
draws (its episodes keep their starts, obstacles, noise seeds), and the same (s, k) always gives
the same weather.

Directions: the wind and the waves are given as the direction they travel **towards** (rad,
NED, as the current), drawn relative to the episode's course χ (start → goal) and mirrored to
either side at random, as the family's current. The sea's T_p is Bales' (1983) most probable
period of its H_s (:data:`usvsim.vessel.weather.waves.SEA_STATES`, interpolated); waves travel
with the wind unless ``wave_spread_rad`` turns them.

:class:`usvsim.task.openwater.OpenWaterScenario` ``weather`` draws one per episode into its
:class:`usvsim.task.disturbance.EpisodeDisturbance`; the batch then steps the boat in
:class:`usvsim.vessel.weather_plant.WeatherPlant` (:func:`sea_conditions` gives its
:class:`usvsim.vessel.weather_plant.SeaConditions`). The stress suite's weather sets
(:mod:`usvsim.evaluation.stress`) use :data:`WEATHER_SETS`.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.vessel.weather.waves import HS_MAX_M, SEA_STATES
from usvsim.vessel.weather.wind import WIND_SPEED_MAX_MPS
from usvsim.vessel.weather_plant import SeaConditions

__all__ = [
    "CALM",
    "WEATHER_SETS",
    "WEATHER_STREAM",
    "Weather",
    "WeatherRanges",
    "draw_weather",
    "sea_conditions",
]

#: The weather's seed stream, appended to an episode's [seed, k] (module docstring).
WEATHER_STREAM = zlib.crc32(b"weather")
Range = tuple[float, float]


@dataclass(frozen=True)
class Weather:
    """One episode's weather (module docstring for the directions)."""

    wind_speed_mps: float = 0.0  # m/s, mean V̄
    wind_dir_rad: float = 0.0  # rad, towards, NED
    gust_intensity: float = 0.0  # -, σ_g / V̄
    hs_m: float = 0.0  # m, significant wave height; 0: calm sea
    tp_s: float = 10.0  # s, peak period (unused in a calm sea)
    wave_dir_rad: float = 0.0  # rad, towards, NED

    @property
    def calm(self) -> bool:
        return self.wind_speed_mps == 0.0 and self.hs_m == 0.0


CALM = Weather()


@dataclass(frozen=True)
class WeatherRanges:
    """The distribution of an episode's weather: uniform in each range."""

    wind_speed_range_mps: Range = (0.0, 0.0)  # m/s
    # rad, wind direction (towards) relative to the course χ, mirrored to either side at random
    wind_direction_range_rad: Range = (-math.pi, math.pi)
    gust_intensity_range: Range = (0.1, 0.1)  # -, σ_g / V̄ (Fossen 2021 §10.1; ASSUMED 0.1)
    hs_range_m: Range = (0.0, 0.0)  # m
    wave_spread_rad: float = 0.0  # rad, waves turned from the wind by up to this, either side

    def __post_init__(self) -> None:
        checks = (
            ("wind_speed_range_mps", self.wind_speed_range_mps, 0.0, WIND_SPEED_MAX_MPS),
            ("gust_intensity_range", self.gust_intensity_range, 0.0, 0.5),
            ("hs_range_m", self.hs_range_m, 0.0, HS_MAX_M),
        )
        for name, (lo, hi), low, high in checks:
            if not (math.isfinite(lo) and math.isfinite(hi) and low <= lo <= hi <= high):
                raise UserError(
                    f"WeatherRanges.{name} must be (low, high) with {low:g} <= low <= high <= "
                    f"{high:g}, got ({lo}, {hi})"
                )
        if not 0.0 <= self.wave_spread_rad <= math.pi:
            raise UserError(f"wave spread must lie in [0, π] rad, got {self.wave_spread_rad}")


# Bales' table (sea states 2-8): H_s (m) and most probable T_p (s), in increasing H_s
_BALES_HS, _BALES_TP = (
    np.array(column, dtype=float)
    for column in zip(*(SEA_STATES[c][:2] for c in sorted(SEA_STATES) if c >= 2), strict=True)
)


def _bales_period(hs_m: float) -> float:
    """Most probable T_p (s) of H_s: Bales' table (sea states 2-8) interpolated, clipped."""
    return float(np.interp(hs_m, _BALES_HS, _BALES_TP))


def draw_weather(ranges: WeatherRanges, seed: int, k: int, course_rad: float) -> Weather:
    """Episode k's weather of a set with seed ``seed`` (module docstring), its course χ (rad)."""
    rng = np.random.default_rng([seed, k, WEATHER_STREAM])
    u = rng.random(6)  # always six draws, in this order, whatever the ranges
    lo, hi = ranges.wind_speed_range_mps
    speed = lo + (hi - lo) * u[0]
    dlo, dhi = ranges.wind_direction_range_rad
    side = 1.0 if u[1] < 0.5 else -1.0
    wind_dir = course_rad + side * (dlo + (dhi - dlo) * u[2])
    glo, ghi = ranges.gust_intensity_range
    gust = glo + (ghi - glo) * u[3]
    hlo, hhi = ranges.hs_range_m
    hs = hlo + (hhi - hlo) * u[4]
    wave_dir = wind_dir + ranges.wave_spread_rad * (2.0 * u[5] - 1.0)
    wind_dir, wave_dir = ssa(np.array([wind_dir, wave_dir])).tolist()
    return Weather(
        wind_speed_mps=float(speed),
        wind_dir_rad=wind_dir,
        gust_intensity=float(gust) if speed > 0 else 0.0,
        hs_m=float(hs),
        tp_s=_bales_period(hs) if hs > 0 else 10.0,
        wave_dir_rad=wave_dir,
    )


def sea_conditions(weathers: Sequence[Weather]) -> SeaConditions:
    """The :class:`SeaConditions` of N episodes' weather (arrays of shape (N,))."""

    def col(name: str) -> np.ndarray:
        return np.array([getattr(w, name) for w in weathers], dtype=float)

    return SeaConditions(
        col("wind_speed_mps"),
        col("wind_dir_rad"),
        col("gust_intensity"),
        col("hs_m"),
        col("tp_s"),
        col("wave_dir_rad"),
    )


DEG = math.pi / 180.0
#: The weather of the stress sets (issue 38), by name; ``moderate`` is what ``everything``
#: would gain (not applied: its published figures must stay valid).
WEATHER_SETS: dict[str, WeatherRanges] = {
    # 8-12 m/s on the beam (blowing 80-100° off the course, either side), gusts 10 %
    "wind-beam": WeatherRanges(
        wind_speed_range_mps=(8.0, 12.0), wind_direction_range_rad=(80 * DEG, 100 * DEG)
    ),
    # 6-10 m/s from any direction, gusty: σ_g 20-30 % of the mean
    "gusts": WeatherRanges(wind_speed_range_mps=(6.0, 10.0), gust_intensity_range=(0.2, 0.3)),
    # WMO sea state code 3 (H_s 0.5-1.25 m) with its wind (Beaufort 4: 5.5-7.9 m/s, WMO No. 8)
    "sea-state-3": WeatherRanges(
        wind_speed_range_mps=(5.5, 7.9), hs_range_m=(0.5, 1.25), wave_spread_rad=30 * DEG
    ),
    # WMO sea state code 4 (H_s 1.25-2.5 m) with Beaufort 5 (8.0-10.7 m/s)
    "sea-state-4": WeatherRanges(
        wind_speed_range_mps=(8.0, 10.7), hs_range_m=(1.25, 2.5), wave_spread_rad=30 * DEG
    ),
    # for `everything`: up to a moderate breeze and sea state 3
    "moderate": WeatherRanges(
        wind_speed_range_mps=(0.0, 8.0), hs_range_m=(0.0, 1.0), wave_spread_rad=30 * DEG
    ),
}
