"""Zig-zag overshoots and turning-circle drift in wind and waves over several seeds (issue 38).

``usvsim manoeuvre`` reports one seed; the gusts and the wave motion make each trial a draw.
This runs the 10/10 and 20/20 zig-zags and the turning circle of one vessel for ``--seeds``
seeds per weather and prints mean ± standard deviation (Markdown, or JSON with ``--json``)::

    python benchmarks/weather_trials.py
    python benchmarks/weather_trials.py --vessel default --seeds 20 --json
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace

import numpy as np

from usvsim.evaluation.manoeuvre import TrialWeather, turning_circle, zigzag
from usvsim.vessel.vessels import get_vessel

WEATHERS = {
    "calm": TrialWeather(),
    "wind 10 m/s, beam": TrialWeather(10.0, 90.0, 0),
    "sea state 3, from 45°": TrialWeather(0.0, 45.0, 3),
    "sea state 4, from 45°": TrialWeather(0.0, 45.0, 4),
    "sea state 4 + 10 m/s, beam": TrialWeather(10.0, 90.0, 4),
}


def measure(vessel_name: str, seeds: int) -> dict[str, dict[str, list[float]]]:
    vessel = get_vessel(vessel_name)
    speed = vessel.cruise_speed_mps
    out: dict[str, dict[str, list[float]]] = {}
    for label, base in WEATHERS.items():
        rows: dict[str, list[float]] = {}
        for seed in range(seeds if not base.calm else 1):
            weather = replace(base, seed=seed)
            for helm in (10.0, 20.0):
                z = zigzag(vessel, speed, helm, weather=weather)
                rows.setdefault(f"{helm:g}/{helm:g} first (deg)", []).append(z.first_overshoot_deg)
                rows.setdefault(f"{helm:g}/{helm:g} second (deg)", []).append(
                    z.second_overshoot_deg
                )
            if not base.calm:
                circle = turning_circle(vessel, (speed,), weather=weather)[0]
                rows.setdefault("circle drift (m/s)", []).append(circle.drift_mps)
        out[label] = rows
    return out


def table(result: dict[str, dict[str, list[float]]]) -> str:
    keys = [*next(iter(result.values())).keys(), "circle drift (m/s)"]
    head = "| weather | " + " | ".join(keys) + " |"
    lines = [head, "|" + "---|" * (len(keys) + 1)]
    for label, rows in result.items():
        cells = []
        for k in keys:
            v = np.asarray(rows.get(k, []), dtype=float)
            fmt = ".2f" if k.startswith("circle") else ".1f"
            cells.append("–" if v.size == 0 else f"{v.mean():{fmt}} ± {v.std():{fmt}}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vessel", default="default")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    result = measure(args.vessel, args.seeds)
    print(json.dumps(result, indent=2) if args.json else table(result))


if __name__ == "__main__":
    main()
