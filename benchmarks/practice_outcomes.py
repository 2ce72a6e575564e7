"""Outcomes of helmsmen on a training practice member's episodes: does the practice hold
situations the helmsmen fail (``docs/notes/2026-12-traffic.md``)?

``--member goal-islet`` (:func:`usvsim.task.openwater_env.goal_islet_family`) or
``goal-approach`` (:func:`usvsim.task.openwater_env.goal_approach_family`): ``--episodes``
episodes drawn from ``--seed`` (default 12345: neither a stress split's seed nor a training
run's), each helmsman's outcome counts. Printed as JSON::

    python benchmarks/practice_outcomes.py --member goal-islet \\
        --helmsmen vo-radar,radar-gaussian-gail-trpo-traffic
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from collections.abc import Callable

from usvsim.common.errors import UserError
from usvsim.evaluation.stress import StressSet, evaluate_set
from usvsim.helm.registry import make_helmsman
from usvsim.task.openwater import draw_open_water
from usvsim.task.openwater_env import ScenarioMixture, goal_approach_family, goal_islet_family

MEMBERS: dict[str, Callable[[], ScenarioMixture]] = {
    "goal-islet": goal_islet_family,
    "goal-approach": goal_approach_family,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--member", choices=sorted(MEMBERS), required=True)
    parser.add_argument(
        "--helmsmen", required=True, help="names or checkpoint files, comma-separated"
    )
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=12345)
    args = parser.parse_args()
    if args.episodes < 1 or args.seed < 0:
        parser.error("--episodes must be >= 1 and --seed >= 0")
    (scenario,) = MEMBERS[args.member]().members
    practice = StressSet(args.member, "a training practice member", scenario)
    episodes = draw_open_water(scenario, args.seed, args.episodes)
    out: dict[str, object] = {"member": args.member, "episodes": args.episodes, "seed": args.seed}
    outcomes = {}
    for name in args.helmsmen.split(","):
        try:
            helmsman = make_helmsman(name)
        except UserError as err:
            parser.exit(2, f"practice_outcomes.py: error: {err}\n")
        outcomes[name] = dict(
            Counter(r.outcome for r in evaluate_set(helmsman, practice, episodes))
        )
    out["outcomes"] = outcomes
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
