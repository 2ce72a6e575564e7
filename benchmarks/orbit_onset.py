"""What the traffic is doing when a helmsman first comes near the goal, by outcome: the onset of
the goal orbits with traffic through the goal (``docs/notes/2026-12-traffic.md``).

The helmsman runs a stress set's ``--split`` episodes; for each episode in which a target vessel
passes through the goal circle within the time limit (a centre within 15 m of the goal,
``benchmarks/stress_outcomes.py``) and whose track comes within ``--near-m`` (25 m) of the goal,
at the first such moment (the *arrival*):

- the nearest vessel centre's distance to the goal (m), and whether the goal is *blocked*: that
  centre closer than ``BLOCK_M`` = goal radius 10 m + the success rule's clearance (pole-equivalent
  10 m, i.e. a centre 14 m from the boat for a 5 m vessel), so that no point of the goal circle
  is clear of it;
- the goal's bearing off the own heading (deg, absolute; and signed, + starboard, − port: the
  traffic policies come in with the goal to port, ``benchmarks/goal_response.py``) and the
  nearest vessel's range from the own boat (m) and bearing off its heading (deg, absolute);
- how long after the arrival every vessel centre is farther than ``BLOCK_M`` from the goal (s;
  0 if the goal was clear; ``inf`` if it stays blocked to the time limit), and for the
  time-limit failures the time left after that (s): how long the boat circled a clear goal.

``--all``: every episode that comes near the goal (the vessel figures of one without vessels
are NaN, left out of the medians). Printed as JSON, one group per outcome (medians and
counts)::

    nice python benchmarks/orbit_onset.py --helmsman radar-gaussian-gail-trpo-traffic
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # stress_outcomes' geometry, shared

from stress_outcomes import THROUGH_GOAL_M, nearest_vessel_to_goal_m, vessel_positions_ne

from usvsim.common.angles import ssa_float
from usvsim.evaluation.stress import evaluate_set, select_sets, stress_episodes
from usvsim.helm.registry import make_helmsman

BLOCK_M = 10.0 + 14.0  # m: goal radius + a 5 m vessel's centre clearance under the success rule


def vessel_goal_distances_m(episode: Any, t_s: np.ndarray) -> np.ndarray:
    """The nearest vessel centre's distance to the goal (m) at each time ``t_s`` (s)."""
    pos, goal = vessel_positions_ne(episode, t_s), np.asarray(episode.goal_ne, dtype=float)
    return np.hypot(pos[..., 0] - goal[0], pos[..., 1] - goal[1]).min(axis=0)


def _signed_deg(d_ne: np.ndarray, psi_rad: float) -> float:
    """The bearing of the vector ``d_ne`` off the heading ``psi_rad`` in degrees (+ starboard)."""
    return math.degrees(ssa_float(math.atan2(d_ne[1], d_ne[0]) - psi_rad))


def _off_deg(d_ne: np.ndarray, psi_rad: float) -> float:
    """|bearing of the vector ``d_ne`` off the heading ``psi_rad``| in degrees."""
    return abs(_signed_deg(d_ne, psi_rad))


def onset(record: Any, near_m: float) -> dict[str, float] | None:
    """The arrival figures of one record (module docstring); None if it never came near."""
    track = record.trajectory
    goal = np.asarray(record.episode.goal_ne, dtype=float)
    d_goal = np.hypot(track[:, 0] - goal[0], track[:, 1] - goal[1])
    near = np.flatnonzero(d_goal < near_m)
    if near.size == 0:
        return None
    dt = record.duration_s / max(len(track) - 1, 1)  # s between recorded states
    t_arrive = float(near[0] * dt)
    own, psi = track[near[0], 0:2], float(track[near[0], 2])
    if not record.episode.vessels:  # --all: the approach only
        nan = float("nan")
        return {"arrival_s": t_arrive, "vessel_to_goal_m": nan, "blocked": 0.0,
                "goal_off_deg": _off_deg(goal - own, psi),
                "goal_signed_deg": _signed_deg(goal - own, psi), "vessel_range_m": nan,
                "vessel_off_deg": nan, "clear_after_s": 0.0, "circled_clear_s": nan}  # fmt: skip
    limit = record.episode.time_limit_s
    t = np.arange(t_arrive, limit + 0.25, 0.5)
    d_vessel = vessel_goal_distances_m(record.episode, t)
    rel = vessel_positions_ne(record.episode, np.array([t_arrive]))[:, 0, :] - own
    j = int(np.argmin(np.hypot(rel[:, 0], rel[:, 1])))
    clear = np.flatnonzero(d_vessel >= BLOCK_M)
    delay = float(t[clear[0]] - t_arrive) if clear.size else float("inf")
    return {
        "arrival_s": t_arrive,
        "vessel_to_goal_m": float(d_vessel[0]),
        "blocked": float(d_vessel[0] < BLOCK_M),
        "goal_off_deg": _off_deg(goal - own, psi),
        "goal_signed_deg": _signed_deg(goal - own, psi),
        "vessel_range_m": float(np.hypot(*rel[j])),
        "vessel_off_deg": _off_deg(rel[j], psi),
        "clear_after_s": delay,
        "circled_clear_s": float(limit - t_arrive - delay) if np.isfinite(delay) else 0.0,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--helmsman", required=True, help="a name or a checkpoint file")
    parser.add_argument("--set", default="moving-vessels", help="a stress set with vessels")
    parser.add_argument("--split", choices=("validation", "test"), default="validation")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--near-m", type=float, default=25.0, help="arrival: within this, m")
    parser.add_argument(
        "--all", action="store_true", help="every episode, not only traffic through the goal"
    )
    args = parser.parse_args()
    if args.episodes < 1 or not args.near_m > 0:
        parser.error("--episodes must be >= 1 and --near-m > 0")
    (stress_set,) = select_sets([args.set])
    records = evaluate_set(
        make_helmsman(args.helmsman), stress_set, stress_episodes(stress_set, args.episodes,
                                                                  args.split)
    )  # fmt: skip
    groups: dict[str, list[dict[str, float]]] = {}
    for r in records:
        through = bool(r.episode.vessels) and nearest_vessel_to_goal_m(r.episode) < THROUGH_GOAL_M
        if not (through or args.all):
            continue
        figures = onset(r, args.near_m)
        if figures is not None:
            groups.setdefault(r.outcome, []).append(figures)
    out = {"helmsman": args.helmsman, "set": args.set, "split": args.split, "all": args.all,
           "near_m": args.near_m, "block_m": BLOCK_M, "groups": {}}  # fmt: skip
    for outcome, rows in sorted(groups.items()):
        cols = {k: np.array([row[k] for row in rows]) for k in rows[0]}
        out["groups"][outcome] = {
            "episodes": len(rows),
            "blocked_at_arrival": int(cols["blocked"].sum()),
            "median_vessel_to_goal_m": round(float(np.nanmedian(cols["vessel_to_goal_m"])), 1),
            "median_clear_after_s": round(float(np.median(cols["clear_after_s"])), 1),
            "median_circled_clear_s": round(float(np.nanmedian(cols["circled_clear_s"])), 1),
            "median_arrival_s": round(float(np.median(cols["arrival_s"])), 1),
            "median_goal_off_deg": round(float(np.median(cols["goal_off_deg"])), 1),
            "goal_to_port": int((cols["goal_signed_deg"] < 0).sum()),
            "median_goal_signed_deg": round(float(np.median(cols["goal_signed_deg"])), 1),
            "median_vessel_range_m": round(float(np.nanmedian(cols["vessel_range_m"])), 1),
            "median_vessel_off_deg": round(float(np.nanmedian(cols["vessel_off_deg"])), 1),
        }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
