"""Checks that a demonstration is physically plausible, and the error a bad file raises.

:class:`DemoFormatError` (re-exported by :mod:`learning.imitation.demonstrations`) names the file,
line and column of the first problem. The limits (:class:`Plausibility`) and what they apply to
are listed in the docstring of :mod:`learning.imitation.demonstrations`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.errors import UserError

__all__ = [
    "PLAUSIBLE",
    "DemoFormatError",
    "Plausibility",
    "check_fix",
    "check_motion",
    "check_site",
    "finite_number",
]

FloatArray = NDArray[np.float64]


class DemoFormatError(UserError):
    """A demonstration file breaks the format; the message names file, line and column."""


@dataclass(frozen=True)
class Plausibility:
    """Physical limits a demonstration must respect (module docstring; usvsim's choices)."""

    max_distance_m: float = 5_000.0  # m from the site origin: a harbour session, not a voyage
    max_speed_mps: float = 15.0  # m/s between GPS fixes, five times the task's 3 m/s
    gps_allowance_m: float = 10.0  # m, GPS noise allowed on top of max_speed_mps × Δt
    max_radar_range_m: float = 10_000.0  # m
    min_radar_range_m: float = -10.0  # m: a noisy echo close to the pole may read below 0 (5σ)


PLAUSIBLE = Plausibility()


def finite_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def check_site(path: str, meta: dict[str, Any]) -> None:
    """Metadata origin, poles and pole radius physically plausible (module docstring)."""
    where = f"{path}, line 1: metadata"
    for key, limit in (("origin_lat_deg", 90.0), ("origin_lon_deg", 180.0)):
        value = meta[key]
        if not (finite_number(value) and -limit <= value <= limit):
            raise DemoFormatError(
                f"{where} {key} must be a number in [-{limit:g}, {limit:g}]°, got {value!r}"
            )
    poles = meta["poles_ne"]
    if not isinstance(poles, list) or not poles:
        raise DemoFormatError(f"{where} poles_ne must be a non-empty list of [x_N, y_E] (m)")
    limit = PLAUSIBLE.max_distance_m
    for k, pole in enumerate(poles):
        ok = isinstance(pole, list) and len(pole) == 2 and all(finite_number(v) for v in pole)
        if not ok or math.hypot(*pole) > limit:
            raise DemoFormatError(
                f"{where} poles_ne[{k}] must be [x_N, y_E] in m within {limit:g} m of the "
                f"origin, got {pole!r}"
            )
    radius = meta["pole_radius_m"]
    if not (finite_number(radius) and 0.0 < radius <= 100.0):
        raise DemoFormatError(f"{where} pole_radius_m must be in (0, 100] m, got {radius!r}")


def check_fix(path: str, line: int, lat: float, lon: float) -> None:
    if not -90.0 <= lat <= 90.0:
        raise DemoFormatError(f"{path}, line {line}, column lat_deg: {lat} is not in [-90, 90]°")
    if not -180.0 <= lon <= 180.0:
        raise DemoFormatError(f"{path}, line {line}, column lon_deg: {lon} is not in [-180, 180]°")


def check_motion(path: str, lines: list[int], t_s: FloatArray, ne: FloatArray) -> None:
    """GPS fixes near the origin and no faster between fixes than the plausible speed."""
    d = np.hypot(ne[:, 0], ne[:, 1])
    far = np.flatnonzero(~(d <= PLAUSIBLE.max_distance_m))
    if far.size:
        k = int(far[0])
        raise DemoFormatError(
            f"{path}, line {lines[k]}: GPS fix {d[k]:.0f} m from the site origin "
            f"(at most {PLAUSIBLE.max_distance_m:g} m; wrong origin or a corrupt fix?)"
        )
    step = np.hypot(*np.diff(ne, axis=0).T)
    allowed = PLAUSIBLE.max_speed_mps * np.diff(t_s) + PLAUSIBLE.gps_allowance_m
    jump = np.flatnonzero(step > allowed)
    if jump.size:
        k = int(jump[0])
        raise DemoFormatError(
            f"{path}, line {lines[k + 1]}: GPS fix {step[k]:.0f} m from the previous one in "
            f"{t_s[k + 1] - t_s[k]:.2f} s (at most {PLAUSIBLE.max_speed_mps:g} m/s plus "
            f"{PLAUSIBLE.gps_allowance_m:g} m of GPS noise)"
        )
