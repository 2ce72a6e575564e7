"""Reward-term ablation of the COLREG reward (issue 41): each term's effect on compliance and
success, every variant on the same setup, family, budget and seeds.

Variants (``--variants``; :data:`usvsim.task.colreg_reward.COLREG_TERMS`): ``all`` (every term,
``rl-gaussian-radar-colreg``), ``none`` (the study's reward alone on the same family:
``rl-gaussian-radar-colreg-noreward``) and ``no-<term>`` (every term but that one). Each variant
and seed is one training run (``learning.experiments.train_rl.train_rl``, its files in
``OUT/<variant>/seed<k>/``) of ``--iterations`` iterations, with no early stop (``stop_after=0``):
the same budget for all.

Selection and reporting (the honest-comparison rules, issue 37): each run's ``best.pt`` and
``latest.pt`` are scored on the COLREG suite's VALIDATION split (``--val-episodes`` per set,
inside :func:`usvsim.common.splits.selection_mode`, so a test draw there fails) and the one with
the higher validation score (success rate × compliance rate, pooled over the sets) is chosen;
only the chosen file is then scored on the TEST split (``--test-episodes`` per set) and
reported. Targets hold course and speed (as Imazu's problems are defined; ``--reactive-targets``
for vo-steered ones). Writes ``OUT/ablation.json`` and ``OUT/ablation.md`` (atomic)::

    nice python benchmarks/colreg_reward_ablation.py --iterations 300 --seeds 0,1,2 \\
        --out usvsim-results/colreg-ablation
    python benchmarks/colreg_reward_ablation.py --score-only --out usvsim-results/colreg-ablation
    # one process per run, each resumable (a cut-off run goes on from its latest.pt):
    nice python benchmarks/colreg_reward_ablation.py --train-only --variants none --seeds 1 \\
        --iterations 300 --out usvsim-results/colreg-ablation
    python benchmarks/colreg_reward_ablation.py --iterations 3 --variants all,none \\
        --val-episodes 1 --test-episodes 1 --sets imazu-01,imazu-02 --out /tmp/abl  # a smoke run
"""

from __future__ import annotations

import argparse
import json
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from learning.experiments.setups import get_setup
from learning.experiments.train_rl import train_rl
from usvsim.common.fileio import atomic_write_text
from usvsim.common.splits import selection_mode
from usvsim.evaluation.colreg_suite import run_colreg, select_colreg_sets
from usvsim.evaluation.stats import proportion
from usvsim.helm.registry import load_checkpoint_helmsman
from usvsim.task.colreg_reward import COLREG_TERMS

SETUP = "rl-gaussian-radar-colreg"
VARIANTS = ("all", "none", *(f"no-{t}" for t in COLREG_TERMS))


def variant_setup(variant: str, base: str = SETUP) -> Any:
    """The setup a variant trains: ``base`` with the COLREG terms of ``variant`` on."""
    setup = get_setup(base)
    if variant == "all":
        return setup.replace(colreg_reward="all")
    if variant == "none":
        return setup.replace(colreg_reward="")
    term = variant.removeprefix("no-")
    if not variant.startswith("no-") or term not in COLREG_TERMS:
        raise SystemExit(f"unknown variant {variant!r}; choose from {', '.join(VARIANTS)}")
    return setup.replace(colreg_reward=",".join(t for t in COLREG_TERMS if t != term))


def pooled(result: Any) -> dict[str, Any]:
    """Success and compliance of the one helmsman of a suite run, pooled over its sets (Wilson
    95 % intervals), and its collisions."""
    rows = result.rows
    s = proportion(sum(r.success.successes for r in rows), sum(r.success.n for r in rows))
    enc = sum(r.compliance.n for r in rows)
    c = proportion(sum(r.compliance.successes for r in rows), enc) if enc else None
    return {
        "episodes": s.n,
        "success_rate": s.rate,
        "success_ci95": [s.lower, s.upper],
        "encounters": enc,
        "compliance_rate": None if c is None else c.rate,
        "compliance_ci95": None if c is None else [c.lower, c.upper],
        "collisions": sum(r.collisions for r in rows),
        "per_set": [r.flat() for r in rows],
    }


def score(path: Path, args: argparse.Namespace, split: str, n: int) -> dict[str, Any]:
    """A checkpoint on the COLREG sets of ``args`` (``n`` episodes per set, ``split``)."""
    sets = select_colreg_sets([s for s in args.sets.split(",") if s])
    factory = {path.stem: partial(load_checkpoint_helmsman, str(path))}
    result = run_colreg(factory, sets, n, split=split,  # type: ignore[arg-type]
                        reactive_targets=args.reactive_targets, progress=False)  # fmt: skip
    return pooled(result)


def _value(p: dict[str, Any]) -> float:
    """The validation score that chooses: success rate × compliance rate (0 without)."""
    return float(p["success_rate"]) * float(p["compliance_rate"] or 0.0)


def choose_and_test(
    files: list[Path], args: argparse.Namespace, caller: str
) -> tuple[Path, dict[str, Any], dict[str, Any]]:
    """The file of ``files`` with the higher validation score (scored inside
    :func:`usvsim.common.splits.selection_mode`, so a test draw there fails), every file's
    validation figures, and the chosen file's test figures."""
    with selection_mode(caller):  # validation chooses: no test episode here
        val = {p.name: score(p, args, "validation", args.val_episodes) for p in files}
    chosen = max(files, key=lambda p: _value(val[p.name]))
    return chosen, val, score(chosen, args, "test", args.test_episodes)


def finished(out: Path) -> dict[str, Any] | None:
    """The ``summary.json`` of a run in ``out`` that ended by its rules (not interrupted),
    else None."""
    path = out / "summary.json"
    if not path.is_file():
        return None
    summary: dict[str, Any] = json.loads(path.read_text())
    return None if summary.get("interrupted", True) else summary


def train_one(variant: str, seed: int, args: argparse.Namespace) -> None:
    """Train one variant and seed into ``OUT/<variant>/seed<k>``: nothing where that run has
    finished, from its ``latest.pt`` where one was cut off (a session's end), else anew."""
    out = Path(args.out) / variant / f"seed{seed}"
    if finished(out) is not None:
        return
    train_rl(variant_setup(variant, args.setup), out, seed=seed, iterations=args.iterations,
             resume=(out / "latest.pt").is_file(), stop_after=0,
             validate_every=args.validate_every, time_budget_s=args.time_budget_s,
             device=args.device,
             command=f"benchmarks/colreg_reward_ablation.py {variant} seed {seed}")  # fmt: skip


SCORING = ("setup", "sets", "val_episodes", "test_episodes", "reactive_targets")


def scored_this_run(record: dict[str, Any], summary: dict[str, Any] | None) -> bool:
    """Whether a kept ``scores.json`` record is of the run now in its folder: True without a
    summary to compare (a record kept without its run) or where either lacks a wall-clock;
    otherwise the summary's wall-clock must be the one the record was scored at (a run resumed
    in a copied folder has trained on, and its kept record is stale)."""
    wall = None if summary is None else summary.get("wall_time_s")
    kept = record.get("train_wall_s")
    return wall is None or kept is None or float(kept) == float(wall)


def cached(out: Path, args: argparse.Namespace) -> dict[str, Any] | None:
    """A finished run's record from its ``scores.json`` where it was scored with these scoring
    arguments (:data:`SCORING`) and is of the run now in ``out`` (:func:`scored_this_run`),
    else None."""
    path = out / "scores.json"
    if not path.is_file():
        return None
    record: dict[str, Any] = json.loads(path.read_text())
    same = all(record.get("scoring", {}).get(k) == getattr(args, k) for k in SCORING)
    return record if same and scored_this_run(record, finished(out)) else None


def run_one(variant: str, seed: int, args: argparse.Namespace) -> dict[str, Any]:
    """Train (unless ``--score-only``), choose on validation, report on test. The record is
    kept in ``OUT/<variant>/seed<k>/scores.json`` (with ``summary.json`` a few kB): a run scored
    once is read from there, so its figures outlive its checkpoints (copy the two files to keep
    them; ``--score-only --out`` on the copies remakes the tables)."""
    out = Path(args.out) / variant / f"seed{seed}"
    setup = variant_setup(variant, args.setup)
    if not args.score_only:
        train_one(variant, seed, args)
    summary, record = finished(out), cached(out, args)
    if record is not None and summary is not None:
        return {k: v for k, v in record.items() if k != "scoring"}
    wall = None if summary is None else float(summary["wall_time_s"])  # resumed parts included
    files = [p for p in (out / "best.pt", out / "latest.pt") if p.is_file()]
    if not files:
        raise SystemExit(f"{out}: no best.pt or latest.pt (train first, without --score-only)")
    chosen, val, test = choose_and_test(files, args, "colreg_reward_ablation")
    record = {"variant": variant, "seed": seed, "colreg_reward": setup.colreg_reward,
              "train_wall_s": wall, "chosen": chosen.name, "validation": val,
              "test": test}  # fmt: skip
    if summary is not None:  # a finished run's figures are final: keep them
        scoring = {k: getattr(args, k) for k in SCORING}
        atomic_write_text(out / "scores.json", json.dumps({**record, "scoring": scoring}))
    return record


def fmt_rate(rate: float | None, ci: list[float] | None) -> str:
    if rate is None or ci is None:
        return "–"
    return f"{100 * rate:.0f} % [{100 * ci[0]:.0f}, {100 * ci[1]:.0f}]"


def across_seeds(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per variant with at least two seeds: the IQM over seeds of the test split's per-set
    success and compliance rates, with rliable's 95 % stratified-bootstrap interval over seeds
    (:func:`usvsim.evaluation.seed_stats.iqm_with_interval`); compliance over the sets where
    every seed met an encounter. Collisions summed over seeds."""
    from usvsim.evaluation.seed_stats import iqm_with_interval

    out = []
    for variant in dict.fromkeys(r["variant"] for r in runs):
        mine = [r for r in runs if r["variant"] == variant]
        if len(mine) < 2:
            continue
        collisions = sum(r["test"]["collisions"] for r in mine)
        row: dict[str, Any] = {
            "variant": variant, "seeds": [r["seed"] for r in mine], "collisions": collisions
        }  # fmt: skip
        for name in ("success_rate", "compliance_rate"):
            scores = np.array(
                [[np.nan if s[name] is None else s[name] for s in r["test"]["per_set"]]
                 for r in mine], dtype=float,
            )  # fmt: skip
            scores = scores[:, np.isfinite(scores).all(axis=0)]  # (seeds, sets)
            if scores.shape[1] == 0:
                row[name] = row[f"{name}_ci95"] = None
                continue
            point, ci = iqm_with_interval(scores)
            row[name], row[f"{name}_ci95"] = point, list(ci)
        out.append(row)
    return out


def markdown(runs: list[dict[str, Any]], args: argparse.Namespace) -> str:
    """The ablation table: one row per variant and seed, test split figures."""
    lines = [
        f"COLREG reward ablation: {args.setup}, {args.iterations} iterations per run, "
        f"test split {args.test_episodes} episodes per set (chosen on validation, "
        f"{args.val_episodes} per set)",
        "",
        "| variant | seed | terms on | file | success | compliance | collisions | train s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        t = r["test"]
        wall = "–" if r["train_wall_s"] is None else f"{r['train_wall_s']:.0f}"
        lines.append(
            f"| {r['variant']} | {r['seed']} | {r['colreg_reward'] or '(none)'} | {r['chosen']} "
            f"| {fmt_rate(t['success_rate'], t['success_ci95'])} "
            f"| {fmt_rate(t['compliance_rate'], t['compliance_ci95'])} "
            f"| {t['collisions']} | {wall} |"
        )
    summary = across_seeds(runs)
    if summary:
        lines += [
            "",
            "Across seeds (test split, IQM over seeds of the per-set rates, rliable's 95 % "
            "bootstrap interval):",
            "",
            "| variant | seeds | success | compliance | collisions |",
            "|---|---|---|---|---|",
        ]
        for r in summary:
            seeds = ",".join(str(k) for k in r["seeds"])
            lines.append(
                f"| {r['variant']} | {seeds} "
                f"| {fmt_rate(r['success_rate'], r['success_rate_ci95'])} "
                f"| {fmt_rate(r['compliance_rate'], r['compliance_rate_ci95'])} "
                f"| {r['collisions']} |"
            )
    return "\n".join(lines) + "\n"


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--setup", default=SETUP, help="the RL setup the variants change")
    ap.add_argument("--variants", default=",".join(VARIANTS), help="comma-separated")
    ap.add_argument("--seeds", default="0", help="comma-separated training seeds")
    ap.add_argument("--iterations", type=int, default=300, help="per run, no early stop")
    ap.add_argument("--validate-every", type=int, default=0, help="0: the setup's")
    ap.add_argument("--time-budget-s", type=float, default=0.0, help="per run; 0: none")
    ap.add_argument("--sets", default="", help="COLREG sets, comma-separated; empty: all")
    ap.add_argument("--val-episodes", type=int, default=5, help="per set, validation split")
    ap.add_argument("--test-episodes", type=int, default=10, help="per set, test split")
    ap.add_argument("--reactive-targets", action="store_true", help="targets steered by vo")
    ap.add_argument("--score-only", action="store_true", help="score the runs in --out")
    ap.add_argument(
        "--train-only",
        action="store_true",
        help="train (or resume) the runs, score nothing (one process per run)",
    )
    ap.add_argument("--device", default="cpu", help="cpu, torch-cpu or cuda (usvsim train's)")
    ap.add_argument("--out", default="usvsim-results/colreg-ablation")
    args = ap.parse_args(argv)
    for v in args.variants.split(","):
        variant_setup(v, args.setup)  # unknown variants fail before anything runs
    if args.iterations < 1 or args.val_episodes < 1 or args.test_episodes < 1:
        raise SystemExit("--iterations, --val-episodes and --test-episodes must be >= 1")
    if args.train_only and args.score_only:
        raise SystemExit("--train-only and --score-only: choose one")
    return args


def main(argv: list[str] | None = None) -> None:
    args = parse(argv)
    runs = []
    if args.train_only:
        for variant in args.variants.split(","):
            for seed in (int(s) for s in args.seeds.split(",")):
                train_one(variant, seed, args)
        return
    for variant in args.variants.split(","):
        for seed in (int(s) for s in args.seeds.split(",")):
            runs.append(run_one(variant, seed, args))
            print(f"{variant} seed {seed}: test {runs[-1]['test']['success_rate']:.2f} success, "
                  f"{runs[-1]['test']['compliance_rate']} compliance", flush=True)  # fmt: skip
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data = {"args": vars(args), "runs": runs, "across_seeds": across_seeds(runs)}
    atomic_write_text(out / "ablation.json", json.dumps(data, indent=1, default=str))
    atomic_write_text(out / "ablation.md", markdown(runs, args))
    print(markdown(runs, args))


if __name__ == "__main__":
    main()
