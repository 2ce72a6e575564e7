"""Expert-likeness and success of open-water helmsmen on the family's held-out set.

The family expert (:mod:`baselines.family_expert`) drives each of the 100 held-out family
episodes (:func:`usvsim.evaluation.family_likeness.family_held_out_episodes`: never trained,
selected or demonstrated on) 4 times; every helmsman named on the command line (shipped model
names, checkpoint paths, or classical helmsmen) runs the same episodes and is compared with it
(:mod:`usvsim.evaluation.family_likeness`: path distance, side agreement on the key obstacle,
heading-change Wasserstein-1). No open-water checkpoint is chosen by these metrics
(:func:`learning.experiments.train_il.train_il` ranks family runs by successes), so IL against
RL of the same setup is a fair comparison. Run from the repository root::

    python benchmarks/family_likeness.py il-gaussian-scene-ow rl-gaussian-scene-ow vo
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.family_likeness import family_likeness, family_reference
from usvsim.evaluation.openwater import evaluate_open_water
from usvsim.evaluation.stats import wilson_interval
from usvsim.helm.registry import helmsman_kinds, make_helmsman


def main(names: list[str], out: str = "usvsim-results/family_likeness.json") -> int:
    if not names or any(n.startswith("-") for n in names):
        print(
            "usage: python benchmarks/family_likeness.py HELMSMAN [HELMSMAN ...]", file=sys.stderr
        )
        return 2
    start = time.perf_counter()
    reference = family_reference()
    results = {}
    for name in names:
        helmsman = make_helmsman(name)
        obs, act = helmsman_kinds(helmsman)
        records = evaluate_open_water(helmsman, reference.episodes, observation=obs, action=act)
        lk = family_likeness(records, reference)
        wins = sum(r.success for r in records)
        lo, hi = wilson_interval(wins, len(records))
        results[name] = {
            "successes": wins,
            "n_episodes": len(records),
            "wilson_95": [lo, hi],
            "path_distance_m": lk.path_distance_m,
            "side_agreement": lk.side_agreement,
            "heading_change_w1_deg": lk.action_distance_deg,
        }
        print(
            f"{name:28s} success {wins:3d}/{len(records)}  path {lk.path_distance_m:5.1f} m  "
            f"side {lk.side_agreement:.2f}  W1 {lk.action_distance_deg:4.1f} deg",
            flush=True,
        )
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, json.dumps(results, indent=2) + "\n")
    print(f"{time.perf_counter() - start:.0f} s; {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
