"""DNV trafficgen situation files <-> usvsim encounter episodes.

trafficgen (DNV's ship traffic generator, pip ``trafficgen``, ICMASS 2023; MIT) writes each
generated traffic situation as a JSON file (maritime-schema 0.2.0): ``ownShip`` and
``targetShips``, each with ``initial.heading`` (deg), ``waypoints[i].position`` {lat, lon} (deg,
WGS-84), ``waypoints[i].leg.sog`` (knots) and ``static.dimensions.length`` (m). This module reads
such a file without needing the package (the format is checked here, field by field) and writes
usvsim episodes back in it.

Frames and units: positions go to a local north-east frame at the own ship's first waypoint by
the flat-Earth approximation (Fossen 2021, "Handbook of Marine Craft Hydrodynamics and Motion
Control", §2.4, his ``llh2flat``): north = (lat − lat0) R_M, east = (lon − lon0) R_N cos lat0,
with the WGS-84 meridian and prime-vertical radii at lat0; knots × 1852 / 3600 = m/s.

Scaling to the boat (:class:`TrafficgenScale`): lengths by the ratio of usvsim's boat length to
the file's own-ship length (``static.dimensions.length``; trafficgen's baseline own ship is 122 m,
so λ = 10.5 / 122 = 0.086), speeds by the ratio of the boat's cruise speed to the own ship's
speed (e.g. 3 m/s / 10 kn = 0.583). :func:`write_situation` with the same scale gives the file's
states back (tested). Suite episodes are drawn from a situation exactly as the Imazu problems
(:func:`usvsim.evaluation.imazu.perturbed_episode`).

Bad input: :func:`read_situation` raises :class:`usvsim.common.errors.UserError` with one line
naming the file and the field, and what is allowed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usvsim.common.errors import UserError
from usvsim.evaluation.imazu import ImazuConfig, ImazuTarget, perturbed_episode
from usvsim.task.openwater import OpenWaterEpisode
from usvsim.vessel.vessels import DEFAULT_VESSEL

__all__ = [
    "KNOT_MPS",
    "Situation",
    "TrafficgenScale",
    "read_situation",
    "situation_episodes",
    "write_situation",
]

KNOT_MPS = 1852.0 / 3600.0  # m/s per knot
WGS84_A_M = 6378137.0  # m, semi-major axis (WGS-84)
WGS84_E2 = 6.69437999014e-3  # -, first eccentricity squared (WGS-84)
MAX_TARGETS = 8  # the scene observation's k nearest (usvsim.task.observations.SCENE_K)
MAX_SOG_KN = 60.0  # kn, above this a speed is taken as a unit slip
SCHEMA_VERSION = "0.2.0"


@dataclass(frozen=True)
class TrafficgenScale:
    """Boat metres per ship metre and boat m/s per ship m/s (module docstring)."""

    length: float
    speed: float


@dataclass(frozen=True)
class ShipState:
    """A ship at the start: north, east (m, from the own ship's start), course (rad), speed
    (m/s), heading (rad), length (m), and its last waypoint (m) for the own ship's goal."""

    north_m: float
    east_m: float
    course_rad: float
    speed_mps: float
    heading_rad: float
    length_m: float
    end_north_m: float
    end_east_m: float


@dataclass(frozen=True)
class Situation:
    """A trafficgen situation at ship scale in the local frame; ``origin`` (lat, lon) deg."""

    title: str
    own: ShipState
    targets: tuple[ShipState, ...]
    origin_deg: tuple[float, float]

    def scale(
        self,
        boat_length_m: float = DEFAULT_VESSEL.length_m,
        boat_speed_mps: float = DEFAULT_VESSEL.cruise_speed_mps,
    ) -> TrafficgenScale:
        """The scale that maps this situation onto the boat (module docstring)."""
        return TrafficgenScale(
            boat_length_m / self.own.length_m, boat_speed_mps / self.own.speed_mps
        )


def _radii(lat0_rad: float) -> tuple[float, float]:
    """WGS-84 meridian and prime-vertical radii (m) at latitude ``lat0_rad``."""
    s2 = math.sin(lat0_rad) ** 2
    r_n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * s2)
    r_m = r_n * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * s2)
    return r_m, r_n


def _num(obj: Any, key: str, where: str, lo: float, hi: float, path: str) -> float:
    if not isinstance(obj, dict) or key not in obj:
        raise UserError(
            f"trafficgen file {path}: {where}.{key} is missing (a number in [{lo}, {hi}])"
        )
    value = obj[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"trafficgen file {path}: {where}.{key} must be a number, got {value!r}")
    if not lo <= value <= hi:
        raise UserError(
            f"trafficgen file {path}: {where}.{key} = {value} is out of range [{lo}, {hi}]"
        )
    return float(value)


def _ship(ship: Any, where: str, path: str, origin: tuple[float, float] | None) -> tuple[Any, ...]:
    """(lat, lon) of every waypoint (deg), sog (kn), heading (deg), length (m) of a ship."""
    if not isinstance(ship, dict):
        raise UserError(f"trafficgen file {path}: {where} must be an object")
    wps = ship.get("waypoints")
    if not isinstance(wps, list) or len(wps) < 2:
        raise UserError(f"trafficgen file {path}: {where}.waypoints must list at least 2 waypoints")
    lat_lon = []
    for i, wp in enumerate(wps):
        pos = wp.get("position") if isinstance(wp, dict) else None
        w = f"{where}.waypoints[{i}].position"
        lat_lon.append(
            (_num(pos, "lat", w, -90.0, 90.0, path), _num(pos, "lon", w, -180.0, 180.0, path))
        )
    leg = wps[0].get("leg")
    sog = _num(leg, "sog", f"{where}.waypoints[0].leg", 1e-3, MAX_SOG_KN, path)
    heading = _num(ship.get("initial"), "heading", f"{where}.initial", 0.0, 360.0, path)
    dims = (ship.get("static") or {}).get("dimensions")
    length = _num(dims, "length", f"{where}.static.dimensions", 1.0, 500.0, path)
    return lat_lon, sog, heading, length


def read_situation(path: str | Path) -> Situation:
    """A trafficgen situation file (module docstring); ``UserError`` for a bad file."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(f"trafficgen file {p}: cannot be read ({err.__class__.__name__})") from None
    except json.JSONDecodeError as err:
        raise UserError(f"trafficgen file {p}: not JSON (line {err.lineno}: {err.msg})") from None
    if not isinstance(data, dict):
        raise UserError(f"trafficgen file {p}: the top level must be an object")
    own = _ship(data.get("ownShip"), "ownShip", str(p), None)
    targets = data.get("targetShips", [])
    if not isinstance(targets, list) or len(targets) > MAX_TARGETS:
        raise UserError(f"trafficgen file {p}: targetShips must list 0-{MAX_TARGETS} ships")
    tgts = [_ship(t, f"targetShips[{i}]", str(p), None) for i, t in enumerate(targets)]
    lat0, lon0 = own[0][0]
    r_m, r_n = _radii(math.radians(lat0))

    def local(lat: float, lon: float) -> tuple[float, float]:
        return (
            math.radians(lat - lat0) * r_m,
            math.radians(lon - lon0) * r_n * math.cos(math.radians(lat0)),
        )

    def state(ship: tuple[Any, ...]) -> ShipState:
        pts = [local(*ll) for ll in ship[0]]
        (n0, e0), (n1, e1) = pts[0], pts[1]
        return ShipState(
            n0,
            e0,
            math.atan2(e1 - e0, n1 - n0),
            ship[1] * KNOT_MPS,
            math.radians(ship[2]),
            ship[3],
            *pts[-1],
        )

    title = str(data["title"]) if isinstance(data.get("title"), str) else p.stem
    return Situation(title, state(own), tuple(state(t) for t in tgts), (lat0, lon0))


def _targets_own_frame(sit: Situation) -> tuple[ImazuTarget, ...]:
    """The targets relative to the own ship's start, own course turned to north (ship scale)."""
    c, s = math.cos(sit.own.course_rad), math.sin(sit.own.course_rad)
    out = []
    for t in sit.targets:
        dn, de = t.north_m - sit.own.north_m, t.east_m - sit.own.east_m
        out.append(
            ImazuTarget(
                c * dn + s * de,
                -s * dn + c * de,
                t.speed_mps,
                math.degrees(t.course_rad - sit.own.course_rad),
            )
        )
    return tuple(out)


def situation_episodes(
    sit: Situation, rng: np.random.Generator, config: ImazuConfig | None = None
) -> OpenWaterEpisode:
    """One perturbed boat-scale episode of ``sit`` (the Imazu scheme, module docstring)."""
    cfg = config or ImazuConfig()
    scale = sit.scale(boat_speed_mps=cfg.own_speed_mps)
    goal = math.hypot(sit.own.end_north_m - sit.own.north_m, sit.own.end_east_m - sit.own.east_m)
    return perturbed_episode(
        rng, _targets_own_frame(sit), cfg, scale.length, scale.speed, goal * scale.length
    )


def write_situation(
    episode: OpenWaterEpisode,
    path: str | Path,
    scale: TrafficgenScale,
    origin_deg: tuple[float, float] = (58.763449, 10.490654),
    title: str = "usvsim encounter",
    own_length_m: float = DEFAULT_VESSEL.length_m,
) -> Path:
    """Write ``episode`` (boat scale) as a trafficgen situation at ship scale (lengths and
    speeds divided by ``scale``; the own ship's first waypoint at ``origin_deg``, default that of
    trafficgen's baseline files). The own ship runs start → goal; each target from its start
    along its course for the episode's time limit. Written to a temporary name, then renamed."""
    from usvsim.common.fileio import atomic_write_text

    lat0, lon0 = origin_deg
    r_m, r_n = _radii(math.radians(lat0))

    def geo(north: float, east: float) -> dict[str, float]:
        lat = lat0 + math.degrees(north / scale.length / r_m)
        lon = lon0 + math.degrees(east / scale.length / (r_n * math.cos(math.radians(lat0))))
        return {"lat": lat, "lon": lon}

    start = episode.start_ne
    own_speed = (
        episode.disturbance.speed_mps
        if episode.disturbance and episode.disturbance.speed_mps
        else DEFAULT_VESSEL.cruise_speed_mps
    )
    heading = episode.start.start_bearing_rad + math.pi + episode.start.heading_offset_rad
    sog = own_speed / scale.speed / KNOT_MPS

    def ship(
        p0: Sequence[float] | np.ndarray,
        p1: Sequence[float] | np.ndarray,
        sog_kn: float,
        hdg: float,
        length: float,
        ident: int,
        name: str,
    ) -> dict[str, Any]:
        leg = {"sog": sog_kn}
        return {
            "initial": {
                "heading": math.degrees(hdg) % 360.0,
                "navStatus": "Under way using engine",
            },
            "waypoints": [
                {"position": geo(p0[0] - start[0], p0[1] - start[1]), "leg": leg},
                {"position": geo(p1[0] - start[0], p1[1] - start[1]), "leg": leg},
            ],
            "static": {"id": ident, "name": name, "dimensions": {"length": length / scale.length}},
        }

    targets = []
    for j, v in enumerate(episode.vessels):
        run = v.speed_mps * episode.time_limit_s
        end = (v.x0_n + run * math.cos(v.course_rad), v.y0_e + run * math.sin(v.course_rad))
        targets.append(
            ship(
                (v.x0_n, v.y0_e),
                end,
                v.speed_mps / scale.speed / KNOT_MPS,
                v.course_rad,
                2.0 * v.radius_m,
                j + 2,
                f"target_ship_{j + 1}",
            )
        )
    data = {
        "trafficgenVersion": "usvsim",
        "schemaVersion": SCHEMA_VERSION,
        "title": title,
        "description": "usvsim encounter episode (usvsim.evaluation.trafficgen_io)",
        "ownShip": ship(start, episode.goal_ne, sog, heading, own_length_m, 1, "usvsim own ship"),
        "targetShips": targets,
    }
    out = Path(path)
    atomic_write_text(out, json.dumps(data, indent=4))
    return out
