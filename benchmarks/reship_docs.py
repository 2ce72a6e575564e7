"""Rewrite the guide tables that show one shipped model's stress rows, after
``benchmarks/reship.sh`` merged the model's new rows into ``docs/data/`` (a shipped file replaced
by another seed's: same name, new weights). Run from the repository root::

    python benchmarks/reship_docs.py radar-categorical-trpo-openwater-continued

What it rewrites, each from the committed data only:

- ``docs/guide/tracker.md``: the model's column of the learned radar models' success table
  (``docs/data/stress.json``) and its row of the comparison with ``vo-radar`` (the stress and
  weather sets' files, :func:`tracker_quality.compare_stress`), where the model is in them;
- ``docs/guide/weather.md``: the weather sets' table (``weather_stress_table.py table`` of
  ``docs/data/stress-weather.json`` and its calm twin).

The prose around the tables names figures too: read it after the run (``git diff``). Each file is
written atomically; a table it cannot find is one line on stderr and exit status 1.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "docs" / "data"
TRACKER = ROOT / "docs" / "guide" / "tracker.md"
WEATHER = ROOT / "docs" / "guide" / "weather.md"
SUCCESS_HEADER = "| set | vo-radar |"  # the learned radar models' success table in tracker.md
COMPARE_HEADER = "| helmsman | better than vo-radar | worse than vo-radar |"
WEATHER_HEADER = "| helmsman | `wind-beam` |"


def _script(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _table(lines: list[str], header: str) -> tuple[int, int]:
    """(first, end) line indices of the Markdown table whose header line starts with
    ``header``; ``SystemExit`` if none."""
    for i, line in enumerate(lines):
        if line.startswith(header):
            end = i
            while end < len(lines) and lines[end].startswith("|"):
                end += 1
            return i, end
    raise SystemExit(f"reship_docs: no table starting {header!r}")


def set_column(text: str, header: str, column: str, values: dict[str, str]) -> str:
    """``text`` with the cells of ``column`` (a header cell) of the table starting ``header``
    set from ``values`` (first cell -> value); rows without a value keep theirs."""
    lines = text.split("\n")
    first, end = _table(lines, header)
    names = _cells(lines[first])
    if column not in names:
        return text
    k = names.index(column)
    for i in range(first + 2, end):
        cells = _cells(lines[i])
        if cells[0] in values:
            cells[k] = values[cells[0]]
            lines[i] = "| " + " | ".join(cells) + " |"
    return "\n".join(lines)


def set_row(text: str, header: str, row: str) -> str:
    """``text`` with the row of the table starting ``header`` whose first cell is ``row``'s
    replaced by ``row`` (left as it is where the table has no such row)."""
    lines = text.split("\n")
    first, end = _table(lines, header)
    key = _cells(row)[0]
    for i in range(first + 2, end):
        if _cells(lines[i])[0] == key:
            lines[i] = row
    return "\n".join(lines)


def set_table(text: str, header: str, table: str) -> str:
    """``text`` with the whole table starting ``header`` replaced by ``table``."""
    lines = text.split("\n")
    first, end = _table(lines, header)
    return "\n".join(lines[:first] + table.rstrip("\n").split("\n") + lines[end:])


def _load(name: str) -> dict[str, Any]:
    return json.loads((DATA / f"{name}.json").read_text())


def tracker_text(text: str, model: str) -> str:
    """tracker.md's text with ``model``'s success column and comparison row from the data."""
    stress = _load("stress")
    success = {
        r["episode_set"]: f"{100 * r['success_rate']:.0f}"
        for r in stress["rows"]
        if r["helmsman"] == model
    }
    text = set_column(text, SUCCESS_HEADER, model, success)
    paths = [str(DATA / "stress.json"), str(DATA / "stress-weather.json")]
    compared = _script("tracker_quality").compare_stress(paths, "vo-radar")
    rows = [line for line in compared.split("\n") if line.startswith(f"| {model} |")]
    return set_row(text, COMPARE_HEADER, rows[0]) if rows else text


def weather_text(text: str) -> str:
    """weather.md's text with the weather sets' table made again from the data."""
    weather, calm = _load("stress-weather"), _load("stress-weather-calm")
    table = _script("weather_stress_table").table(weather, calm)
    return set_table(text, WEATHER_HEADER, table)


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python benchmarks/reship_docs.py MODEL", file=sys.stderr)
        return 2
    from usvsim.common.fileio import atomic_write_text

    try:
        for path, make in ((TRACKER, lambda t: tracker_text(t, argv[0])), (WEATHER, weather_text)):
            old = path.read_text()
            new = make(old)
            if new != old:
                atomic_write_text(path, new)
                print(f"rewrote {path.relative_to(ROOT)}")
    except SystemExit as err:
        print(err, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
