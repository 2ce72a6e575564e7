"""Training wall-clock benchmark of the four RL setups (issue 5), and the shipped models.

For each setup this runs the recorded training command (``usvsim train SETUP --seed S``, the
setup's defaults otherwise; :mod:`learning.cli.train`) on this machine's CPU with
``--threads`` torch threads, then evaluates the run's ``best.pt`` on the 15 validation and 200
held-out episodes (:mod:`learning.cli.evaluate`) and writes a Markdown table::

    python benchmarks/train_rl.py                       # all four setups
    python benchmarks/train_rl.py --setups rl-gaussian-positional --out /tmp/bench
    python benchmarks/train_rl.py --ship                # also copy the models to usvsim/models
    python benchmarks/train_rl.py --ship-only --setups S --out DIR  # ship the ended run DIR/S

Reported per setup: wall-clock, environment steps and iterations to the FIRST 15/15 validation
(validation time included), the study's iterations to its best validation (Table 4.1,
``shared/reference/table-4-1.md``), the whole run (it stops after ``--stop-after`` consecutive
15/15), where an iteration's time went (mean s of ``log.csv``'s time columns: rollout / batch /
policy step / critic, :func:`time_split`), and the shipped checkpoint's validation / held-out
results. ``--ship`` writes slim
copies (policy + normaliser; float16 weights for the radar CNN, see :func:`slim_copy`) to
``usvsim/models/<setup>.pt`` and records everything in ``usvsim/models/models.json`` and the
table in ``usvsim/models/README.md``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import sys
from pathlib import Path
from typing import Any

import torch

from learning.algorithms.loop import TIME_FIELDS
from learning.cli.evaluate import evaluation_row
from learning.cli.train import TrainArgs, run
from learning.experiments.checkpoint import (
    PolicyHelmsman,
    load_agent,
    load_checkpoint,
    save_checkpoint,
    slim_copy,
)
from learning.experiments.memory_start import setup_goal_mark
from learning.experiments.setups import SETUPS, get_setup
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.episodes import evaluate, heldout_episodes, validation_episodes

MODELS_DIR = Path(__file__).resolve().parent.parent / "usvsim" / "models"


def model_path(setup: str) -> Path:
    """The shipped file of ``setup`` (found by its former name), in :data:`MODELS_DIR`."""
    from usvsim.helm.registry import model_path as shipped

    return shipped(setup, MODELS_DIR)


def train_one(
    name: str,
    seed: int,
    out: Path,
    threads: int,
    stop_after: int,
    budget_s: float,
    resume: bool = False,
) -> dict[str, Any]:
    """Run the recorded command for ``name`` into ``out``; returns its ``summary.json``."""
    args = TrainArgs(
        setup=name,
        seed=seed,
        out=str(out),
        threads=threads,
        stop_after=stop_after,
        time_budget_s=budget_s,
        resume=resume,
    )
    if run(args) != 0:
        raise SystemExit(f"training {name} failed (see above)")
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text())
    return summary


def evaluate_checkpoint(path: Path) -> dict[str, Any]:
    """Validation and held-out rows (:func:`evaluation_row`) of the checkpoint at ``path``."""
    ckpt = load_checkpoint(path)
    h = PolicyHelmsman(
        load_agent(ckpt, path), ckpt.observation, ckpt.action,
        goal_mark=setup_goal_mark(ckpt.setup_params),
    )  # fmt: skip
    kinds = {"observation": ckpt.observation, "action": ckpt.action}
    return {
        "validation": evaluation_row("validation", evaluate(h, validation_episodes(), **kinds)),
        "held-out": evaluation_row("held-out", evaluate(h, heldout_episodes(), **kinds)),
    }


def time_split(run_dir: Path) -> dict[str, float]:
    """Mean s per iteration of each time column of ``run_dir/log.csv`` that the run has
    (:data:`learning.algorithms.loop.TIME_FIELDS`)."""
    if not (run_dir / "log.csv").is_file():
        return {}
    with (run_dir / "log.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    fields = [f for f in TIME_FIELDS if rows and rows[0].get(f)]
    return {f: round(sum(float(r[f]) for r in rows) / len(rows), 3) for f in fields}


def split_cell(result: dict[str, Any]) -> str:
    """``rollout / batch / policy / critic [/ discriminator]`` s per iteration, or —."""
    split = result.get("time_split")
    return " / ".join(f"{v:.2f}" for v in split.values()) if split else "—"


def study_cell(result: dict[str, Any]) -> str:
    """The study's iterations to its best validation, or — for a setup the study did not have."""
    iterations = result["summary"]["study_iterations"]
    return f"~{iterations}" if iterations else "—"


def markdown_table(results: list[dict[str, Any]]) -> str:
    head = (
        "| setup | first 15/15: wall-clock | env steps | iterations | study iterations "
        "| run: iterations / wall-clock | s per iteration: rollout / batch / policy / critic "
        "| validation | held-out (200) | min d_pole m (min / median, held-out) |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for r in results:
        first = r["summary"]["first_15_of_15"]
        val, held = r["evaluation"]["validation"], r["evaluation"]["held-out"]
        if first is None:
            f_wall, f_steps, f_it = "not reached", "-", "-"
        else:
            f_wall = f"{first['wall_time_s']:.0f} s"
            f_steps, f_it = f"{first['env_steps']:,}", str(first["iteration"])
        lines.append(
            f"| {r['setup']} | {f_wall} | {f_steps} | {f_it} | {study_cell(r)} "
            f"| {r['summary']['iterations']} / {r['summary']['wall_time_s']:.0f} s "
            f"| {split_cell(r)} | {val['successes']}/15 | {held['successes']}/200 "
            f"({100 * held['success_rate']:.1f} %) "
            f"| {held['min_pole_distance_m']:.1f} / {held['median_pole_distance_m']:.1f} |"
        )
    return head + "\n".join(lines) + "\n"


def run_options(
    description: str, setups: list[str], out: str, threads: int
) -> argparse.ArgumentParser:
    """The options of a training benchmark (this one and ``train_il.py``)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--setups", nargs="+", default=setups, help="setups to train")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=threads, help="torch CPU threads")
    parser.add_argument("--stop-after", type=int, default=3, help="consecutive 15/15 to stop")
    parser.add_argument("--resume", action="store_true", help="continue the runs in --out")
    parser.add_argument("--time-budget-s", type=float, default=0.0, help="per setup; 0: none")
    parser.add_argument("--out", default=out, help="output folder")
    return parser


def write_results(
    out: Path, name: str, table: str, threads: int, results: list[dict[str, Any]]
) -> dict[str, Any]:
    """``<name>.md`` (the table) and ``<name>.json`` (this machine and ``results``) in ``out``;
    returns the machine's description."""
    machine = {
        "cpu_count": os.cpu_count(),
        "torch_threads": threads,
        "torch": torch.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    atomic_write_text(out / f"{name}.md", table)
    atomic_write_text(
        out / f"{name}.json", json.dumps({"machine": machine, "results": results}, indent=2)
    )
    return machine


def main(argv: list[str] | None = None) -> int:
    parser = run_options(
        __doc__.splitlines()[0], list(SETUPS), "usvsim-results/bench-train", threads=2
    )
    parser.add_argument("--ship", action="store_true", help="copy the models to usvsim/models")
    parser.add_argument(
        "--ship-only",
        action="store_true",
        help="ship the ended runs in --out as they are (their summary.json), training nothing",
    )
    args = parser.parse_args(argv)
    args.ship = args.ship or args.ship_only
    out = Path(args.out)
    results = []
    for name in args.setups:
        setup = get_setup(name)
        run_dir = out / name
        if args.ship_only:
            summary = json.loads((run_dir / "summary.json").read_text())
        else:
            summary = train_one(
                name, args.seed, run_dir, args.threads, args.stop_after, args.time_budget_s,
                args.resume,
            )  # fmt: skip
        source = run_dir / "best.pt"
        if args.ship:
            ckpt = slim_copy(load_checkpoint(source), half=setup.observation.startswith("radar"))
            target = model_path(name)  # the setup's shipped file, by its former name
            save_checkpoint(ckpt, target)
            source = target
        evaluation = evaluate_checkpoint(source)
        results.append(
            {
                "setup": name,
                "command": summary["command"],
                "checkpoint": str(source),
                "checkpoint_bytes": source.stat().st_size,
                "summary": summary,
                "time_split": time_split(run_dir),
                "evaluation": evaluation,
            }
        )
        print(markdown_table(results[-1:]), flush=True)
    table = markdown_table(results)
    machine = write_results(out, "train_rl", table, args.threads, results)
    if args.ship:
        merged = merge_models_json(results, machine)
        atomic_write_text(MODELS_DIR / "models.json", json.dumps(merged, indent=2) + "\n")
        write_readme_table([m for m in merged["models"].values() if m["setup"].startswith("rl-")])
    print(table)
    return 0


def write_readme_table(results: list[dict[str, Any]]) -> None:
    """Replace the RL table in ``usvsim/models/README.md`` (between its ``rl-table`` markers)."""
    replace_readme_section("rl-table", "train_rl.py", markdown_table(results), results)


def replace_readme_section(
    marker: str, script: str, table: str, results: list[dict[str, Any]]
) -> None:
    """Put ``table`` and the commands of ``results`` between the ``marker`` comments of
    ``usvsim/models/README.md``."""
    path = MODELS_DIR / "README.md"
    text = path.read_text()
    start, end = f"<!-- {marker}: written by benchmarks/{script} --ship -->", f"<!-- /{marker} -->"
    i, j = text.index(start) + len(start), text.index(end)
    commands = "\n".join(f"- `{r['setup']}`: `{r['command']}`" for r in results)
    body = f"\n{table}\nCommands (`--seed` when not 0):\n\n{commands}\n"
    atomic_write_text(path, text[:i] + body + text[j:])


def merge_models_json(results: list[dict[str, Any]], machine: dict[str, Any]) -> dict[str, Any]:
    """``models.json`` with the entries of ``results`` replacing those of the same setup; an
    entry's model card is kept (``usvsim models`` then names the fields the new file changed)."""
    path = MODELS_DIR / "models.json"
    models: dict[str, Any] = json.loads(path.read_text())["models"] if path.is_file() else {}
    for r in results:
        name = model_path(r["setup"]).stem  # the model's name (its setup's name if new)
        card = models.get(name, {}).get("card")
        models[name] = {**r, "checkpoint": f"usvsim/models/{name}.pt",
                        "machine": machine, **({"card": card} if card else {})}  # fmt: skip
    return {"models": dict(sorted(models.items()))}


if __name__ == "__main__":
    sys.exit(main())
