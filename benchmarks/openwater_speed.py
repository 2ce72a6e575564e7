"""How fast ``usvsim/OpenWater-v0`` runs on the CPU (issue 40): decision steps per second.

``OpenWater-v0`` on its training family (scene and radar+goal observations, random Gaussian
actions, autoresets drawing new family episodes included) at N = 64, 256 and 1,024 boats,
beside the study task's env (positional) at the same N as the reference, measured in the same
run: per N, ``--rounds`` interleaved turns of ``--seconds / --rounds`` per env, so that a change
of machine load hits all three alike; the median turn is reported, and each open-water rate as
a share of the study task's (:func:`usvsim.evaluation.perf.open_water_speed_table`)::

    python benchmarks/openwater_speed.py
    python benchmarks/openwater_speed.py --sizes 256 --seconds 6 --json
    python benchmarks/openwater_speed.py --sizes 256 1024 --cpu

``--cpu``: the same interleaved turns, each timed by the wall clock and by the process's CPU
time (``time.process_time``, every thread of the process), so the table gives decision steps
per wall second and per CPU second, and each open-water CPU rate as a share of the study
task's CPU rate. On a machine shared with other jobs the wall-clock rate falls with the load;
the CPU rate moves less (it still rises and falls with the neighbours' use of caches and cores),
and the share least.

Where a step's time goes: ``usvsim perf --profile`` (cProfile of the same envs at N = 256).
The machine's load and CPU count are printed with the table: on a shared machine compare the
shares, not the rates.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any

import numpy as np

from usvsim.evaluation.perf import open_water_speed_table
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

STUDY = "study task positional"


def format_table(result: dict) -> str:
    """The table (markdown) of :func:`open_water_speed_table`'s result."""
    names = list(result["rows"][0]["decision_steps_per_s"])
    lines = [
        "| N | " + " | ".join(names) + " |",
        "|---:|" + "---:|" * len(names),
    ]
    for row in result["rows"]:
        cells = []
        for name in names:
            cell = f"{row['decision_steps_per_s'][name]:,}"
            share = row["over_study_task"].get(name)
            cells.append(cell if share is None else f"{cell} ({share:.2f}×)")
        lines.append(f"| {row['n_boats']:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _turn(env: Any, n_boats: int, seconds: float, actions: np.ndarray) -> tuple[float, float]:
    """Decision steps per wall second and per CPU second of one turn of about ``seconds``."""
    steps = 0
    wall0, cpu0 = time.perf_counter(), time.process_time()
    while time.perf_counter() - wall0 < seconds or steps == 0:
        env.step(actions[steps % len(actions)])
        steps += 1
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    return n_boats * steps / wall, n_boats * steps / max(cpu, 1e-9)


def cpu_speed_table(sizes: list[int], seconds: float, rounds: int) -> dict[str, Any]:
    """Per size: the study task's env (positional) and ``OpenWater-v0`` (scene, radar+goal) on
    its family, random Gaussian actions, autoresets included, in ``rounds`` interleaved turns
    of ``seconds / rounds`` each; medians of the turns' decision steps per wall second and per
    CPU second, and each open-water CPU rate over the study task's."""
    rows = []
    for n in sizes:
        envs: dict[str, Any] = {
            STUDY: PoleAvoidanceVectorEnv(n, observation="positional", action="gaussian"),
            "OpenWater-v0 scene": OpenWaterVectorEnv(n, observation="scene", action="gaussian"),
            "OpenWater-v0 radar+goal": OpenWaterVectorEnv(
                n, observation="radar+goal", action="gaussian"
            ),
        }
        actions = np.random.default_rng(0).uniform(-1.0, 1.0, (64, n, 1)).astype(np.float32)
        for env in envs.values():
            env.reset(seed=0)
            for k in range(3):  # warm-up: kernels built and loaded
                env.step(actions[k])
        turns: dict[str, list[tuple[float, float]]] = {name: [] for name in envs}
        for _ in range(rounds):
            for name, env in envs.items():
                turns[name].append(_turn(env, n, seconds / rounds, actions))
        wall = {name: float(np.median([w for w, _ in t])) for name, t in turns.items()}
        cpu = {name: float(np.median([c for _, c in t])) for name, t in turns.items()}
        rows.append(
            {
                "n_boats": n,
                "decision_steps_per_wall_s": {k: round(v) for k, v in wall.items()},
                "decision_steps_per_cpu_s": {k: round(v) for k, v in cpu.items()},
                "cpu_over_study_task": {
                    k: round(v / cpu[STUDY], 3) for k, v in cpu.items() if k != STUDY
                },
            }
        )
    return {"rows": rows, "load_average_1min": os.getloadavg()[0], "cpus": os.cpu_count()}


def format_cpu_table(result: dict) -> str:
    """The table (markdown) of :func:`cpu_speed_table`'s result."""
    lines = [
        "| N | env | per wall s | per CPU s | CPU share of the study task's |",
        "|---:|---|---:|---:|---:|",
    ]
    for row in result["rows"]:
        for name, wall in row["decision_steps_per_wall_s"].items():
            share = row["cpu_over_study_task"].get(name)
            cells = [f"{wall:,}", f"{row['decision_steps_per_cpu_s'][name]:,}"]
            cells.append("1" if share is None else f"{share:.2f}×")
            lines.append(f"| {row['n_boats']:,} | {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024])
    parser.add_argument("--seconds", type=float, default=3.0, help="per env and size")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    parser.add_argument(
        "--cpu", action="store_true", help="per wall second and per CPU second (module docstring)"
    )
    args = parser.parse_args()
    if args.seconds <= 0 or args.rounds < 1 or min(args.sizes) < 1:
        parser.error("--seconds must be > 0, --rounds and --sizes >= 1")
    if args.cpu:
        cpu_result = cpu_speed_table(args.sizes, args.seconds, args.rounds)
        if args.json:
            print(json.dumps(cpu_result, indent=2))
            return
        print("decision steps/s, per wall second and per CPU second (same turns)")
        print(format_cpu_table(cpu_result))
        load, cpus = cpu_result["load_average_1min"], cpu_result["cpus"]
        print(f"load average (1 min) {load:.2f} on {cpus} CPUs")
        return
    result = open_water_speed_table(tuple(args.sizes), args.seconds, args.rounds)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print("decision steps/s (share of the study task's env at the same N, same run)")
    print(format_table(result))
    print(
        f"load average (1 min) {result['load_average_1min']} on {result['cpus']} CPUs; "
        f"issue 40's bar: {result['target_N=256']:,} at N = 256"
    )


if __name__ == "__main__":
    main()
