"""The README's stress table from a stress run's ``stress.csv``: success in % of each set's
episodes, collisions in brackets where any; one column per helmsman, one row per set (the
suite's order). Run from the repository root after ``usvsim bench --suite stress``::

    python benchmarks/stress_table.py usvsim-results/bench/stress.csv
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

SHORT = {"categorical": "cat", "gaussian": "gau", "positional": "pos"}


def short_name(helmsman: str) -> str:
    """``positional-categorical-gail-study`` → ``pos-cat-gail-study`` (the column labels)."""
    return "-".join(SHORT.get(part, part) for part in helmsman.split("-"))


def table(rows: list[dict[str, str]]) -> str:
    """The Markdown table of ``rows`` (``stress.csv`` rows)."""
    helmsmen = list(dict.fromkeys(r["helmsman"] for r in rows))
    sets = list(dict.fromkeys(r["episode_set"] for r in rows))
    cell = {(r["episode_set"], r["helmsman"]): r for r in rows}
    lines = [
        "| set | " + " | ".join(short_name(h) for h in helmsmen) + " |",
        "|---" * (len(helmsmen) + 1) + "|",
    ]
    for s in sets:
        cells = []
        for h in helmsmen:
            r = cell.get((s, h))
            if r is None:
                cells.append("–")
                continue
            pct = round(100 * int(r["successes"]) / int(r["episodes"]))
            hits = int(r["collisions"])
            cells.append(f"{pct} ({hits})" if hits else f"{pct}")
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python benchmarks/stress_table.py STRESS_CSV", file=sys.stderr)
        return 2
    with Path(argv[0]).open(newline="") as handle:
        print(table(list(csv.DictReader(handle))), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
