"""The training compute spent on issue 41: every finished run's wall-clock under the record
folders (each run's ``summary.json``: ``wall_time_s``, ``setup``, ``seed`` in the command),
per setup and in total, in seconds and core-hours. Runs went one torch thread each on the 2
shared cores, often two to three side by side, so a run's wall-clock is its compute on one
core (an upper bound where it shared a core)::

    python benchmarks/colreg_compute.py benchmarks/data/colreg-ablation benchmarks/data/il-colreg \\
        benchmarks/data/il-mixed benchmarks/data/il-owcr
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path


def runs(folders: list[Path]) -> list[tuple[str, str, float]]:
    """(folder, setup, wall-clock s) of every ``summary.json`` under ``folders``, sorted."""
    out = []
    for folder in folders:
        for path in sorted(folder.rglob("summary.json")):
            summary = json.loads(path.read_text())
            if "wall_time_s" not in summary:
                continue
            out.append((str(path.parent), str(summary.get("setup", "?")), summary["wall_time_s"]))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path, help="record folders to search")
    args = parser.parse_args(argv)
    found = runs(args.folders)
    if not found:
        parser.error("no summary.json with wall_time_s under " + ", ".join(map(str, args.folders)))
    per_setup: dict[str, list[float]] = defaultdict(list)
    print("| run | setup | wall-clock s |\n|---|---|---|")
    for where, setup, wall in found:
        per_setup[setup].append(wall)
        print(f"| {where} | `{setup}` | {wall:,.0f} |")
    print("\n| setup | runs | wall-clock s | core-hours |\n|---|---|---|---|")
    for setup, walls in per_setup.items():
        print(f"| `{setup}` | {len(walls)} | {sum(walls):,.0f} | {sum(walls) / 3600:.1f} |")
    total = sum(w for _, _, w in found)
    print(f"| total | {len(found)} | {total:,.0f} | {total / 3600:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
