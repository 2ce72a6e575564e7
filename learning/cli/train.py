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
                  IL: the most successes on 60 selection episodes, the 15 among them, then
                  the smaller path distance to the expert's)
``summary.json``  the run's outcome: first 15/15 (iteration, env steps, wall-clock), stop reason
                  (IL also: first >= 14/15, the best validation record)
================  ===========================================================================

Every ``validate_every`` iterations the deterministic policy runs the 15 validation episodes
(:func:`usvsim.evaluation.episodes.validation_episodes`); the run stops early when it scores
15/15 at
``stop_after`` consecutive validations. Files are written atomically: a crash, a NaN or Ctrl-C
never leaves half a checkpoint, and a failing update (non-finite loss, gradient or data) stops
the run with a clear message *before* anything is saved, so ``latest.pt`` and ``best.pt`` stay
those of the last good validation. ``--resume`` continues from ``latest.pt`` with the setup,
hyperparameters, seed and ``n_envs`` stored there; a ``--seed`` or ``--n-envs`` other than the
default that differs from the stored value is refused (exit 2: the run cannot honour it), and
``summary.json`` records the seed really used.

Ctrl-C or SIGTERM ends a run cleanly: ``log.csv`` and ``summary.json`` (stop reason
``"interrupted"``) are written, ``latest.pt``/``best.pt`` stay those of the last validation, one
line says so, exit status 130; ``--resume`` continues from there. Bad options (ranges in
:class:`TrainArgs`), an unknown setup, an unwritable ``--out`` or an unusable ``--demos`` folder
are one line and exit status 2 before any work starts (:mod:`usvsim.cli.main`).

``--demos DIR`` (il-* only) trains from your own ``usvsim-demo/1`` files (``-ow`` setups:
``/2``; ``DIR/demo_*.csv``,
format in :mod:`learning.imitation.demonstrations`) instead of the shipped ones; files that
cannot be read or are physically implausible are skipped with a warning, and the run says how
many it used (also in ``summary.json``).

``--init-policy FILE`` (rl-* only) starts a new run from a checkpoint's policy and observation
normaliser (any setup's with the same observation and action kinds, e.g.
``usvsim/models/il-gaussian-scene-ow.pt``: RL fine-tuning of an imitation policy) with a new
critic; a setup with an ``init_policy`` (``rl-*-ft``) starts from its shipped model by default.

``--crowded-share S`` (rl-*-ow only, a new run) draws that share of the training episodes from
the crowded family (every member at its most obstacles and vessels), the rest from the family
(:attr:`learning.experiments.setups.RLSetup.crowded_share`; stored in the checkpoints, so a
resumed run keeps it).

``--harsh-radar-share S`` (rl-*-radar-ow only, a new run) puts that share of the training
episodes at the family's harshest radar, every degradation at its strongest
(:attr:`learning.experiments.setups.RLSetup.harsh_radar_share`; stored in the checkpoints).

``--disc-observation scene`` (il-*-ow only, a new run): GAIL's discriminator sees the true
scene's k-nearest form (the demonstrations' scene, the env's ``info["observation_scene"]``)
whatever the policy sees, e.g. beside a radar policy
(:attr:`learning.imitation.discriminator.GAILConfig.disc_observation`; stored in the
checkpoints).

``--tensorboard DIR`` also writes every ``log.csv`` row as TensorBoard scalars into
``DIR/<name of the output folder>`` (``tensorboard --logdir DIR`` shows runs side by side; tags
and steps: :mod:`learning.experiments.run_log`; needs ``pip install "usvsim[tensorboard]"``).

``--device {cpu,torch-cpu,cuda}`` (the TRPO positional setups, the open-water scene and radar
setups ``rl-*-scene-ow``, ``rl-*-radar-ow`` and their ``-ft``, ``-cont``, the ``rl-*-colreg``
setups; GAIL for ``il-*-positional`` and the ``il-*-ow`` / ``-colreg`` setups): ``cpu`` (the
default) steps the CPU env with NumPy arrays; ``torch-cpu`` and ``cuda`` train with the torch
env (the study task's, or the open-water one on the setup's training family), rollouts, GAE,
the TRPO step and GAIL's discriminator on that device (:mod:`learning.algorithms.device_loop`,
:func:`learning.imitation.gail.train_gail_on_device`); validation, checkpoints and files are
those of a ``cpu`` run. Another setup, or ``cuda`` where torch sees no GPU: one line, exit 2.

``--harsh-radar-copies K`` (il-*-radar-ow only, a new run): every demonstration also enters the
expert data K times with its radar at the family's harshest level, and K/(K+1) of the training
episodes are drawn from that harsh-radar family
(:attr:`learning.experiments.il_setups.ILSetup.harsh_radar_copies`; stored in the checkpoints).
"""

from __future__ import annotations

import dataclasses
import sys
import typing
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch

from learning.algorithms.rollout import NonFiniteError
from learning.experiments.checkpoint import CheckpointError, NonFiniteWeightsError, load_checkpoint
from learning.experiments.il_setups import IL_SETUPS, MAX_HARSH_RADAR_COPIES, get_il_setup
from learning.experiments.run_log import check_tensorboard
from learning.experiments.setups import SETUPS, get_setup, setup_from_params
from learning.experiments.train_il import train_il
from learning.experiments.train_rl import (
    DEVICES,
    device_env_maker,
    first_policy,
    il_device_env_maker,
    train_rl,
)
from learning.experiments.validation import RunResult
from learning.imitation.discriminator import DISC_OBSERVATIONS, DiscObservation
from usvsim.common.errors import UserError
from usvsim.common.fileio import check_writable_dir
from usvsim.common.options import bounds

INTERRUPTED = 130  # exit status after Ctrl-C / SIGTERM

__all__ = ["TrainArgs", "command_of", "outcome", "run", "setup_table"]


@dataclass(frozen=True)
class TrainArgs:
    """Train a steering policy: rl-* by TRPO (rl-*-ppo by PPO), il-* by GAIL (with early stop)."""

    setup: str  # one of the setups listed below (rl-*: TRPO or PPO, il-*: GAIL)
    seed: int = field(default=0, metadata=bounds(ge=0, lt=2**32))  # networks, sampling, episodes
    iterations: int = field(default=0, metadata=bounds(ge=0))  # iteration budget; 0: the setup's
    validate_every: int = field(default=0, metadata=bounds(ge=0))  # every K iterations; 0: setup's
    stop_after: int = field(default=3, metadata=bounds(ge=0))  # after N 15/15 in a row; 0: never
    out: str = ""  # output folder; default usvsim-results/train/<setup>-seed<seed>
    resume: bool = False  # continue the run in --out from its latest.pt (its seed and n_envs)
    n_envs: int = field(  # boats per batch (batch = n_envs x 64 decisions); 0: setup default
        default=0, metadata=bounds(ge=1, le=65_536, zero_ok=True)
    )
    time_budget_s: float = field(  # the run's wall-clock limit, s (resumes: in all); 0: none
        default=0.0, metadata=bounds(ge=0)
    )
    threads: int = field(default=2, metadata=bounds(ge=1, le=1024))  # torch CPU threads
    quiet: bool = False  # no progress bar
    demos: str = ""  # il-*: folder of your demo_*.csv files; default: the shipped demonstrations
    init_policy: str = ""  # rl-*: start from this checkpoint's policy (fine-tuning); "": setup's
    crowded_share: float = field(  # rl-*-ow: share of episodes from the crowded family; 0: setup's
        default=0.0, metadata=bounds(gt=0, lt=1, zero_ok=True)
    )
    harsh_radar_share: float = field(  # rl-*-radar-ow: share at the harshest radar; 0: setup's
        default=0.0, metadata=bounds(gt=0, lt=1, zero_ok=True)
    )
    disc_observation: str = ""  # il-*-ow: "scene" = GAIL's discriminator sees the true scene
    harsh_radar_copies: int = field(  # il-*-radar-ow: K harsh-radar copies per demo; 0: setup's
        default=0, metadata=bounds(ge=0, le=MAX_HARSH_RADAR_COPIES)
    )
    tensorboard: str = ""  # also TensorBoard scalars in DIR/<out folder's name>; "": none
    device: str = "cpu"  # cpu (C kernel, NumPy), torch-cpu or cuda (module docstring: which)

    @classmethod
    def cli_epilog(cls) -> str:
        """The end of ``usvsim train --help``: every registered setup (:func:`setup_table`)."""
        return setup_table()

    def check(self) -> None:
        """Rules beyond the ranges (:func:`usvsim.cli.args.check_options` calls it)."""
        if self.setup not in SETUPS and self.setup not in IL_SETUPS:
            raise UserError(
                f"unknown setup {self.setup!r}; RL setups: {', '.join(SETUPS)}; "
                f"IL setups: {', '.join(IL_SETUPS)}"
            )
        if self.tensorboard:
            check_tensorboard()
        if self.device != "cpu":
            self._check_device()
        if self.demos and not self.setup.startswith("il-"):
            raise UserError(f"--demos is for the il-* setups, not {self.setup!r}")
        if self.demos and not Path(self.demos).is_dir():
            raise UserError(f"--demos {self.demos}: no such folder")
        if self.init_policy and not self.setup.startswith("rl-"):
            raise UserError(f"--init-policy is for the rl-* setups, not {self.setup!r}")
        if self.init_policy and self.resume:
            raise UserError("--init-policy starts a new run; --resume continues one: not both")
        if self.init_policy and not Path(self.init_policy).is_file():
            raise UserError(f"--init-policy {self.init_policy}: no such file")
        rl_setup = SETUPS.get(self.setup)
        if rl_setup and rl_setup.init_policy_required and not (self.init_policy or self.resume):
            raise UserError(
                f"{self.setup} starts from a trained checkpoint: give --init-policy FILE "
                "(e.g. an il-gaussian-radar-ow-colreg seed's best.pt)"
            )
        if self.crowded_share:
            if self.setup not in SETUPS or SETUPS[self.setup].task != "open-water":
                raise UserError(
                    f"--crowded-share is for the rl-*-ow setups (the open-water family), "
                    f"not {self.setup!r}"
                )
            if self.resume:
                raise UserError("--crowded-share starts a new run; --resume keeps the run's own")
        if self.harsh_radar_share:
            rl = SETUPS.get(self.setup)
            if rl is None or rl.task != "open-water" or rl.observation != "radar+goal":
                raise UserError(
                    f"--harsh-radar-share is for the rl-*-radar-ow setups, not {self.setup!r} "
                    "(il-*-radar-ow: --harsh-radar-copies)"
                )
            if self.resume:
                raise UserError(
                    "--harsh-radar-share starts a new run; --resume keeps the run's own"
                )
        if self.disc_observation:
            if self.disc_observation not in DISC_OBSERVATIONS:
                raise UserError(
                    f"--disc-observation must be one of {', '.join(DISC_OBSERVATIONS)}, "
                    f"got {self.disc_observation!r}"
                )
            if self.setup not in IL_SETUPS or IL_SETUPS[self.setup].task != "open-water":
                raise UserError(
                    f"--disc-observation is for the il-*-ow setups (scene demonstrations), "
                    f"not {self.setup!r}"
                )
            if self.resume:
                raise UserError("--disc-observation starts a new run; --resume keeps the run's own")
        if self.harsh_radar_copies:
            il = IL_SETUPS.get(self.setup)
            if il is None or il.task != "open-water" or il.observation != "radar+goal":
                raise UserError(
                    f"--harsh-radar-copies is for the il-*-radar-ow setups, not {self.setup!r}"
                )
            if self.resume:
                raise UserError(
                    "--harsh-radar-copies starts a new run; --resume keeps the run's own"
                )

    def _check_device(self) -> None:
        """``--device``: one of :data:`DEVICES`; other than cpu only for a setup that the
        device loop trains, and cuda only where torch sees a GPU."""
        if self.device not in DEVICES:
            raise UserError(f"--device must be one of {', '.join(DEVICES)}, got {self.device!r}")
        rl, il = SETUPS.get(self.setup), IL_SETUPS.get(self.setup)
        try:
            if rl is not None:
                device_env_maker(rl, self.device)
            elif il is not None:
                il_device_env_maker(il, self.device)
        except ValueError as err:
            raise UserError(str(err)) from None
        if self.device == "cuda" and not torch.cuda.is_available():
            raise UserError("--device cuda: torch sees no CUDA GPU here (use cpu or torch-cpu)")


def setup_table() -> str:
    """Every registered setup (:data:`learning.experiments.setups.SETUPS`, then
    :data:`learning.experiments.il_setups.IL_SETUPS`), one line each: algorithm, task,
    observation, action, and ``*`` where a trained model of it ships in ``usvsim/models``."""
    from usvsim.helm.registry import model_path

    setups: list[Any] = [*SETUPS.values(), *IL_SETUPS.values()]
    width = max(len(s.name) for s in setups) + 2
    lines = [
        f"setups ({len(setups)}; * = a trained model of the setup ships in usvsim/models):",
        f"  {'setup':<{width}}{'algorithm':<11}{'task':<12}{'observation':<13}action",
    ]
    for s in setups:
        algorithm = f"{s.algorithm}+gail" if s.name.startswith("il-") else s.algorithm
        mark = "*" if model_path(s.name).is_file() else " "
        lines.append(
            f"{mark} {s.name:<{width}}{algorithm:<11}{s.task:<12}{s.observation:<13}{s.action}"
        )
    return "\n".join(lines)


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
        if isinstance(value, bool):  # a switch: --x, or --no-x for a default of True
            out.append(flag if value else "--no-" + flag[2:])
        else:
            out += [flag, str(value)]
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
    """The option checks of :func:`usvsim.cli.args.check_options`, for callers of :func:`run`
    that build a ``TrainArgs`` themselves."""
    from usvsim.common.options import check_bounds

    try:
        check_bounds(args)
        args.check()
    except UserError as err:
        raise _fail(str(err)) from None


def _out_dir(args: TrainArgs, name: str) -> Path:
    """``--out``, default ``usvsim-results/train/<setup>-seed<seed>``; refuses to overwrite,
    and checks that it can be written before anything is trained."""
    out = Path(args.out or f"usvsim-results/train/{name}-seed{args.seed}")
    if not args.resume and (out / "latest.pt").exists():
        raise _fail(f"{out / 'latest.pt'} exists: use --resume, or another --out")
    check_writable_dir(out, "--out")
    if args.resume:
        _check_resume(args, out)
    return out


def _check_resume(args: TrainArgs, out: Path) -> None:
    """Refuse a ``--seed`` / ``--n-envs`` that contradicts the run being resumed (module
    docstring). An unreadable ``latest.pt`` is left to the training run to report."""
    path = out / "latest.pt"
    try:
        ckpt = load_checkpoint(path)
        base = get_il_setup(ckpt.setup) if ckpt.setup.startswith("il-") else get_setup(ckpt.setup)
        stored = setup_from_params(base, ckpt.setup_params)
        stored_seed = int(ckpt.agent["config"]["seed"])
        stored_envs = int(stored.run_config().num_envs)
    except (CheckpointError, ValueError, KeyError, TypeError):
        return
    for flag, given, value in (
        ("--seed", args.seed, stored_seed),
        ("--n-envs", args.n_envs, stored_envs),
    ):
        if given not in (0, value):
            raise _fail(
                f"{flag} {given} contradicts {path} ({flag} {value}); --resume continues with "
                f"the stored value: drop {flag}, or start a new run in another --out"
            )


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
    out = _out_dir(args, setup.name)
    if args.n_envs:
        setup = setup.with_num_envs(args.n_envs)
    if args.disc_observation:
        view = typing.cast(DiscObservation, args.disc_observation)  # checked: TrainArgs.check
        gail = dataclasses.replace(setup.gail, disc_observation=view)
        setup = setup.replace(gail=gail)
    if args.harsh_radar_copies:
        setup = setup.replace(harsh_radar_copies=args.harsh_radar_copies)
    return _train_and_report(
        lambda: train_il(
            setup,
            out,
            demos_dirs=(args.demos,) if args.demos else None,
            seed=args.seed,
            iterations=args.iterations or None,
            resume=args.resume,
            threads=args.threads,
            validate_every=args.validate_every,
            stop_after=args.stop_after,
            time_budget_s=args.time_budget_s,
            quiet=args.quiet,
            command=command_of(args),
            tensorboard=_board(args, out),
            device=args.device,
        ),
        setup.name,
        out,
    )


def _board(args: TrainArgs, out: Path) -> str:
    """The run's TensorBoard folder: ``--tensorboard DIR``'s subfolder named as ``out`` (runs
    side by side in one TensorBoard, as SB3's ``tensorboard_log``); "" without the option."""
    return str(Path(args.tensorboard) / out.resolve().name) if args.tensorboard else ""


def _train_and_report(train: Callable[[], RunResult], name: str, out: Path) -> int:
    """Run ``train`` and print its outcome line; exit codes and messages of ``usvsim train``."""
    try:
        result = train()
    except CheckpointError as err:
        raise _fail(f"cannot resume: {err}") from None
    except (NonFiniteError, NonFiniteWeightsError) as err:
        return _report_failure(f"non-finite value in training ({err})", out)
    if result.stop_reason == "interrupted":
        kept = (
            f"latest.pt of iteration {result.history[-1]['iteration']} kept"
            if result.history
            else "no checkpoint yet (interrupted before the first validation)"
        )
        print(
            f"usvsim train: interrupted at iteration {result.iterations}; {kept}; "
            f"summary.json marked interrupted in {out} (continue with --resume)",
            file=sys.stderr,
            flush=True,
        )
        return INTERRUPTED
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
    """Run ``usvsim train`` (module docstring); 0 on success, 1 on a non-finite loss, 130 after
    Ctrl-C / SIGTERM."""
    _check_options(args)
    torch.set_num_threads(args.threads)
    if args.setup.startswith("il-"):
        return _run_il(args)
    try:
        setup = get_setup(args.setup)
    except ValueError as err:
        raise _fail(str(err)) from None
    out = _out_dir(args, setup.name)
    if args.n_envs and not args.resume:
        setup = setup.with_num_envs(args.n_envs)
    if args.crowded_share:
        setup = setup.replace(crowded_share=args.crowded_share)
    if args.harsh_radar_share:
        setup = setup.replace(harsh_radar_share=args.harsh_radar_share)
    if not args.resume:
        try:  # a policy that cannot start this setup: one line before any work
            first_policy(setup, args.init_policy)
        except CheckpointError as err:
            raise _fail(f"cannot start from that policy: {err}") from None
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
            init_policy=args.init_policy,
            tensorboard=_board(args, out),
            device=args.device,
        ),
        setup.name,
        out,
    )
