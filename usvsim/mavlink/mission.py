"""Mission files for the MAVLink bridge: pole(s) and goal as latitude/longitude, validated.

A mission is JSON (always) or YAML (when PyYAML is importable), one object::

    {
      "origin": {"lat": 63.4305, "lon": 10.3951},      # optional; default: the first pole
      "poles": [{"lat": 63.4305, "lon": 10.3951}],      # one or more
      "goal": {"lat": 63.4312, "lon": 10.3975},
      "pole_radius_m": 1.0,                             # optional, default 1.0 m
      "goal_radius_m": 10.0,                            # optional, default 10.0 m
      "cruise_speed_mps": 3.0                           # optional, default 3.0 m/s
    }

Every error names the file and the exact key path (``mission.json: poles[1].lat: ...``); unknown
keys raise. A goal inside a pole's safety circle (:data:`SAFETY_DISTANCE_M`, 10 m: the task's
success needs the pole never closer) is refused. Positions are converted once to the local NED
frame around the origin (:mod:`usvsim.nav.geo`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.errors import UserError
from usvsim.nav.geo import GeoOrigin, geodetic_from_ned, ned_from_geodetic
from usvsim.task.scenario import Scenario

__all__ = ["LatLon", "Mission", "MissionError", "load_mission", "parse_mission"]

SAFETY_DISTANCE_M = Scenario().safety_distance_m  # m, success needs the pole never closer
_TOP_KEYS = ("origin", "poles", "goal", "pole_radius_m", "goal_radius_m", "cruise_speed_mps")


class MissionError(UserError):
    """A mission file that cannot be used; the message names the file and the key path."""


@dataclass(frozen=True)
class LatLon:
    """A WGS-84 position in degrees."""

    lat_deg: float
    lon_deg: float


@dataclass(frozen=True)
class Mission:
    """A validated mission: origin, poles and goal (lat/lon) plus radii and speed."""

    origin: GeoOrigin
    poles: tuple[LatLon, ...]
    goal: LatLon
    pole_radius_m: float = 1.0  # m
    goal_radius_m: float = 10.0  # m
    cruise_speed_mps: float = 3.0  # m/s

    @property
    def poles_ne(self) -> NDArray[np.float64]:
        """Pole positions (K, 2) [x_N, y_E] in m around the origin."""
        lat = [p.lat_deg for p in self.poles]
        lon = [p.lon_deg for p in self.poles]
        return ned_from_geodetic(lat, lon, self.origin)

    @property
    def goal_ne(self) -> NDArray[np.float64]:
        """Goal position (2,) [x_N, y_E] in m around the origin."""
        return ned_from_geodetic(self.goal.lat_deg, self.goal.lon_deg, self.origin)

    @classmethod
    def from_ned(
        cls,
        origin: GeoOrigin,
        poles_ne: NDArray[np.float64],
        goal_ne: NDArray[np.float64],
        **kwargs: float,
    ) -> Mission:
        """A mission from NED coordinates (m) around ``origin`` (e.g. a simulator episode)."""
        poles = geodetic_from_ned(np.asarray(poles_ne)[:, 0], np.asarray(poles_ne)[:, 1], origin)
        goal = geodetic_from_ned(goal_ne[0], goal_ne[1], origin)
        return cls(
            origin,
            tuple(LatLon(float(a), float(b)) for a, b in poles),
            LatLon(float(goal[0]), float(goal[1])),
            **kwargs,
        )

    def to_dict(self) -> dict[str, Any]:
        """The mission as a JSON-ready dict (inverse of :func:`parse_mission`)."""
        return {
            "origin": {"lat": self.origin.lat_deg, "lon": self.origin.lon_deg},
            "poles": [{"lat": p.lat_deg, "lon": p.lon_deg} for p in self.poles],
            "goal": {"lat": self.goal.lat_deg, "lon": self.goal.lon_deg},
            "pole_radius_m": self.pole_radius_m,
            "goal_radius_m": self.goal_radius_m,
            "cruise_speed_mps": self.cruise_speed_mps,
        }


def _number(where: str, value: Any, lo: float, hi: float, strict_lo: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MissionError(f"{where}: must be a number, got {value!r}")
    v = float(value)
    low_ok = v > lo if strict_lo else v >= lo
    if not (math.isfinite(v) and low_ok and v <= hi):
        bracket = "(" if strict_lo else "["
        raise MissionError(f"{where}: must lie in {bracket}{lo}, {hi}], got {value!r}")
    return v


def _latlon(where: str, value: Any) -> LatLon:
    if not isinstance(value, dict):
        raise MissionError(f"{where}: must be an object with 'lat' and 'lon', got {value!r}")
    unknown = sorted(set(value) - {"lat", "lon"})
    if unknown:
        raise MissionError(f"{where}: unknown key(s) {unknown}; expected 'lat' and 'lon'")
    for key in ("lat", "lon"):
        if key not in value:
            raise MissionError(f"{where}: missing '{key}'")
    return LatLon(
        _number(f"{where}.lat", value["lat"], -89.0, 89.0),
        _number(f"{where}.lon", value["lon"], -180.0, 180.0),
    )


def parse_mission(data: Any, source: str = "mission") -> Mission:
    """Validate a decoded mission object; errors read ``{source}: {key path}: {problem}``."""
    if not isinstance(data, dict):
        raise MissionError(f"{source}: the mission must be an object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(_TOP_KEYS))
    if unknown:
        raise MissionError(f"{source}: unknown key(s) {unknown}; known: {list(_TOP_KEYS)}")
    for key in ("poles", "goal"):
        if key not in data:
            raise MissionError(f"{source}: missing '{key}'")
    poles_raw = data["poles"]
    if not isinstance(poles_raw, list) or not poles_raw:
        raise MissionError(f"{source}: poles: must be a non-empty list, got {poles_raw!r}")
    poles = tuple(_latlon(f"{source}: poles[{i}]", p) for i, p in enumerate(poles_raw))
    goal = _latlon(f"{source}: goal", data["goal"])
    first = poles[0]
    origin_ll = _latlon(f"{source}: origin", data["origin"]) if "origin" in data else first
    mission = Mission(
        origin=GeoOrigin(origin_ll.lat_deg, origin_ll.lon_deg),
        poles=poles,
        goal=goal,
        pole_radius_m=_number(
            f"{source}: pole_radius_m", data.get("pole_radius_m", 1.0), 0.0, 100.0, strict_lo=True
        ),
        goal_radius_m=_number(
            f"{source}: goal_radius_m", data.get("goal_radius_m", 10.0), 0.0, 1000.0, strict_lo=True
        ),
        cruise_speed_mps=_number(
            f"{source}: cruise_speed_mps",
            data.get("cruise_speed_mps", 3.0),
            0.0,
            30.0,
            strict_lo=True,
        ),
    )
    to_goal = np.hypot(*(mission.poles_ne - mission.goal_ne).T)
    k = int(np.argmin(to_goal))
    if to_goal[k] < SAFETY_DISTANCE_M:
        raise MissionError(
            f"{source}: goal: lies {to_goal[k]:.1f} m from poles[{k}], inside its "
            f"{SAFETY_DISTANCE_M:g} m safety circle (no run could reach it and succeed); "
            f"move the goal at least {SAFETY_DISTANCE_M:g} m away"
        )
    far = np.hypot(*np.vstack([mission.poles_ne, mission.goal_ne[None]]).T).max()
    if far > 20_000.0:  # flat-earth error ~ d²/(2R) would exceed ~3 cm beyond this
        raise MissionError(
            f"{source}: poles and goal must lie within 20 km of the origin "
            f"(flat-earth frame), farthest is {far:.0f} m"
        )
    return mission


def load_mission(path: str | Path) -> Mission:
    """Read and validate a JSON (``.json``) or YAML (``.yaml``/``.yml``) mission file.

    Raises
    ------
    MissionError
        On a missing file, a syntax error (with line and column), or invalid content.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as err:
        raise MissionError(f"{p}: cannot read mission file: {err.strerror}") from None
    except UnicodeDecodeError as err:  # found by the property tests
        raise MissionError(f"{p}: not UTF-8 text ({err.reason} at byte {err.start})") from None
    if p.suffix.lower() in (".yaml", ".yml"):
        try:
            import yaml
        except ImportError:
            raise MissionError(f"{p}: YAML missions need PyYAML; install it or use JSON") from None
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as err:
            raise MissionError(f"{p}: invalid YAML: {err}") from None
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise MissionError(
                f"{p}: invalid JSON at line {err.lineno} column {err.colno}: {err.msg}"
            ) from None
    return parse_mission(data, str(p))
