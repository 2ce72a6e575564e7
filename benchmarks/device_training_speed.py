"""Wall-clock of one TRPO iteration: ``usvsim train --device torch-cpu`` against ``cpu``.

Both devices train ``rl-categorical-positional`` (seed 0, its N = 32 boats x 64 decisions, or
``--n-envs``) for ``--iterations`` iterations, in alternating turns, so that load changes on a
shared machine hit both; prints the median iteration wall-clock (rollout + update) of each, the
ratio torch-cpu / cpu, the rollout and update parts, and ``uptime`` before and after.

    python benchmarks/device_training_speed.py --iterations 6 --turns 2
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import torch

from learning.algorithms.device_loop import train_on_device
from learning.algorithms.loop import IterationStats, train
from learning.experiments.setups import get_setup
from learning.experiments.train_rl import device_env_maker


def one_run(device: str, n_envs: int, iterations: int) -> list[tuple[float, float]]:
    """(rollout_s, update_s) of every iteration after the first."""
    setup = get_setup("rl-categorical-positional").with_num_envs(n_envs)
    rows: list[tuple[float, float]] = []

    def callback(s: IterationStats, agent: Any) -> None:
        rows.append((s.rollout_time_s, s.update_time_s))

    config = setup.run_config(0, iterations)
    if device == "cpu":
        train(config, setup.make_vector_env, callback=callback)
    else:
        train_on_device(config, device_env_maker(setup, device), callback=callback)
    return rows[1:]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=6)
    parser.add_argument("--turns", type=int, default=2)
    parser.add_argument("--n-envs", type=int, default=32)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    print(
        "uptime before:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    )
    times: dict[str, list[tuple[float, float]]] = {"cpu": [], "torch-cpu": []}
    for _ in range(args.turns):
        for device in times:
            times[device] += one_run(device, args.n_envs, args.iterations)
    print(
        "uptime after: ", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    )
    median = {}
    for device, rows in times.items():
        it = statistics.median(r + u for r, u in rows)
        median[device] = it
        rollout, update = (statistics.median(part) for part in zip(*rows, strict=True))
        print(
            f"{device:>9}: {it:.3f} s per iteration (rollout {rollout:.3f} s, update "
            f"{update:.3f} s; {len(rows)} iterations, "
            f"N = {args.n_envs}, {args.threads} torch thread(s))"
        )
    print(
        f"torch-cpu / cpu: {median['torch-cpu'] / median['cpu']:.2f}x the wall-clock per iteration"
    )


if __name__ == "__main__":
    main()
