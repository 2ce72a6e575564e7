"""``usvsim train SETUP``: TRPO on one of the study's four RL setups (GAIL on one of its four
IL setups, :mod:`learning.experiments.il_setups`); validation, checkpoints.

One run (RL or IL) writes into its output folder (default
``usvsim-results/train/<setup>-seed<seed>``):

================  ===========================================================================
file              contents
================  ===========================================================================
``log.csv``       one row per iteration (:data:`CSV_FIELDS`; IL: ``IL_CSV_FIELDS`` of
                  :mod:`learning.experiments.il_setups`); validation columns filled on validation
                  iterations, empty otherwise
``curve.png``     learning curve: training return and validation successes vs env steps
``latest.pt``     the full (resumable) checkpoint at the last validation (:mod:`checkpoint`)
``best.pt``       the checkpoint with the most validation successes (ties: higher mean return;
                  IL: the smaller path distance to the expert's)
``summary.json``  the run's outcome: first 15/15 (iteration, env steps, wall-clock), stop reason
                  (IL also: first >= 14/15, the best validation record)
================  ===========================================================================

Every ``validate_every`` iterations the deterministic policy runs the 15 validation episodes
(:func:`usvsim.evaluation.episodes.validation_episodes`); the run stops early when it scores 15/15 at
``stop_after`` consecutive validations. Files are written atomically: a crash, a NaN or Ctrl-C
never leaves half a checkpoint, and a failing update (non-finite loss, gradient or data) stops
the run with a clear message *before* anything is saved, so ``latest.pt`` and ``best.pt`` stay
those of the last good validation. ``--resume`` continues from ``latest.pt`` with the setup and
hyperparameters stored there.
"""

from __future__ import annotations

import dataclasses
import json
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from learning.algorithms.rollout import NonFiniteError
from learning.algorithms.trpo import IterationStats, TRPOAgent, train
from learning.experiments.checkpoint import (
    Checkpoint,
    CheckpointError,
    NonFiniteWeightsError,
    PolicyHelmsman,
    load_checkpoint,
    save_checkpoint,
)
from learning.experiments.run_log import Milestones, RunLog, advance, progress_bar, read_log_rows
from learning.experiments.setups import RLSetup, get_setup
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.episodes import EpisodeRecord, evaluate, validation_episodes

__all__ = ["CSV_FIELDS", "TrainArgs", "run", "validate"]

CSV_FIELDS = (
    "iteration",
    "env_steps",
    "wall_time_s",
    "episodes",
    "mean_return",
    "mean_length",
    "kl",
    "entropy",
    "surrogate_improvement",
    "line_search_accepted",
    "value_loss",
    "val_successes",
    "val_mean_return",
    "val_min_pole_distance_m",
)


@dataclass(frozen=True)
class TrainArgs:
    """Train a steering policy, rl-* by TRPO, il-* by GAIL (validation, checkpoints, early stop)."""

    setup: str  # rl-* (TRPO) or il-* (GAIL): {rl,il}-{gaussian,categorical}-{positional,radar}
    seed: int = 0  # seeds networks, action sampling and training episodes
    iterations: int = 0  # iteration budget (TRPO or GAIL); 0: the setup's default
    validate_every: int = 0  # validate on the 15 episodes every K iterations; 0: setup default
    stop_after: int = 3  # stop after this many consecutive 15/15 validations; 0: never stop early
    out: str = ""  # output folder; default usvsim-results/train/<setup>-seed<seed>
    resume: bool = False  # continue the run in --out from its latest.pt
    n_envs: int = 0  # boats per batch (batch = n_envs x 64 decisions); 0: setup default
    time_budget_s: float = 0.0  # stop after this much wall-clock, s; 0: no limit
    threads: int = 2  # torch CPU threads (1 is faster when other jobs load the CPU)
    quiet: bool = False  # no progress bar


def validate(agent: TRPOAgent, setup: RLSetup) -> dict[str, float]:
    """The deterministic policy on the 15 validation episodes: successes, mean return, min d."""
    records = evaluate(
        PolicyHelmsman(agent, setup.observation, setup.action),
        validation_episodes(),
        observation=setup.observation,
        action=setup.action,
    )
    return validation_summary(records)


def validation_summary(records: Sequence[EpisodeRecord]) -> dict[str, float]:
    """Successes, episodes, mean return and the closest pole approach (m) of ``records``."""
    returns = [float(np.sum(r.reward_pole) + np.sum(r.reward_goal)) for r in records]
    return {
        "successes": int(sum(r.success for r in records)),
        "n_episodes": len(records),
        "mean_return": float(np.mean(returns)),
        "min_pole_distance_m": float(min(r.min_pole_distance_m for r in records)),
    }


def _fail(message: str) -> SystemExit:
    return SystemExit(f"usvsim train: {message}")


class _Run:
    """State of one training run: files, log rows, validation history, the stopping rule."""

    def __init__(self, args: TrainArgs, setup: RLSetup, out: Path, rows: list[dict[str, Any]]):
        self.args, self.setup, self.out = args, setup, out
        self.log = RunLog(out, CSV_FIELDS, setup.name, rows)
        self.rows = self.log.rows
        self.history: list[dict[str, Any]] = []
        self.best: tuple[int, float] | None = None
        self.milestones = Milestones()
        self.stop_reason = "iterations"
        self.wall_offset_s = 0.0  # wall-clock of the run before a resume
        self.validate_every = args.validate_every or setup.validate_every

    def restore(self, history: list[dict[str, Any]]) -> None:
        """Continue the validation bookkeeping of a resumed run from its stored history."""
        self.history = list(history)
        self.wall_offset_s = float(history[-1]["wall_time_s"]) if history else 0.0
        for h in history:
            self.milestones.add(h)
            key = (int(h["successes"]), float(h["mean_return"]))
            self.best = key if self.best is None or key > self.best else self.best

    def train_args(self) -> dict[str, Any]:
        return dataclasses.asdict(self.args)

    def on_iteration(self, stats: IterationStats, agent: TRPOAgent) -> bool:
        wall = self.wall_offset_s + stats.wall_time_s
        row: dict[str, Any] = {
            "iteration": stats.iteration,
            "env_steps": stats.env_steps,
            "wall_time_s": round(wall, 3),
            "episodes": stats.episodes,
            "mean_return": stats.mean_return,
            "mean_length": stats.mean_length,
            "kl": stats.kl,
            "entropy": stats.entropy,
            "surrogate_improvement": stats.surrogate_improvement,
            "line_search_accepted": int(stats.line_search_accepted),
            "value_loss": stats.value_loss,
        }
        self.rows.append(row)
        stop = False
        if stats.iteration % self.validate_every == 0:
            stop = self._validate(stats, agent, row, wall)
        budget = self.args.time_budget_s
        if not stop and budget > 0 and stats.wall_time_s >= budget:
            self.stop_reason, stop = "time budget", True
        return stop

    def _validate(
        self, stats: IterationStats, agent: TRPOAgent, row: dict[str, Any], wall: float
    ) -> bool:
        val = validate(agent, self.setup)
        record = validation_record(row, wall, val, kl=stats.kl, entropy=stats.entropy)
        self.history.append(record)
        self.milestones.add(record)
        ckpt = Checkpoint.from_agent(
            agent,
            self.setup,
            train_args=self.train_args(),
            validation=record,
            history=self.history,
        )
        save_checkpoint(ckpt, self.out / "latest.pt")
        key = (int(val["successes"]), float(val["mean_return"]))
        if self.best is None or key > self.best:
            self.best = key
            save_checkpoint(ckpt, self.out / "best.pt")
        self.log.write(plot=self.log.plot_due())
        reason = self.milestones.stop_reason(self.args.stop_after)
        if reason:
            self.stop_reason = reason
            return True
        return False

    def write_summary(self, agent: TRPOAgent, wall_s: float, error: str | None) -> None:
        summary = {
            "setup": self.setup.name,
            "seed": self.args.seed,
            "command": command_of(self.args),
            "iterations": agent.iteration,
            "env_steps": agent.env_steps,
            "wall_time_s": wall_s,
            "stop_reason": error or self.stop_reason,
            "first_15_of_15": self.milestones.first_full,
            "best": None
            if self.best is None
            else {"successes": self.best[0], "mean_return": self.best[1]},
            "study_iterations": self.setup.study_iterations,
            "threads": torch.get_num_threads(),
        }
        atomic_write_text(self.out / "summary.json", json.dumps(summary, indent=2) + "\n")


def validation_record(
    row: dict[str, Any], wall_s: float, val: dict[str, float], **extra: Any
) -> dict[str, Any]:
    """Fill the log ``row``'s ``val_*`` columns from ``val`` (:func:`validation_summary`, and
    whatever else was measured) and return the validation's record for the checkpoints'
    history and ``summary.json``: iteration, env steps, wall-clock, ``val``, the success rate
    and ``extra``."""
    row.update({f"val_{k}": v for k, v in val.items() if k != "n_episodes"})
    return {
        "iteration": row["iteration"],
        "env_steps": row["env_steps"],
        "wall_time_s": wall_s,
        **val,
        "success_rate": val["successes"] / val["n_episodes"],
        **extra,
    }


def command_of(args: TrainArgs) -> str:
    """The ``usvsim train`` command line that reproduces ``args`` (non-default options only)."""
    out = [args.setup]
    for f in dataclasses.fields(args):
        value = getattr(args, f.name)
        if f.name == "setup" or value == f.default:
            continue
        flag = "--" + f.name.replace("_", "-")
        out += [flag] if isinstance(value, bool) else [flag, str(value)]
    return "usvsim train " + " ".join(out)


def outcome(
    name: str,
    iterations: int,
    env_steps: int,
    wall_s: float,
    stop: str,
    first_full: dict[str, Any] | None,
    out: Path,
) -> str:
    """The one line a finished run prints."""
    first = (
        "never"
        if first_full is None
        else f"iteration {first_full['iteration']} ({first_full['env_steps']:,} steps, "
        f"{first_full['wall_time_s']:.0f} s)"
    )
    return (
        f"{name}: {iterations} iterations, {env_steps:,} env steps, {wall_s:.0f} s; "
        f"stopped: {stop}; first 15/15: {first}; files in {out}"
    )


def _check_options(args: TrainArgs) -> None:
    for name in ("iterations", "validate_every", "stop_after", "n_envs"):
        if getattr(args, name) < 0:
            raise _fail(f"--{name.replace('_', '-')} must be >= 0")


def _out_dir(args: TrainArgs, name: str) -> Path:
    """``--out``, default ``usvsim-results/train/<setup>-seed<seed>``; refuses to overwrite."""
    out = Path(args.out or f"usvsim-results/train/{name}-seed{args.seed}")
    if not args.resume and (out / "latest.pt").exists():
        raise _fail(f"{out / 'latest.pt'} exists: use --resume, or another --out")
    return out


def _report_failure(error: str, out: Path) -> int:
    print(
        f"usvsim train: {error}. Checkpoints in {out} are those of the last good validation "
        "(nothing was saved after the failure).",
        file=sys.stderr,
    )
    return 1


def _run_il(args: TrainArgs) -> int:
    """``usvsim train il-*``: GAIL from the shipped demonstrations (:func:`il_setups.train_il`),
    with the options and output files of an RL run (module docstring)."""
    from learning.experiments.il_setups import get_il_setup, train_il

    try:
        setup = get_il_setup(args.setup)
    except ValueError as err:
        raise _fail(str(err)) from None
    _check_options(args)
    out = _out_dir(args, setup.name)
    if args.n_envs:
        setup = setup.replace(num_envs=args.n_envs)
    try:
        result = train_il(
            setup,
            out,
            seed=args.seed,
            iterations=args.iterations or None,
            resume=args.resume,
            threads=args.threads,
            validate_every=args.validate_every,
            stop_after=args.stop_after,
            time_budget_s=args.time_budget_s,
            quiet=args.quiet,
            command=command_of(args),
        )
    except CheckpointError as err:
        raise _fail(f"cannot resume: {err}") from None
    except (NonFiniteError, NonFiniteWeightsError) as err:
        return _report_failure(f"non-finite value in training ({err})", out)
    print(
        outcome(
            setup.name,
            result.iterations,
            result.env_steps,
            result.wall_time_s,
            result.stop_reason,
            result.first_full,
            out,
        )
    )
    return 0


def run(args: TrainArgs) -> int:
    """Run ``usvsim train`` (module docstring); 0 on success, 1 on a non-finite loss."""
    torch.set_num_threads(max(1, args.threads))
    if args.setup.startswith("il-"):
        return _run_il(args)
    try:
        setup = get_setup(args.setup)
    except ValueError as err:
        raise _fail(str(err)) from None
    _check_options(args)
    out = _out_dir(args, setup.name)
    state: dict[str, Any] | None = None
    rows: list[dict[str, Any]] = []
    history: list[dict[str, Any]] = []
    if args.resume:
        try:
            ckpt = load_checkpoint(out / "latest.pt", expected_setup=setup)
        except CheckpointError as err:
            raise _fail(f"cannot resume: {err}") from None
        if ckpt.slim:
            raise _fail(f"cannot resume from {out / 'latest.pt'}: slim checkpoint (no critic)")
        setup = setup.replace(**{k: v for k, v in ckpt.setup_params.items() if k != "name"})
        state, history = ckpt.agent, ckpt.history
        rows = read_log_rows(out / "log.csv", int(state["iteration"]))
    if args.n_envs and state is None:
        setup = setup.replace(num_envs=args.n_envs)
    config = setup.trpo_config(args.seed, args.iterations or None)
    if state is not None:
        config = dataclasses.replace(config, seed=int(state["config"]["seed"]))
    out.mkdir(parents=True, exist_ok=True)
    r = _Run(args, setup, out, rows)
    r.restore(history)

    start_iteration = int(state["iteration"]) if state is not None else 0
    bar = progress_bar(config.iterations, start_iteration, setup.name, args.quiet)

    def callback(stats: IterationStats, agent: TRPOAgent) -> bool:
        stop = r.on_iteration(stats, agent)
        advance(bar, stats.mean_return, stats.kl, r.history[-1] if r.history else None)
        return stop

    t0 = time.perf_counter()
    agent: TRPOAgent | None = None
    error: str | None = None
    try:
        agent = train(config, setup.make_vector_env, callback=callback, state=state)
    except (NonFiniteError, NonFiniteWeightsError) as err:
        error = f"non-finite value in training ({err}); stopped at iteration {len(r.rows) + 1}"
    finally:
        bar.close()
    wall = r.wall_offset_s + time.perf_counter() - t0
    r.log.write()
    if error is not None:
        return _report_failure(error, out)
    assert agent is not None
    r.write_summary(agent, wall, None)
    print(
        outcome(
            setup.name,
            agent.iteration,
            agent.env_steps,
            wall,
            r.stop_reason,
            r.milestones.first_full,
            out,
        )
    )
    return 0
