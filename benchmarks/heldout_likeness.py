"""Expert-likeness of the shipped IL and RL models on the 200 held-out starts.

No checkpoint is chosen on these starts (IL ``best.pt`` files are ranked partly by the path
distance on the 15 validation starts), so this is the unbiased form of the IL-vs-RL comparison
(:mod:`usvsim.evaluation.likeness`: path distance to the careful expert's 8 runs per start,
side agreement, heading-change Wasserstein-1). Run as a script from the repository root::

    python benchmarks/heldout_likeness.py        # prints one line per model, writes JSON
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.episodes import heldout_episodes
from usvsim.evaluation.likeness import expert_reference, helmsman_likeness
from usvsim.helm.registry import helmsman_kinds, make_helmsman

SETUPS = ("gaussian-positional", "categorical-positional", "gaussian-radar", "categorical-radar")


def main(out: str = "usvsim-results/heldout_likeness.json") -> int:
    start = time.perf_counter()
    reference = expert_reference(heldout_episodes())
    results = {}
    for setup in SETUPS:
        for kind in ("il", "rl"):
            name = f"{kind}-{setup}"
            helmsman = make_helmsman(name)  # the setup's name: the model's former name
            obs, act = helmsman_kinds(helmsman)
            lk = helmsman_likeness(helmsman, observation=obs, action=act, reference=reference)
            results[name] = {
                "path_distance_m": lk.path_distance_m,
                "side_agreement": lk.side_agreement,
                "heading_change_w1_deg": lk.action_distance_deg,
            }
            print(
                f"{name:28s} path {lk.path_distance_m:5.1f} m  side {lk.side_agreement:.2f}  "
                f"W1 {lk.action_distance_deg:4.1f} deg",
                flush=True,
            )
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, json.dumps(results, indent=2) + "\n")
    print(f"{time.perf_counter() - start:.0f} s; {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
