"""Fill the model cards' stress figures and recommended marks in ``usvsim/models/models.json``.

First the validation split, then the marks (they read validation only), then the test split::

    python benchmarks/stress_splits.py --splits validation --out R      # every shipped model
    python benchmarks/model_cards.py --stress R/stress-validation.json --recommend
    python benchmarks/stress_splits.py --splits test --helmsmen <recommended> --out R
    python benchmarks/model_cards.py --stress R/stress-test.json

(:mod:`usvsim.evaluation.model_cards`: the card fields and :data:`RECOMMENDATION_RULE`.)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from usvsim.evaluation.model_cards import (
    check_cards,
    load_cards,
    recommend,
    with_recommendations,
    with_stress_figures,
    write_cards,
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--stress",
        type=Path,
        action="append",
        default=[],
        help="a stress JSON (usvsim bench --suite stress --json); repeatable",
    )
    parser.add_argument(
        "--sets-of",
        type=Path,
        default=None,
        help="keep only the sets of this stress JSON (docs/data/stress.json: the cards' sets)",
    )
    parser.add_argument(
        "--recommend",
        action="store_true",
        help="set the recommended marks by the rule (validation figures only)",
    )
    args = parser.parse_args(argv)  # fmt: skip
    cards = load_cards()
    keep = json.loads(args.sets_of.read_text())["sets"] if args.sets_of else None
    for path in args.stress:
        stress = json.loads(path.read_text())
        if keep is not None:
            stress["sets"] = [s for s in stress["sets"] if s in keep]
            stress["rows"] = [r for r in stress["rows"] if r["episode_set"] in keep]
        cards = with_stress_figures(cards, stress)
    if args.recommend:
        cards = with_recommendations(cards)
        for (use, family), name in recommend(cards).items():
            print(f"recommended for {use} ({family}): {name}")
    write_cards(cards)
    check_cards()
    return 0


if __name__ == "__main__":
    sys.exit(main())
