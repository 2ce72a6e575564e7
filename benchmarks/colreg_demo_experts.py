"""The SB-MPC expert against the family expert on the episodes of the COLREG demonstrations.

Drives the :data:`learning.experiments.colreg_demos.COLREG_DEMO_RUNS` episodes that
``python -m learning.experiments.colreg_demos`` records (same seed, same episodes, the same
human: traits, noise and wobble from the same expert seed) once with each expert's judgement
(:mod:`baselines.sbmpc_expert`'s ``sb-mpc``, :mod:`baselines.family_expert`'s ``vo``), scores
both with the COLREG scorer and the task's success (:func:`learning.experiments.colreg_demos.
score_runs`), and writes the figures as JSON (wall-clock per episode and the machine's load
with them). ``--runs N``: the first N of those episodes only (the family expert takes about
1 s of wall-clock per episode on 2 loaded cores). Run from the repository root::

    nice -n 5 python benchmarks/colreg_demo_experts.py --runs 200 usvsim/demos/colreg/experts.json
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from baselines.family_expert import run_family_expert
from baselines.sbmpc_expert import run_sbmpc_expert
from learning.experiments.colreg_demos import (
    COLREG_DEMO_RUNS,
    COLREG_DEMO_SEED,
    colreg_demo_episodes,
    score_runs,
)
from usvsim.common.fileio import atomic_write_text


def main(argv: list[str]) -> int:
    runs_wanted = COLREG_DEMO_RUNS
    if len(argv) == 3 and argv[0] == "--runs" and argv[1].isdigit():
        runs_wanted, argv = int(argv[1]), argv[2:]
    if len(argv) != 1 or not 1 <= runs_wanted <= COLREG_DEMO_RUNS:
        print(
            "usage: python benchmarks/colreg_demo_experts.py [--runs N] OUT.json "
            f"(1 <= N <= {COLREG_DEMO_RUNS})",
            file=sys.stderr,
        )
        return 2
    _, episodes = colreg_demo_episodes(runs_wanted, seed=COLREG_DEMO_SEED)
    expert_seed = int(np.random.SeedSequence(COLREG_DEMO_SEED).spawn(3)[1].generate_state(1)[0])
    out: dict[str, object] = {"runs": len(episodes), "seed": COLREG_DEMO_SEED, "experts": {}}
    experts = out["experts"]
    assert isinstance(experts, dict)
    for name, run in (("sb-mpc", run_sbmpc_expert), ("family (vo)", run_family_expert)):
        t0, c0 = time.perf_counter(), time.process_time()
        runs = run(episodes, seed=expert_seed)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        score = score_runs(runs)
        experts[name] = {
            **score.to_dict(),
            "runs_compliant_and_successful": int((score.success & score.passed).sum()),
            "wall_s_per_episode": wall / len(runs),
            "cpu_s_per_episode": cpu / len(runs),
            "load_1min": os.getloadavg()[0],
        }
        fig = experts[name]
        print(
            f"{name}: success {fig['success_rate']:.3f}, collisions {fig['collisions']}, "
            f"compliance {fig['compliance_rate']:.3f} of {fig['encounters']} encounters, "
            f"{wall / len(runs):.2f} s per episode (load {fig['load_1min']:.1f})"
        )
    atomic_write_text(Path(argv[0]), json.dumps(out, indent=1, sort_keys=True) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
