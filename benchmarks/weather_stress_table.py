"""The weather stress sets' table (docs/guide/weather.md) from ``usvsim bench --suite stress
--json`` output, beside the same episodes in calm water (issue 38).

``table`` mode: one row per helmsman, one column per weather set: success in % [Wilson 95 %
interval] and collisions where any; with a calm-twin JSON, the calm success of the same episodes
in brackets; the last column names the sets where the helmsman falls below 95 %::

    nice usvsim bench --suite stress --sets wind-beam,gusts,sea-state-3,sea-state-4 \
        --split test --json > weather.json
    nice python benchmarks/weather_stress_table.py calm-twin > calm.json
    python benchmarks/weather_stress_table.py table weather.json calm.json

``calm-twin`` mode: the same four sets with their weather removed (the same seeds, so the same
episodes, :mod:`usvsim.task.weather_draw`'s own stream) for the same helmsmen (the baselines and
the recommended models, or ``--helmsmen a,b``), as the suite's JSON on stdout (``--episodes``,
default 100). A replaced shipped file's twin rows go into the committed file with
``benchmarks/stress_merge.py --replace-helmsmen``.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

WEATHER = ("wind-beam", "gusts", "sea-state-3", "sea-state-4")
BAR = 0.95  # the "which fall below 95 %"


def calm_twin(episodes: int, helmsmen: str = "") -> str:
    """The suite's JSON for the weather sets without their weather (module docstring);
    ``helmsmen`` as ``usvsim bench --helmsmen`` (empty: the baselines and recommended models)."""
    from usvsim.evaluation.bench import BenchArgs, loadable_helmsmen
    from usvsim.evaluation.stress import run_stress, select_sets, stress_json
    from usvsim.helm.registry import select_helmsmen

    def warn(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    names, explicit = BenchArgs(helmsmen=helmsmen).selection()
    factories, skipped = loadable_helmsmen(select_helmsmen(names), explicit, warn)
    sets = []
    for s in select_sets(list(WEATHER)):
        assert s.scenario is not None
        sets.append(replace(s, scenario=replace(s.scenario, weather=None)))
    result = run_stress(factories, sets, episodes, progress=False, skipped=skipped)
    return stress_json(result)


def _cell(row: dict[str, Any], calm: dict[str, Any] | None) -> str:
    pct = 100.0 * row["success_rate"]
    text = f"{pct:.0f} [{100 * row['success_ci95_low']:.0f}, {100 * row['success_ci95_high']:.0f}]"
    if calm is not None:
        text += f" ({100.0 * calm['success_rate']:.0f})"
    if row["collisions"]:
        text += f", {row['collisions']} coll."
    return text


def table(weather: dict[str, Any], calm: dict[str, Any] | None = None) -> str:
    """The Markdown table (module docstring) of the suite's JSON ``weather`` (and ``calm``)."""
    by = {(r["episode_set"], r["helmsman"]): r for r in weather["rows"]}
    calm_by = {(r["episode_set"], r["helmsman"]): r for r in (calm or {}).get("rows", [])}
    sets = [s for s in weather["sets"] if s in WEATHER]
    lines = [
        "| helmsman | " + " | ".join(f"`{s}`" for s in sets) + " | below 95 % |",
        "|---|" + "---|" * (len(sets) + 1),
    ]
    for h in weather["helmsmen"]:
        cells, below = [], []
        for s in sets:
            row = by.get((s, h))
            if row is None:
                cells.append("–")
                continue
            cells.append(_cell(row, calm_by.get((s, h))))
            if row["success_rate"] < BAR:
                below.append(s)
        lines.append(f"| {h} | " + " | ".join(cells) + f" | {', '.join(below) or '–'} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="mode", required=True)
    twin = sub.add_parser("calm-twin")
    twin.add_argument("--episodes", type=int, default=100)
    twin.add_argument("--helmsmen", default="", help="comma-separated; empty: the default set")
    tab = sub.add_parser("table")
    tab.add_argument("weather_json")
    tab.add_argument("calm_json", nargs="?")
    args = parser.parse_args(argv)
    if args.mode == "calm-twin":
        if args.episodes < 1:
            parser.error("--episodes must be >= 1")
        print(calm_twin(args.episodes, args.helmsmen))
        return 0
    weather = json.loads(Path(args.weather_json).read_text())
    calm = json.loads(Path(args.calm_json).read_text()) if args.calm_json else None
    print(table(weather, calm), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
