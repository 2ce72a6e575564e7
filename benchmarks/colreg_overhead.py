"""What the COLREG columns add to the stress suite's run time (issue 39: at most 20 %).

Runs the stress suite's traffic sets (``moving-vessels``, ``everything``) for the chosen
helmsmen twice in one process, per helmsman, in alternating order so that the machine's load
hits both alike: without the COLREG columns (``run_stress(colreg=False)``) and with them.
Prints, as JSON, the wall-clock and CPU time of each, their ratio, and the scoring time measured
inside the runs (``colreg_s`` of the rows: tracks + scorer) over the rollouts' time, with
``uptime``'s load::

    python benchmarks/colreg_overhead.py                       # default helmsmen, 100 episodes
    python benchmarks/colreg_overhead.py --episodes 50 --helmsmen vo,sb-mpc
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from typing import Any


def _timed(factories: dict[str, Any], sets: Any, n: int, colreg: bool) -> tuple[Any, float, float]:
    from usvsim.evaluation.stress import run_stress

    wall, cpu = time.perf_counter(), time.process_time()
    result = run_stress(factories, sets, n, progress=False, colreg=colreg)
    return result, time.perf_counter() - wall, time.process_time() - cpu


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--helmsmen", default="", help="comma-separated; default: usvsim bench's")
    args = parser.parse_args(argv)

    from usvsim.evaluation.bench import loadable_helmsmen
    from usvsim.evaluation.model_cards import default_helmsmen
    from usvsim.evaluation.stress import select_sets
    from usvsim.evaluation.stress_colreg import colreg_overhead
    from usvsim.helm.registry import select_helmsmen

    names = [n for n in args.helmsmen.split(",") if n] or default_helmsmen()
    factories, _ = loadable_helmsmen(select_helmsmen(names), True, print)
    sets = select_sets(["moving-vessels", "everything"])
    totals = {"off": [0.0, 0.0], "on": [0.0, 0.0]}
    rows: list[Any] = []
    for i, (name, factory) in enumerate(factories.items()):
        # alternate the order per helmsman, so that the load's drift hits both modes alike
        for mode in ("off", "on") if i % 2 == 0 else ("on", "off"):
            result, wall, cpu = _timed({name: factory}, sets, args.episodes, mode == "on")
            totals[mode][0] += wall
            totals[mode][1] += cpu
            if mode == "on":
                rows += result.rows
    report = {
        "helmsmen": list(factories),
        "sets": [s.name for s in sets],
        "episodes_per_set": args.episodes,
        "without_scoring_wall_s": totals["off"][0],
        "with_scoring_wall_s": totals["on"][0],
        "wall_ratio": totals["on"][0] / totals["off"][0],
        "without_scoring_cpu_s": totals["off"][1],
        "with_scoring_cpu_s": totals["on"][1],
        "cpu_ratio": totals["on"][1] / totals["off"][1],
        "scoring_s_inside_runs": sum(r.colreg_s for r in rows),
        "scoring_over_rollouts": colreg_overhead(rows),
        "encounters_scored": sum(r.colreg_encounters for r in rows),
        "load_average_1_5_15": list(os.getloadavg()),
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
