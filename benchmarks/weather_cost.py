"""What wind and waves cost the plant kernel (issue 38): boat-substeps/s, calm vs weather.

N boats (default 1024) of the default vessel with its PID autopilot, stepped ``--steps`` plant
steps per call; three kernels timed in interleaved blocks so that machine load hits them alike,
``--repeats`` times, medians reported (per wall-clock second and per CPU second of the process)
with the 1-minute load average before and after::

    python benchmarks/weather_cost.py
    python benchmarks/weather_cost.py --n 1024 --repeats 7 --json

=================  =========================================================================
row                what runs
=================  =========================================================================
``calm``           :class:`usvsim.vessel.plant.Plant` (the kernel every environment uses)
``weather-calm``   :class:`usvsim.vessel.weather_plant.WeatherPlant`, no wind, calm sea
``weather``        the same with 10 m/s wind (gusts 10 %) and sea state 4, wave filter on
=================  =========================================================================

The weather rows include drawing the three standard normals per boat and step in NumPy.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from collections.abc import Callable

import numpy as np

from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.waves import sea_state_from_code
from usvsim.vessel.weather_plant import SeaConditions, WeatherPlant


def _timer(run: Callable[[], object], block_s: float) -> tuple[float, float]:
    """Calls of ``run`` per second of wall-clock time and per second of this process's CPU
    time (all its threads) over about ``block_s`` seconds. On a machine shared with other jobs
    the CPU-time rate is the steadier one: time spent waiting for a core is not counted."""
    run()  # warm
    t0, c0, calls = time.perf_counter(), time.process_time(), 0
    while time.perf_counter() - t0 < block_s:
        run()
        calls += 1
    return calls / (time.perf_counter() - t0), calls / (time.process_time() - c0)


def measure(n: int, steps: int, repeats: int, block_s: float) -> dict[str, object]:
    plant = Plant("default")
    rng = np.random.default_rng(0)
    eta = np.c_[rng.uniform(-100, 100, (n, 2)), rng.uniform(-3, 3, n)]
    ref = rng.uniform(-math.pi, math.pi, n)
    calm_state = plant.initial_state(eta)
    weather = WeatherPlant(plant, seed=0)
    still = weather.initial_state(eta, SeaConditions.uniform(n))
    windy = weather.initial_state(
        eta, SeaConditions.uniform(n, 10.0, 1.0, sea_state_from_code(4, 2.0))
    )
    runs = {
        "calm": lambda: plant.step(calm_state, ref, n_steps=steps),
        "weather-calm": lambda: weather.step(still, ref, n_steps=steps),
        "weather": lambda: weather.step(windy, ref, n_steps=steps),
    }
    rates: dict[str, list[float]] = {k: [] for k in runs}
    cpu_rates: dict[str, list[float]] = {k: [] for k in runs}
    load_before = os.getloadavg()[0]
    for _ in range(repeats):
        for key, run in runs.items():
            wall, cpu = _timer(run, block_s)
            rates[key].append(wall * n * steps)
            cpu_rates[key].append(cpu * n * steps)
    med = {k: float(np.median(v)) for k, v in rates.items()}
    cpu_med = {k: float(np.median(v)) for k, v in cpu_rates.items()}
    return {
        "n_boats": n,
        "steps_per_call": steps,
        "kernel": plant.kernel,
        "boat_substeps_per_s": {k: round(v) for k, v in med.items()},
        "weather_over_calm": round(med["weather"] / med["calm"], 3),
        "weather_calm_over_calm": round(med["weather-calm"] / med["calm"], 3),
        "boat_substeps_per_cpu_s": {k: round(v) for k, v in cpu_med.items()},
        "cpu_weather_over_calm": round(cpu_med["weather"] / cpu_med["calm"], 3),
        "load_average_1min": [round(load_before, 2), round(os.getloadavg()[0], 2)],
        "repeats": repeats,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1024)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--block-s", type=float, default=1.0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = measure(args.n, args.steps, args.repeats, args.block_s)
    if args.json:
        print(json.dumps(result, indent=2))
        return
    rates = result["boat_substeps_per_s"]
    assert isinstance(rates, dict)
    print(
        f"N={args.n}, {result['kernel']} kernel, load {result['load_average_1min']}: "
        + ", ".join(f"{k} {v:,}/s" for k, v in rates.items())
        + f"; weather / calm = {result['weather_over_calm']} (per CPU second: "
        + f"{result['cpu_weather_over_calm']})"
    )


if __name__ == "__main__":
    main()
