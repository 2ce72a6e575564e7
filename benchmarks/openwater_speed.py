"""How fast ``usvsim/OpenWater-v0`` runs on the CPU (issue 40): decision steps per second.

``OpenWater-v0`` on its training family (scene and radar+goal observations, random Gaussian
actions, autoresets drawing new family episodes included) at N = 64, 256 and 1,024 boats,
beside the study task's env (positional) at the same N as the reference, measured in the same
run: per N, ``--rounds`` interleaved turns of ``--seconds / --rounds`` per env, so that a change
of machine load hits all three alike; the median turn is reported, and each open-water rate as
a share of the study task's (:func:`usvsim.evaluation.perf.open_water_speed_table`)::

    python benchmarks/openwater_speed.py
    python benchmarks/openwater_speed.py --sizes 256 --seconds 6 --json

Where a step's time goes: ``usvsim perf --profile`` (cProfile of the same envs at N = 256).
The machine's load and CPU count are printed with the table: on a shared machine compare the
shares, not the rates.
"""

from __future__ import annotations

import argparse
import json

from usvsim.evaluation.perf import open_water_speed_table


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024])
    parser.add_argument("--seconds", type=float, default=3.0, help="per env and size")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.seconds <= 0 or args.rounds < 1 or min(args.sizes) < 1:
        parser.error("--seconds must be > 0, --rounds and --sizes >= 1")
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
