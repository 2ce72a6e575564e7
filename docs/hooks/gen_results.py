"""Result tables generated from the JSON that ``usvsim bench --helmsmen all --json`` and
``usvsim bench --suite stress --helmsmen all --json`` write (committed under ``docs/data/``), so
the pages cannot drift from the data; what each file holds (helmsmen, sets, split, run time, the
shipped helmsmen it lacks) is read from the file too (:func:`provenance`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

DATA = Path(__file__).resolve().parents[1] / "data"
STRESS_COMMAND = "usvsim bench --suite stress --helmsmen all --json > docs/data/stress.json"
BENCH_COMMAND = "usvsim bench --helmsmen all --json --no-plots > docs/data/bench.json"


def load(name: str) -> dict[str, Any]:
    """``docs/data/NAME.json``."""
    return json.loads((DATA / f"{name}.json").read_text())


def _names(names: list[str]) -> str:
    return ", ".join(f"`{n}`" for n in names)


def provenance(name: str, data: dict[str, Any]) -> str:
    """One line on what ``docs/data/NAME.json`` holds, read from the file: its helmsmen, sets
    and split, the run's wall-clock, and the helmsmen ``--helmsmen all`` runs today that the file
    lacks (added after it was written)."""
    from usvsim.helm.registry import available_helmsmen

    helmsmen = list(dict.fromkeys(r["helmsman"] for r in data["rows"]))
    missing = [h for h in available_helmsmen() if h not in helmsmen]
    if name == "stress":
        split = data.get("split")
        split = f"{split} split" if split else "test split (written before the split field)"
        what = (
            f"{len(helmsmen)} helmsmen × {len(data['sets'])} sets, "
            f"{data['episodes_per_set']} episodes per set, {split}"
        )
    else:
        sets = ", ".join(f"{k} {v}" for k, v in data["episode_sets"].items())
        what = f"{len(helmsmen)} helmsmen on the {data['scenario']} task ({sets} episodes)"
    line = f"`docs/data/{name}.json`: {what}; the run took {data['wall_s'] / 60:.0f} min."
    if data.get("interrupted"):
        line += " The run was interrupted: the file holds what it finished."
    if data.get("skipped"):
        line += f" Skipped (unreadable): {_names(list(data['skipped']))}."
    for run in data.get("merged", []):  # benchmarks/stress_merge.py: helmsmen added later
        line += (
            f" Added later from a run of {_names(run['run_helmsmen'])} "
            f"({run['wall_s'] / 60:.0f} min, `benchmarks/stress_merge.py`): "
            f"{_names(run['helmsmen'])}."
        )
    if missing:
        line += f" Not in it: {_names(missing)} (the command above adds them)."
    return line


def _pct(row: dict[str, Any]) -> str:
    return f"{100.0 * row['success_rate']:.0f}"


def _ci(row: dict[str, Any]) -> str:
    return (
        f"{100.0 * row['success_rate']:.1f} % "
        f"[{100.0 * row['success_ci95_low']:.1f}, {100.0 * row['success_ci95_high']:.1f}]"
    )


def _m(value: float | None, digits: int = 1) -> str:
    return "–" if value is None else f"{value:.{digits}f}"


def stress_summary(stress: dict[str, Any]) -> str:
    """Per helmsman: sets at ≥ 95 %, mean and worst success over the sets, the `everything` set."""
    sets = stress["sets"]
    lines = [
        f"| helmsman | sets ≥ 95 % (of {len(sets)}) | mean success | worst set | `everything` |",
        "|---|---|---|---|---|",
    ]
    summary = []
    for h in stress["helmsmen"]:
        rows = [r for r in stress["rows"] if r["helmsman"] == h]
        rates = [r["success_rate"] for r in rows]
        worst = min(rows, key=lambda r: r["success_rate"])
        every = next((r for r in rows if r["episode_set"] == "everything"), None)
        n95 = sum(rate >= 0.95 for rate in rates)
        summary.append((n95, sum(rates) / len(rates), h, worst, every))
    for n95, mean, h, worst, every in sorted(summary, key=lambda s: (-s[0], -s[1])):
        lines.append(
            f"| `{h}` | {n95} | {100.0 * mean:.1f} % | {worst['episode_set']} "
            f"{_pct(worst)} % | {_pct(every) + ' %' if every else '–'} |"
        )
    return "\n".join(lines)


def stress_table(stress: dict[str, Any]) -> str:
    """Success (%) per set and helmsman, collisions in brackets where any."""
    by = {(r["episode_set"], r["helmsman"]): r for r in stress["rows"]}
    helmsmen = stress["helmsmen"]
    lines = [
        "| set | " + " | ".join(helmsmen) + " |",
        "|---" * (len(helmsmen) + 1) + "|",
    ]
    for s in stress["sets"]:
        cells = []
        for h in helmsmen:
            r = by.get((s, h))
            if r is None:
                cells.append("–")
            else:
                cells.append(_pct(r) + (f" ({r['collisions']})" if r["collisions"] else ""))
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def seeds_section(stress: dict[str, Any], weather: dict[str, Any] | None = None) -> str:
    """Per recommended setup with across-seed figures (``usvsim/models/seeds/``,
    :mod:`usvsim.evaluation.seed_stats`): each set's IQM over seeds [95 % CI] and the seeds'
    own figures beside the shipped file's (``stress`` and the weather sets' ``weather`` JSON);
    empty where no setup has them."""
    from usvsim.evaluation.model_cards import load_cards
    from usvsim.evaluation.seed_stats import load_seed_tables

    tables, cards = load_seed_tables(), load_cards()
    rows = stress["rows"] + (weather["rows"] if weather else [])
    parts = []
    for setup, t in tables.items():
        shipped = [n for n, c in cards.items() if c.setup == setup]
        name = shipped[0] if shipped else None
        own = {r["episode_set"]: r["success_rate"] for r in rows if r["helmsman"] == name}
        seeds = " / ".join(str(s) for s in t.seeds)
        lines = [
            f"### `{setup}`",
            "",
            f"Shipped file `{name}`; {t.label} on the {t.split} split "
            f"({t.episodes_per_set} episodes per set). Seed rule: {t.rule}; it picks seed "
            f"{t.picked_seed}. Written by (the `--provenance` says how the seeds were trained):",
            "",
            f"```bash\n{t.command}\n```",
            "",
            f"| set | `{name}` (shipped) | {t.label} | seeds {seeds} |",
            "|---|---|---|---|",
        ]
        for f in t.sets:
            mine = f"{100 * own[f.name]:.0f}" if f.name in own else "–"
            each = " / ".join(f"{100 * v:.0f}" for v in f.per_seed)
            lines.append(f"| {f.name} | {mine} | {f.cell()} | {each} |")
        original = [own[f.name] for f in t.sets if f.name in own and f.name in stress["sets"]]
        mine = f"{100 * sum(original) / len(original):.1f}" if original else "–"
        each = " / ".join(f"{100 * v:.1f}" for v in t.original.per_seed)
        lines.append(f"| mean of the 22 original sets | {mine} | {t.original.cell()} | {each} |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


def bench_table(bench: dict[str, Any]) -> str:
    """The study-task table: validation and held-out rows per helmsman."""
    sets = list(bench["episode_sets"])
    by = {(r["episode_set"], r["helmsman"]): r for r in bench["rows"]}
    helmsmen = list(dict.fromkeys(r["helmsman"] for r in bench["rows"]))
    head = " | ".join(f"{s} ({bench['episode_sets'][s]}) success [95 % CI]" for s in sets)
    lines = [
        f"| helmsman | {head} | held-out min / median d_pole (m) | t_goal (s) | path (m) |",
        "|---" * (len(sets) + 4) + "|",
    ]
    last = sets[-1]
    for h in helmsmen:
        cells = [_ci(by[(s, h)]) if (s, h) in by else "–" for s in sets]
        r = by.get((last, h), {})
        lines.append(
            f"| `{h}` | " + " | ".join(cells) + " | "
            f"{_m(r.get('min_pole_distance_min_m'))} / {_m(r.get('min_pole_distance_median_m'))}"
            f" | {_m(r.get('time_to_goal_mean_s'))} | {_m(r.get('path_length_mean_m'), 0)} |"
        )
    return "\n".join(lines)


def results_page() -> str:
    """The Results page."""
    stress, bench = load("stress"), load("bench")
    return f"""# Results

Generated when this site is built from the JSON files in `docs/data/`, which the tools wrote;
nothing here is typed by hand. To reproduce them (from the repository root):

```bash
{BENCH_COMMAND}
{STRESS_COMMAND}
python benchmarks/readme_figures.py   # the README's figure from docs/data/stress.json
```

`--helmsmen all` runs every shipped helmsman; without it `usvsim bench` runs the baselines and the
recommended models only ([Helmsmen](guide/helmsmen.md)). What the committed files hold:

- {provenance("bench", bench)}
- {provenance("stress", stress)}

## The study's task

`{BENCH_COMMAND.split(" >")[0]}`: the helmsmen on the study's validation episodes and on held-out
episodes (success with a 95 % Wilson interval; distances and times on the last set, times and
paths over successful episodes). Columns: [Benchmarks](guide/benchmarks.md).

{bench_table(bench)}

## The stress suite

`{STRESS_COMMAND.split(" >")[0]}`: {stress["episodes_per_set"]} episodes per set; what each set
perturbs is on the [Benchmarks](guide/benchmarks.md) page.

### Summary per helmsman

{stress_summary(stress)}

### Success per set (%)

Collisions in brackets where any.

{stress_table(stress)}

![Stress-suite heat map and one episode](assets/readme-figure.png)

### Across seeds

Recommended setups trained with several seeds (issue 37): per set, the interquartile mean over
seeds of each seed's `best.pt` with rliable's 95 % stratified-bootstrap interval, beside the
shipped file's own figure (from `docs/data/stress.json` and `docs/data/stress-weather.json`).
`usvsim bench --suite stress` and `usvsim models` show the same columns; setups not listed have
one seed.

{seeds_section(stress, load("stress-weather"))}
"""


def models_page() -> str:
    """``models.md``: every shipped model's card (``usvsim models --json``, rendered by
    :func:`usvsim.evaluation.model_cards.cards_markdown`) with its setup's across-seed figures."""
    from usvsim.evaluation.model_cards import cards_markdown, load_cards
    from usvsim.evaluation.seed_stats import load_seed_tables

    return cards_markdown(load_cards(), load_seed_tables())


def model_zoo() -> str:
    """The shipped models (``usvsim/models/models.json`` and their cards): how each was trained
    and scored, under its name and the name it was published under before."""
    from usvsim.evaluation.model_cards import load_cards

    root = Path(__file__).resolve().parents[2]
    models = json.loads((root / "usvsim" / "models" / "models.json").read_text())["models"]
    cards = load_cards()
    lines = [
        "| model | former name | trained by | observation | action | held-out success "
        "| training run | command |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in sorted(models):
        m, card = models[name], cards[name]
        algo = "GAIL (IL)" if card.family == "IL" else "TRPO (RL)"
        if "gail-trpo" in name:
            algo = "GAIL, then TRPO"
        heldout = m.get("evaluation", {}).get("held-out", {})
        ok = f"{heldout['successes']}/{heldout['episodes']}" if heldout else "–"
        summary = m.get("summary", {})
        run = (
            f"{summary['iterations']} it, {summary['wall_time_s']:.0f} s"
            if "iterations" in summary and "wall_time_s" in summary
            else "–"
        )
        command = m.get("command", "–")
        former = ", ".join(f"`{n}`" for n in card.former_names)
        lines.append(
            f"| `{name}` | {former} | {algo} | {card.observation} | {card.action} | {ok} | {run} "
            f"| `{command}` |"
        )
    return "\n".join(lines)


def training_times() -> str:
    """Expected wall-clock per setup: the shipped run's first 15/15 and its whole run
    (``models.json``; one torch thread on the 2-core CI machine)."""
    root = Path(__file__).resolve().parents[2]
    models = json.loads((root / "usvsim" / "models" / "models.json").read_text())["models"]
    lines = [
        "| setup | first 15/15: iteration, wall-clock | whole run: iterations, wall-clock |",
        "|---|---|---|",
    ]
    for name in sorted(models, key=lambda n: models[n]["setup"]):
        summary = models[name].get("summary", {})
        first = summary.get("first_15_of_15") or {}
        first_text = (
            f"{first['iteration']}, {first['wall_time_s']:.0f} s"
            if "iteration" in first and "wall_time_s" in first
            else "–"
        )
        whole = (
            f"{summary['iterations']}, {summary['wall_time_s']:.0f} s"
            if "iterations" in summary and "wall_time_s" in summary
            else "–"
        )
        lines.append(f"| `{models[name]['setup']}` | {first_text} | {whole} |")
    return "\n".join(lines)
