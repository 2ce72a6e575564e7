"""``usvsim train SETUP``: TRPO on one of the study's four RL setups
(:func:`learning.experiments.train_rl.train_rl`), GAIL on one of its four IL setups
(:func:`learning.experiments.train_il.train_il`); validation, checkpoints. This module is the
command line only: options, output folder, messages and exit codes.

One run (RL or IL) writes into its output folder (default
``usvsim-results/train/<setup>-seed<seed>``):

================  ===========================================================================
file              contents
================  ===========================================================================
``log.csv``       one row per iteration (:func:`learning.experiments.train_rl.csv_fields`;
                  IL: ``IL_CSV_FIELDS`` of :mod:`learning.experiments.train_il`); validation
                  columns filled on validation iterations, empty otherwise
``curve.png``     learning curve: training return and validation successes vs env steps
``latest.pt``     the full (resumable) checkpoint at the last validation
                  (:mod:`learning.experiments.checkpoint`)
``best.pt``       the checkpoint with the most validation successes (ties: higher mean return;
                  IL: the smaller path distance to the expert's)
``summary.json``  the run's outcome: first 15/15 (iteration, env steps, wall-clock), stop reason
                  (IL also: first >= 14/15, the best validation record)
================  ===========================================================================

Every ``validate_every`` iterations the deterministic policy runs the 15 validation episodes
(:func:`usvsim.evaluation.episodes.validation_episodes`); the run stops early when it scores
15/15 at
``stop_after`` consecutive validations. Files are written atomically: a crash, a NaN or Ctrl-C
never leaves half a checkpoint, and a failing update (non-finite loss, gradient or data) stops
the run with a clear message *before* anything is saved, so ``latest.pt`` and ``best.pt`` stay
those of the last good validation. ``--resume`` continues from ``latest.pt`` with the setup and
hyperparameters stored there.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from learning.algorithms.rollout import NonFiniteError
from learning.experiments.checkpoint import CheckpointError, NonFiniteWeightsError
from learning.experiments.il_setups import get_il_setup
from learning.experiments.setups import get_setup
from learning.experiments.train_il import train_il
from learning.experiments.train_rl import train_rl
from learning.experiments.validation import RunResult

__all__ = ["TrainArgs", "command_of", "outcome", "run"]


@dataclass(frozen=True)
class TrainArgs:
    """Train a steering policy: rl-* by TRPO (rl-*-ppo by PPO), il-* by GAIL (with early stop)."""

    setup: str  # {rl,il}-{gaussian,categorical}-{positional,radar}; rl-*-ppo: PPO, not TRPO
    seed: int = 0  # seeds networks, action sampling and training episodes
    iterations: int = 0  # iteration budget; 0: the setup's default
    validate_every: int = 0  # validate on the 15 episodes every K iterations; 0: setup default
    stop_after: int = 3  # stop after this many consecutive 15/15 validations; 0: never stop early
    out: str = ""  # output folder; default usvsim-results/train/<setup>-seed<seed>
    resume: bool = False  # continue the run in --out from its latest.pt
    n_envs: int = 0  # boats per batch (batch = n_envs x 64 decisions); 0: setup default
    time_budget_s: float = 0.0  # stop after this much wall-clock, s; 0: no limit
    threads: int = 2  # torch CPU threads (1 is faster when other jobs load the CPU)
    quiet: bool = False  # no progress bar


def _fail(message: str) -> SystemExit:
    return SystemExit(f"usvsim train: {message}")


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
    """``usvsim train il-*``: GAIL from the shipped demonstrations
    (:func:`learning.experiments.train_il.train_il`), with the options and output files of an
    RL run (module docstring)."""
    try:
        setup = get_il_setup(args.setup)
    except ValueError as err:
        raise _fail(str(err)) from None
    _check_options(args)
    out = _out_dir(args, setup.name)
    if args.n_envs:
        setup = setup.with_num_envs(args.n_envs)
    return _train_and_report(
        lambda: train_il(
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
        ),
        setup.name,
        out,
    )


def _train_and_report(train: Callable[[], RunResult], name: str, out: Path) -> int:
    """Run ``train`` and print its outcome line; exit codes and messages of ``usvsim train``."""
    try:
        result = train()
    except CheckpointError as err:
        raise _fail(f"cannot resume: {err}") from None
    except (NonFiniteError, NonFiniteWeightsError) as err:
        return _report_failure(f"non-finite value in training ({err})", out)
    print(
        outcome(
            name,
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
    if args.n_envs and not args.resume:
        setup = setup.with_num_envs(args.n_envs)
    return _train_and_report(
        lambda: train_rl(
            setup,
            out,
            seed=args.seed,
            iterations=args.iterations or None,
            resume=args.resume,
            validate_every=args.validate_every,
            stop_after=args.stop_after,
            time_budget_s=args.time_budget_s,
            quiet=args.quiet,
            train_args=dataclasses.asdict(args),
            command=command_of(args),
        ),
        setup.name,
        out,
    )
