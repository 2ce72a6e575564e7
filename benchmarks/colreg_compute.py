"""The training compute spent on issue 41: every finished run's wall-clock under the record
folders (each run's ``summary.json``: ``wall_time_s``, ``setup``, ``seed`` in the command),
per setup and in total, in seconds and core-hours. Runs went one torch thread each on the 2
shared cores, often two to three side by side, so a run's wall-clock is its compute on one
core (an upper bound where it shared a core). A run resumed in a copy of its folder (a longer
budget) counts its whole wall-clock, the earlier part included, so the two folders of one chain
(the same setup, seed and first ``log.csv`` row) count once, at the longer::

    python benchmarks/colreg_compute.py benchmarks/data/colreg-ablation benchmarks/data/il-colreg \\
        benchmarks/data/il-mixed benchmarks/data/il-owcr
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path


def _chain(path: Path, summary: dict[str, object]) -> tuple[object, ...]:
    """What a run shares with the copy it was resumed in: setup, seed and first log row (the
    folder itself where there is no log)."""
    log = path.parent / "log.csv"
    lines = log.read_text().splitlines()[:2] if log.is_file() else []
    first = lines[1] if len(lines) == 2 else str(path.parent)
    return (summary.get("setup"), summary.get("seed"), first)


def runs(folders: list[Path]) -> list[tuple[str, str, float]]:
    """(folder, setup, wall-clock s) of every ``summary.json`` under ``folders``, sorted, one
    per chain of resumed copies (its longest)."""
    longest: dict[tuple[object, ...], tuple[str, str, float]] = {}
    for folder in folders:
        for path in sorted(folder.rglob("summary.json")):
            summary = json.loads(path.read_text())
            if "wall_time_s" not in summary:
                continue
            run = (str(path.parent), str(summary.get("setup", "?")), float(summary["wall_time_s"]))
            key = _chain(path, summary)
            if key not in longest or run[2] > longest[key][2]:
                longest[key] = run
    return sorted(longest.values())


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
