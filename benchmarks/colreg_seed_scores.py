"""Trained seeds of traffic setups against the classical radar helmsmen on the COLREG suite
(issue 41): the same selection and report as the reward ablation, for any run folders.

Each run folder (``--runs LABEL=DIR,DIR,...``, one folder per seed, a finished ``usvsim train``
run: ``summary.json``, ``best.pt``, ``latest.pt``) is scored as
``benchmarks/colreg_reward_ablation.py`` scores its runs: ``best.pt`` and ``latest.pt`` on the
COLREG suite's VALIDATION split, the one with the higher pooled success × compliance chosen,
only it scored on the TEST split. The record is kept in ``DIR/scores.json`` (the ablation's
format: a folder the ablation scored is read, not scored again, and a kept record in a folder
without checkpoints is enough; a record whose training wall-clock is not the folder's
``summary.json``'s, a run resumed after it was scored, is scored again). The classical
helmsmen of ``--baselines`` run on the same test episodes. Writes ``OUT/seeds.json`` and
``OUT/seeds.md`` (atomic):

- one row per seed, and per label the IQM over seeds of the per-set rates with rliable's 95 %
  interval (``colreg_reward_ablation.across_seeds``);
- per set, each label's seeds pooled (Wilson 95 %) beside each baseline, and the sets where a
  label beats every baseline on success or compliance by a margin outside both intervals::

    python benchmarks/colreg_seed_scores.py \\
        --runs il-radar=/work/runs/il-colreg/seed0,/work/runs/il-colreg/seed1 \\
        --runs rl-radar=benchmarks/data/colreg-ablation/all/seed0 \\
        --baselines vo-radar,sb-mpc-radar --out benchmarks/data/colreg-seeds
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the ablation's scoring, shared

from colreg_reward_ablation import (
    across_seeds,
    choose_and_test,
    finished,
    fmt_rate,
    pooled,
    scored_this_run,
)

from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.colreg_suite import run_colreg, select_colreg_sets
from usvsim.evaluation.stats import proportion
from usvsim.helm.registry import select_helmsmen

SCORING = ("sets", "val_episodes", "test_episodes", "reactive_targets")


def _same_scoring(record: dict[str, Any], args: argparse.Namespace) -> bool:
    kept = record.get("scoring", {})
    return all(kept.get(k) == getattr(args, k) for k in SCORING)


def seed_record(label: str, run: Path, args: argparse.Namespace) -> dict[str, Any]:
    """One seed's record: kept in ``run/scores.json``, or chosen on validation and scored on
    test now (a finished run only)."""
    kept = run / "scores.json"
    summary = finished(run)
    if kept.is_file():
        record: dict[str, Any] = json.loads(kept.read_text())
        if _same_scoring(record, args) and scored_this_run(record, summary):
            setup = record.get("setup") or (summary or {}).get("setup", "")  # ablation records
            kept_record = {k: v for k, v in record.items() if k != "scoring"}
            return {**kept_record, "variant": label, "setup": setup}
    if summary is None:
        raise SystemExit(f"{run}: not a finished run (summary.json with interrupted: false)")
    files = [p for p in (run / "best.pt", run / "latest.pt") if p.is_file()]
    if not files:
        raise SystemExit(
            f"{run}: no best.pt or latest.pt, and no scores.json kept with this scoring"
        )
    chosen, val, test = choose_and_test(files, args, "colreg_seed_scores")
    record = {"variant": label, "seed": int(summary["seed"]), "setup": summary["setup"],
              "colreg_reward": summary.get("colreg_reward", ""),
              "train_wall_s": float(summary["wall_time_s"]), "chosen": chosen.name,
              "validation": val, "test": test}  # fmt: skip
    scoring = {k: getattr(args, k) for k in SCORING}
    atomic_write_text(kept, json.dumps({**record, "scoring": scoring}))
    return record


def baseline_records(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """Each classical helmsman of ``--baselines`` on the test split (kept in
    ``OUT/baselines.json`` for the same scoring)."""
    names = [n for n in args.baselines.split(",") if n]
    path = Path(args.out) / "baselines.json"
    kept: dict[str, Any] = json.loads(path.read_text()) if path.is_file() else {}
    if kept.get("scoring") == {k: getattr(args, k) for k in SCORING} and set(names) <= set(
        kept.get("helmsmen", {})
    ):
        return {n: kept["helmsmen"][n] for n in names}
    if not names:
        return {}
    sets = select_colreg_sets([s for s in args.sets.split(",") if s])
    result = run_colreg(select_helmsmen(names), sets, args.test_episodes, split="test",
                        reactive_targets=args.reactive_targets, progress=False)  # fmt: skip
    records = {}
    for name in names:
        mine = [r for r in result.rows if r.helmsman == name]
        records[name] = pooled(SimpleNamespace(rows=mine))
    scoring = {k: getattr(args, k) for k in SCORING}
    atomic_write_text(path, json.dumps({"scoring": scoring, "helmsmen": records}))
    return records


def _counts(per_set: list[dict[str, Any]], name: str) -> dict[str, Any]:
    """The flat row of set ``name``."""
    return next(r for r in per_set if r["episode_set"] == name)


def per_set_comparison(
    runs: list[dict[str, Any]], baselines: dict[str, dict[str, Any]]
) -> list[dict[str, Any]]:
    """Per set: each label's seeds pooled and each baseline, success and compliance with Wilson
    95 % intervals; ``beats`` lists the (label, figure) pairs whose lower bound is above every
    baseline's upper bound."""
    sets = [r["episode_set"] for r in runs[0]["test"]["per_set"]] if runs else []
    labels = list(dict.fromkeys(r["variant"] for r in runs))
    table = []
    for name in sets:
        entry: dict[str, Any] = {"set": name, "rows": {}, "beats": []}
        for label in labels:
            rows = [_counts(r["test"]["per_set"], name) for r in runs if r["variant"] == label]
            entry["rows"][label] = _pool(rows)
        for base, rec in baselines.items():
            entry["rows"][base] = _pool([_counts(rec["per_set"], name)])
        for label in labels:
            for fig in ("success", "compliance"):
                low = entry["rows"][label][fig]
                if low is None or not baselines:
                    continue
                ups = [entry["rows"][b][fig] for b in baselines]
                if all(u is not None and low[1] > u[2] for u in ups):
                    entry["beats"].append([label, fig])
        table.append(entry)
    return table


def _pool(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """[rate, low, high] of success and compliance over ``rows`` (per-set flat rows)."""
    s = proportion(sum(r["successes"] for r in rows), sum(r["episodes"] for r in rows))
    enc = sum(r["encounters"] for r in rows)
    c = proportion(sum(r["compliant"] for r in rows), enc) if enc else None
    return {
        "success": [s.rate, s.lower, s.upper],
        "compliance": None if c is None else [c.rate, c.lower, c.upper],
        "collisions": sum(r["collisions"] for r in rows),
    }


def _cell(v: list[float] | None) -> str:
    return "–" if v is None else fmt_rate(v[0], v[1:])


def markdown(data: dict[str, Any]) -> str:
    a = data["args"]
    lines = [
        f"COLREG suite, test split {a['test_episodes']} episodes per set (each seed's file chosen "
        f"on the validation split, {a['val_episodes']} per set)",
        "",
        "| label | seed | setup | file | success | compliance | collisions | train s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in data["runs"]:
        t = r["test"]
        lines.append(
            f"| {r['variant']} | {r['seed']} | {r.get('setup', '')} | {r['chosen']} "
            f"| {fmt_rate(t['success_rate'], t['success_ci95'])} "
            f"| {fmt_rate(t['compliance_rate'], t['compliance_ci95'])} | {t['collisions']} "
            f"| {r['train_wall_s']:.0f} |"
        )
    for name, t in data["baselines"].items():
        lines.append(
            f"| `{name}` | – | baseline | – | {fmt_rate(t['success_rate'], t['success_ci95'])} "
            f"| {fmt_rate(t['compliance_rate'], t['compliance_ci95'])} | {t['collisions']} | – |"
        )
    if data["across_seeds"]:
        lines += [
            "",
            "Across seeds (IQM of the per-set rates, rliable's 95 % interval; then every episode "
            "and encounter of the seeds pooled, Wilson 95 %, as the baselines' rows above):",
            "",
            "| label | seeds | success IQM | compliance IQM | success pooled "
            "| compliance pooled | collisions |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in data["across_seeds"]:
            rows = [row for run in data["runs"] if run["variant"] == r["variant"]
                    for row in run["test"]["per_set"]]  # fmt: skip
            pooled_rows = _pool(rows)
            lines.append(
                f"| {r['variant']} | {','.join(str(k) for k in r['seeds'])} "
                f"| {fmt_rate(r['success_rate'], r['success_rate_ci95'])} "
                f"| {fmt_rate(r['compliance_rate'], r['compliance_rate_ci95'])} "
                f"| {_cell(pooled_rows['success'])} | {_cell(pooled_rows['compliance'])} "
                f"| {r['collisions']} |"
            )
    table = data["per_set"]
    if table:
        cols = list(table[0]["rows"])
        lines += ["", "Per set, success / compliance (seeds pooled, Wilson 95 %):", "",
                  "| set | " + " | ".join(cols) + " | beats every baseline |",
                  "|---|" + "---|" * (len(cols) + 1)]  # fmt: skip
        for e in table:
            cells = [f"{_cell(e['rows'][c]['success'])} / {_cell(e['rows'][c]['compliance'])}"
                     for c in cols]  # fmt: skip
            beats = ", ".join(f"{lab} ({fig})" for lab, fig in e["beats"]) or "–"
            lines.append(f"| {e['set']} | " + " | ".join(cells) + f" | {beats} |")
    return "\n".join(lines) + "\n"


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", action="append", default=[], help="LABEL=DIR,DIR,... (repeat)")
    ap.add_argument("--baselines", default="vo-radar,sb-mpc-radar", help="comma-separated")
    ap.add_argument("--sets", default="", help="COLREG sets, comma-separated; empty: all")
    ap.add_argument("--val-episodes", type=int, default=5, help="per set, validation split")
    ap.add_argument("--test-episodes", type=int, default=10, help="per set, test split")
    ap.add_argument("--reactive-targets", action="store_true", help="targets steered by vo")
    ap.add_argument("--out", default="usvsim-results/colreg-seeds")
    args = ap.parse_args(argv)
    if not args.runs or any("=" not in r for r in args.runs):
        ap.error("--runs LABEL=DIR,DIR,... is required (at least one)")
    if args.val_episodes < 1 or args.test_episodes < 1:
        ap.error("--val-episodes and --test-episodes must be >= 1")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse(argv)
    runs = []
    for spec in args.runs:
        label, dirs = spec.split("=", 1)
        for d in (Path(x) for x in dirs.split(",") if x):
            runs.append(seed_record(label, d, args))
            t = runs[-1]["test"]
            print(f"{label} {d}: test success {t['success_rate']:.2f}, "
                  f"compliance {t['compliance_rate']}", flush=True)  # fmt: skip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    baselines = baseline_records(args)
    data = {
        "args": vars(args),
        "runs": runs,
        "baselines": baselines,
        "across_seeds": across_seeds(runs),
        "per_set": per_set_comparison(runs, baselines),
    }
    atomic_write_text(out / "seeds.json", json.dumps(data, indent=1, default=str))
    atomic_write_text(out / "seeds.md", markdown(data))
    print(markdown(data))


if __name__ == "__main__":
    main()
