"""Why the overtaking Imazu problems are hard to pass: the same recorded episodes scored with the
scorer's ``ahead_range_m`` (1100 m × 0.3 = 330 m, ranges scaled as equal *times* at the boat's
speed, usvsim.evaluation.colreg_params) and with 1100 m × λ = 47 m (λ = 300 / 7060, the *length*
scale of the Imazu scenes, usvsim.evaluation.imazu). Prints a Markdown table: per overtaking
problem and helmsman, the overtaking (give-way) encounters, the ones that pass, and the ones
that cross the target's course line ahead of its bow, under each range::

    python benchmarks/colreg_overtaking.py                    # sb-mpc and vo, 20 test episodes
    python benchmarks/colreg_overtaking.py --helmsmen sb-mpc --episodes 10
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

OVERTAKING_PROBLEMS = (3, 7, 15, 17, 20, 22)  # an overtaking target (usvsim.evaluation.imazu)
SHIP_AHEAD_RANGE_M = 1100.0  # m, colav-simulator's stage-2 range (colreg_params.ahead_range_m)


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--helmsmen", default="sb-mpc,vo")
    args = parser.parse_args(argv)

    from usvsim.evaluation.colreg import ColregParams, EncounterType, evaluate_colreg
    from usvsim.evaluation.colreg_rollout import run_encounters
    from usvsim.evaluation.imazu import ImazuConfig, imazu_episodes
    from usvsim.helm.registry import make_helmsman

    scene_range = SHIP_AHEAD_RANGE_M * ImazuConfig().length_scale
    default = ColregParams()
    variants = {
        f"{default.ahead_range_m:.0f} m": default,
        f"{scene_range:.0f} m": replace(default, ahead_range_m=scene_range),
    }
    print(
        f"{args.episodes} test episodes per problem; cells: overtaking encounters / passed / "
        "crossed ahead, with ahead_range_m = " + " | ".join(variants) + "\n"
    )
    names = [h for h in args.helmsmen.split(",") if h]
    print("| problem | " + " | ".join(f"`{h}` {v}" for h in names for v in variants) + " |")
    print("|---" * (1 + len(names) * len(variants)) + "|")
    for p in OVERTAKING_PROBLEMS:
        episodes = imazu_episodes(p, args.episodes, "test")
        cells = []
        for h in names:
            run = run_encounters(make_helmsman(h), episodes)
            for params in variants.values():
                res = evaluate_colreg(run.tracks, params)
                ot = np.asarray(res.encounter) == int(EncounterType.OVERTAKING_GIVE_WAY)
                ahead = np.nan_to_num(res.penalties["overtaking_ahead"]) > 0.0
                cells.append(
                    f"{int(ot.sum())} / {int((ot & np.asarray(res.passed)).sum())} / "
                    f"{int((ot & ahead).sum())}"
                )
        print(f"| imazu-{p:02d} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
