"""The COLREG reward replayed on a helmsman's stress-set tracks, by outcome and by whether a
target vessel passes through the goal circle (the goal orbits of ``docs/notes/2026-12-traffic.md``).

The helmsman runs the set's ``--split`` episodes (:func:`usvsim.evaluation.stress.stress_episodes`);
each episode's COLREG terms are summed over its decisions as the training env pays them
(``benchmarks/colreg_reward_check.py``'s replay) and grouped by outcome and by traffic through
the goal (a vessel centre within 15 m of the goal within the time limit,
``benchmarks/stress_outcomes.py``). Printed as JSON: per group the episodes, how many paid each
term at all, and each term's mean sum::

    nice python benchmarks/orbit_colreg_replay.py --helmsman radar-gaussian-gail-trpo-traffic
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the two scripts' pieces, shared

from colreg_reward_check import replay
from stress_outcomes import THROUGH_GOAL_M, nearest_vessel_to_goal_m

from usvsim.evaluation.stress import evaluate_set, select_sets, stress_episodes
from usvsim.helm.registry import make_helmsman
from usvsim.task.colreg_reward import COLREG_TERMS, ColregRewardWeights


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--helmsman", required=True, help="a name or a checkpoint file")
    parser.add_argument("--set", default="moving-vessels", help="a stress set with vessels")
    parser.add_argument("--split", choices=("validation", "test"), default="validation")
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {args.episodes}")
    (stress_set,) = select_sets([args.set])
    episodes = stress_episodes(stress_set, args.episodes, args.split)
    records = [
        r for r in evaluate_set(make_helmsman(args.helmsman), stress_set, episodes)
        if r.episode.vessels
    ]  # fmt: skip
    if not records:
        parser.error(f"--set {args.set}: no episode with target vessels")
    sums = replay(records, ColregRewardWeights())
    through = np.array([nearest_vessel_to_goal_m(r.episode) < THROUGH_GOAL_M for r in records])
    outcome = np.array([r.outcome for r in records])
    groups = []
    for name in sorted(set(outcome.tolist())):
        for crossed in (True, False):
            m = (outcome == name) & (through == crossed)
            if not m.any():
                continue
            groups.append(
                {
                    "outcome": name,
                    "traffic_through_goal": crossed,
                    "episodes": int(m.sum()),
                    "paid": {t: int(np.sum(sums[t][m] != 0.0)) for t in COLREG_TERMS},
                    "mean_sum": {t: round(float(sums[t][m].mean()), 3) for t in COLREG_TERMS},
                }
            )
    print(json.dumps({"helmsman": args.helmsman, "set": args.set, "split": args.split,
                      "groups": groups}, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
