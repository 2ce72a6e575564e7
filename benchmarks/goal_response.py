"""How a helmsman turns towards a goal in clear water: its action for a grid of the goal's range
and bearing, nothing else around (``docs/notes/2026-12-traffic.md``, "A starboard dead zone near
the goal").

For each range r (m) and bearing β off the heading (deg, + starboard) the boat sits at the
origin heading north at the cruise speed (3 m/s, the study's) with the goal at (r, β) and no
obstacle or vessel; the observation is the one the open-water env would give
(:func:`usvsim.task.openwater_batch.observe_scene`, a clean radar image for the radar kinds),
and the table holds the helmsman's heading change (deg; a Gaussian policy's mean, clipped, as
``usvsim bench`` runs it). A helmsman that aims at the goal turns by about β up to its ±30°
limit; a *dead zone* is a bearing on one side that gets no turn while the mirrored one does.
``asymmetry_deg`` is, per range, the largest |a(β) + a(−β)| over the grid's bearings.
``--islet R,B,RADIUS`` puts one static islet in the water too (its centre R m away at B deg
off the bow, RADIUS m): how the turn towards the goal changes beside an islet's radar returns.
Printed as JSON::

    python benchmarks/goal_response.py --helmsman radar-gaussian-gail-trpo-traffic
    python benchmarks/goal_response.py --helmsman radar-gaussian-gail-trpo-traffic --islet 60,-40,15
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from usvsim.common.errors import UserError
from usvsim.helm.registry import helmsman_kinds, make_helmsman
from usvsim.task.batch import heading_change_rad
from usvsim.task.openwater_batch import SceneDiscs, observe_scene
from usvsim.task.scenario import Scenario
from usvsim.task.scene_radar import RadarDegradation

RANGES_M = (15.0, 25.0, 40.0, 60.0, 100.0, 200.0)
BEARINGS_DEG = (-90.0, -60.0, -45.0, -30.0, -20.0, -10.0, -5.0, 0.0, 5.0, 10.0, 20.0, 30.0,
                45.0, 60.0, 90.0)  # fmt: skip
CRUISE_MPS = 3.0  # m/s, the study's cruise speed


def _polar_ne(range_m: float, bearing_rad: Any) -> np.ndarray:
    """Points ``range_m`` from the origin at ``bearing_rad`` off north (the bow), (…, 2)."""
    b = np.asarray(bearing_rad, dtype=float)
    return range_m * np.stack([np.cos(b), np.sin(b)], axis=-1)


def clear_water_observations(
    kind: Any,
    range_m: float,
    bearings_rad: np.ndarray,
    islet: tuple[float, float, float] | None = None,
) -> Any:
    """The ``kind`` observations (one per bearing) of a boat at the origin heading north at
    :data:`CRUISE_MPS` with the goal ``range_m`` away at each of ``bearings_rad`` off the bow,
    and ``islet`` (range m, bearing rad, radius m) in the water if given."""
    n = len(bearings_rad)
    goal = _polar_ne(range_m, bearings_rad)
    velocity = np.tile([CRUISE_MPS, 0.0], (n, 1))
    k = 0 if islet is None else 1
    discs = SceneDiscs(np.zeros((n, k, 2)), np.zeros((n, k)), np.zeros((n, k, 2)),
                       np.ones((n, k), dtype=bool))  # fmt: skip
    if islet is not None:
        discs.centres_ne[:, 0] = _polar_ne(islet[0], islet[1])
        discs.radii_m[:, 0] = islet[2]
    zeros = np.zeros(n)
    return observe_scene(
        kind, np.zeros((n, 2)), zeros, velocity, goal, discs,
        degradation=RadarDegradation(zeros, zeros, zeros, zeros),
        keys=np.zeros(n, dtype=np.uint64),
    )  # fmt: skip


def response_deg(helmsman: Any, kind: Any, action: Any, range_m: float,
                 bearings_deg: np.ndarray,
                 islet: tuple[float, float, float] | None = None) -> np.ndarray:  # fmt: skip
    """The helmsman's heading change (deg, + starboard) for the goal at ``range_m`` and each of
    ``bearings_deg`` in clear water (beside ``islet``: range m, bearing rad, radius m)."""
    n = len(bearings_deg)
    helmsman.reset(n)
    obs = clear_water_observations(kind, range_m, np.radians(bearings_deg), islet)
    limit = Scenario().max_heading_change_rad
    return np.degrees(heading_change_rad(action, helmsman.act(obs), n, limit))


def asymmetry_deg(bearings_deg: np.ndarray, turns_deg: np.ndarray) -> float:
    """max |a(β) + a(−β)| over the grid's bearings β > 0 whose mirror −β is on the grid."""
    worst = 0.0
    for i, b in enumerate(bearings_deg):
        mirror = np.flatnonzero(bearings_deg == -b)
        if b > 0 and mirror.size:
            worst = max(worst, abs(float(turns_deg[i] + turns_deg[mirror[0]])))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--helmsman", required=True, help="a name or a checkpoint file")
    parser.add_argument("--islet", help="RANGE_M,BEARING_DEG,RADIUS_M: one islet in the water")
    args = parser.parse_args()
    islet = None
    if args.islet is not None:
        try:
            islet_r, b, radius = (float(x) for x in args.islet.split(","))
        except ValueError:
            parser.error(f"--islet must be RANGE_M,BEARING_DEG,RADIUS_M, got {args.islet!r}")
        if not (0 < radius < islet_r and np.isfinite(b)):
            parser.error(
                f"--islet needs 0 < RADIUS_M < RANGE_M and a finite bearing, got {args.islet!r}"
            )
        islet = (islet_r, math.radians(b), radius)
    try:
        helmsman = make_helmsman(args.helmsman)
        kind, action = helmsman_kinds(helmsman)
    except UserError as err:
        parser.exit(2, f"goal_response.py: error: {err}\n")
    bearings = np.array(BEARINGS_DEG)
    rows = {}
    for r in RANGES_M:
        turns = response_deg(helmsman, kind, action, r, bearings, islet)
        rows[f"{r:g}"] = {"turn_deg": [round(float(t), 1) for t in turns],
                          "asymmetry_deg": round(asymmetry_deg(bearings, turns), 1)}  # fmt: skip
    out = {"helmsman": args.helmsman, "observation": kind, "cruise_mps": CRUISE_MPS,
           "islet": args.islet,
           "bearings_deg": list(BEARINGS_DEG), "ranges_m": rows}  # fmt: skip
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
