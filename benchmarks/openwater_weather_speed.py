"""What weather costs ``usvsim/OpenWater-v0`` (issue 38): decision steps per second of the env on
its calm training family beside the same family in weather, measured in the same run.

Three envs at N boats (``--sizes``, default 256) per observation (``--observations``, default
``scene`` and ``radar+goal``), random actions, autoresets drawing new family episodes included:

* ``calm``: the default family (:data:`usvsim.task.openwater_env.OPEN_WATER_FAMILY`), the calm
  plant fused with the navigation filter;
* ``moderate``: :func:`usvsim.task.openwater_env.weather_family` (0-8 m/s wind, H_s 0-1 m), the
  weather plant for every boat;
* ``sea-state-4``: the family with the stress set's weather (8-10.7 m/s, H_s 1.25-2.5 m).

``--rounds`` interleaved turns of ``--seconds / --rounds`` per env, so that a change of the
machine's load hits all three alike; the median turn is reported and each weather rate as a
share of the calm one (the issue's bar: >= 0.8), per wall-clock and per CPU second::

    nice python benchmarks/openwater_weather_speed.py --json
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import time

import numpy as np

from usvsim.task.openwater_env import OPEN_WATER_FAMILY, OpenWaterVectorEnv, weather_family
from usvsim.task.weather_draw import WEATHER_SETS


def decision_rate(
    env: OpenWaterVectorEnv, seconds: float, rng: np.random.Generator
) -> tuple[float, float]:
    """Decision steps (boats × steps) per wall-clock second and per CPU second of this process
    (all its threads) over about ``seconds``; the CPU-time rate is the steadier one on a
    machine shared with other jobs (time waiting for a core is not counted)."""
    n = env.num_envs
    steps, start, cpu = 0, time.perf_counter(), time.process_time()
    while True:
        env.step(rng.uniform(-1.0, 1.0, (n, 1)).astype(np.float32))
        steps += 1
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return n * steps / elapsed, n * steps / (time.process_time() - cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[256])
    parser.add_argument("--observations", nargs="+", default=["scene", "radar+goal"])
    parser.add_argument("--seconds", type=float, default=12.0, help="per env and size")
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.seconds <= 0 or args.rounds < 1 or min(args.sizes) < 1:
        parser.error("--seconds must be > 0, --rounds and --sizes >= 1")
    families = {
        "calm": OPEN_WATER_FAMILY,
        "moderate": weather_family(),
        "sea-state-4": weather_family(ranges=WEATHER_SETS["sea-state-4"]),
    }
    rows = []
    uptime_before = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    for n, observation in itertools.product(args.sizes, args.observations):
        envs = {
            k: OpenWaterVectorEnv(n, observation=observation, family=f)  # type: ignore[arg-type]
            for k, f in families.items()
        }
        rng = np.random.default_rng(0)
        turns: dict[str, list[tuple[float, float]]] = {k: [] for k in envs}
        for env in envs.values():
            env.reset(seed=0)
            decision_rate(env, 0.5, rng)  # warm-up: compiled kernels loaded, buffers grown
        for _ in range(args.rounds):
            for name, env in envs.items():
                turns[name].append(decision_rate(env, args.seconds / args.rounds, rng))
        rates = {k: float(np.median([w for w, _ in v])) for k, v in turns.items()}
        cpu = {k: float(np.median([c for _, c in v])) for k, v in turns.items()}
        rows.append(
            {
                "n_boats": n,
                "observation": observation,
                "decision_steps_per_s": {k: round(v) for k, v in rates.items()},
                "over_calm": {k: round(v / rates["calm"], 3) for k, v in rates.items()},
                "decision_steps_per_cpu_s": {k: round(v) for k, v in cpu.items()},
                "cpu_over_calm": {k: round(v / cpu["calm"], 3) for k, v in cpu.items()},
                "in_weather": {k: bool(e.sim.inner.in_weather) for k, e in envs.items()},
            }
        )
    result = {
        "rows": rows,
        "uptime_before": uptime_before,
        "uptime_after": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip(),
        "cpus": os.cpu_count(),
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return
    for row in rows:
        print(row)
    print(result["uptime_before"], "|", result["uptime_after"])


if __name__ == "__main__":
    main()
