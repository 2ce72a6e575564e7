"""Training wall-clock benchmark of the four IL setups (GAIL), as ``train_rl.py`` for RL.

For each setup this runs the recorded training command (``usvsim train SETUP --seed S``, the
setup's defaults otherwise; :mod:`learning.cli.train`, :mod:`learning.experiments.il_setups`) on
this machine's CPU with ``--threads`` torch threads, then evaluates the run's ``best.pt`` on the
15 validation and 200 held-out episodes (:mod:`learning.cli.evaluate`) and for expert-likeness on
the validation starts (:mod:`usvsim.evaluation.likeness`), and writes ``train_il.md`` (a Markdown
table) and ``train_il.json`` (everything, with each run's ``summary.json``) into ``--out``::

    python benchmarks/train_il.py                       # all four setups (run as a script)
    python benchmarks/train_il.py --setups il-gaussian-positional --out /tmp/bench
    python benchmarks/train_il.py --iterations 20       # a short budget for every setup
    python benchmarks/train_il.py --finished --ship     # ship the runs already in --out

Reported per setup: wall-clock, environment steps and iterations to the FIRST validation with
at least 14/15 successes and to the first 15/15 (validation time included; behavioural cloning
included), the best validation (most successes, then most expert-like path; what ``best.pt``
holds) and when it came, the study's best success and iterations to it (Table 4.1,
``shared/reference/table-4-1.md``), the whole run (it stops after ``--stop-after`` consecutive
15/15, or at its iteration budget), where an iteration's time went (rollout / batch / policy
step / critic / discriminator, mean s; ``train_rl.time_split``) and ``best.pt``'s validation,
held-out and likeness results. ``--ship`` writes slim copies of the ``best.pt`` files to
``usvsim/models/<setup>.pt`` (float16 weights for the radar CNN, as for RL), evaluates those,
and records them in ``usvsim/models/models.json`` and the IL table of
``usvsim/models/README.md``.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

from train_rl import (  # this folder
    MODELS_DIR,
    evaluate_checkpoint,
    merge_models_json,
    model_path,
    replace_readme_section,
    run_options,
    split_cell,
    time_split,
    write_results,
)

from learning.cli.train import TrainArgs, run
from learning.experiments.checkpoint import (
    load_checkpoint,
    load_helmsman,
    save_checkpoint,
    slim_copy,
)
from learning.experiments.il_setups import IL_SETUPS
from learning.experiments.run_log import VALIDATION_EPISODES
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.likeness import helmsman_likeness


def train_one(args: TrainArgs) -> dict[str, Any]:
    """Run the training command ``args`` (into ``args.out``); returns its ``summary.json``."""
    if run(args) != 0:
        raise SystemExit(f"training {args.setup} failed (see above)")
    summary: dict[str, Any] = json.loads((Path(args.out) / "summary.json").read_text())
    return summary


def likeness_of(path: Path) -> dict[str, Any]:
    """Expert-likeness of the checkpoint at ``path`` on the 15 validation starts."""
    h = load_helmsman(path)
    return dataclasses.asdict(helmsman_likeness(h, observation=h.observation, action=h.action))


def _when(record: dict[str, Any] | None) -> str:
    """``wall-clock | env steps | iterations`` cells of a validation record."""
    if record is None:
        return "not reached | - | -"
    return f"{record['wall_time_s']:.0f} s | {record['env_steps']:,} | {record['iteration']}"


def markdown_table(results: list[dict[str, Any]]) -> str:
    head = (
        "| setup | first >= 14/15: wall-clock | env steps | iterations "
        "| first 15/15: wall-clock | env steps | iterations "
        "| best validation | at: wall-clock | env steps | iterations "
        "| study: best / iterations | run: iterations / wall-clock | stopped "
        "| s per iteration: rollout / batch / policy / critic / discriminator "
        "| best.pt: validation | held-out (200) | min d_pole m (min / median, held-out) "
        "| path to expert m | side agreement | heading-change W1 deg |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for r in results:
        s, like = r["summary"], r["likeness"]
        val, held = r["evaluation"]["validation"], r["evaluation"]["held-out"]
        best = s["best"] or {"successes": 0}
        study = round(s["study_success"] * VALIDATION_EPISODES)
        study_cell = (
            f"{study}/15 ({100 * s['study_success']:.1f} %) / ~{s['study_iterations']}"
            if s["study_iterations"]
            else "—"  # a setup the study did not have (the -ow ones)
        )
        lines.append(
            f"| {r['setup']} | {_when(s['first_14_of_15'])} | {_when(s['first_15_of_15'])} "
            f"| {best['successes']}/15 | {_when(s['best'])} "
            f"| {study_cell} "
            f"| {s['iterations']} / {s['wall_time_s']:.0f} s | {s['stop_reason']} "
            f"| {split_cell(r)} "
            f"| {val['successes']}/15 | {held['successes']}/200 "
            f"({100 * held['success_rate']:.1f} %) "
            f"| {held['min_pole_distance_m']:.1f} / {held['median_pole_distance_m']:.1f} "
            f"| {like['path_distance_m']:.1f} | {like['side_agreement']:.2f} "
            f"| {like['action_distance_deg']:.1f} |"
        )
    return head + "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = run_options(
        __doc__.splitlines()[0], list(IL_SETUPS), "usvsim-results/bench-train-il", threads=1
    )
    parser.add_argument("--iterations", type=int, default=0, help="budget; 0: setup default")
    parser.add_argument("--ship", action="store_true", help="copy the models to usvsim/models")
    parser.add_argument(
        "--finished",
        action="store_true",
        help="do not train: evaluate (and --ship) the finished runs in --out (their summary.json)",
    )
    args = parser.parse_args(argv)
    out = Path(args.out)
    results = []
    for name in args.setups:
        run_dir = out / name
        train_args = TrainArgs(
            setup=name,
            seed=args.seed,
            iterations=args.iterations,
            stop_after=args.stop_after,
            out=str(run_dir),
            resume=args.resume,
            time_budget_s=args.time_budget_s,
            threads=args.threads,
        )
        if args.finished:
            summary = json.loads((run_dir / "summary.json").read_text())
        else:
            summary = train_one(train_args)
        best = run_dir / "best.pt"
        if args.ship:
            radar = IL_SETUPS[name].observation.startswith("radar")
            target = model_path(name)  # the setup's shipped file, by its former name
            save_checkpoint(slim_copy(load_checkpoint(best), half=radar), target)
            best = target
        results.append(
            {
                "setup": name,
                "command": summary["command"],
                "checkpoint": str(best),
                "summary": summary,
                "time_split": time_split(run_dir),
                "evaluation": evaluate_checkpoint(best),
                "likeness": likeness_of(best),
            }
        )
        print(markdown_table(results[-1:]), flush=True)
    table = markdown_table(results)
    machine = write_results(out, "train_il", table, args.threads, results)
    if args.ship:
        merged = merge_models_json(results, machine)
        atomic_write_text(MODELS_DIR / "models.json", json.dumps(merged, indent=2) + "\n")
        il = [m for m in merged["models"].values() if m["setup"].startswith("il-")]
        replace_readme_section("il-table", "train_il.py", markdown_table(il), il)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
