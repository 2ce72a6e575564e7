"""One IL training run (``usvsim train il-*``): GAIL (:mod:`learning.imitation.gail`) on one of
the setups of :mod:`learning.experiments.il_setups`.

:func:`train_il` is the run: load and filter the demonstrations
(:mod:`learning.imitation.demonstrations`), preprocess them (:mod:`learning.imitation.preprocess`),
GAIL (:func:`learning.imitation.gail.train_gail`), validate on the 15 episodes every
``validate_every`` iterations, keep the best checkpoint (:mod:`learning.experiments.checkpoint`
format, the policy agent; the discriminator in a ``latest.gail.pt`` sidecar for resuming), and
write ``log.csv`` (:data:`IL_CSV_FIELDS`), ``curve.png`` and ``summary.json`` as an RL run does
(:mod:`learning.experiments.train_rl`). ``usvsim train SETUP`` (:mod:`learning.cli.train`) runs
it with the options of an RL run: ``--stop-after`` (default 3 consecutive 15/15 validations,
as RL; 0 runs the whole budget), ``--time-budget-s``, ``--validate-every``, ``--n-envs``,
``--resume``, ``--quiet``.

Why this module is long: loading, validating and checkpointing a GAIL run mirror
:mod:`learning.experiments.train_rl` step by step, and are kept in one place as that module is.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import torch
from gymnasium.vector import VectorEnv

from learning.algorithms.base import log_row
from learning.algorithms.loop import TIME_FIELDS, IterationStats, time_row
from learning.experiments.checkpoint import (
    Checkpoint,
    CheckpointError,
    load_checkpoint,
    save_checkpoint,
)
from learning.experiments.il_setups import ILSetup
from learning.experiments.memory_start import check_cpu_only_options
from learning.experiments.run_log import Milestones, RunLog, advance, progress_bar, read_log_rows
from learning.experiments.setups import setup_from_params
from learning.experiments.train_rl import il_device_env_maker, open_water_fields
from learning.experiments.validation import (
    RunResult,
    extra_successes,
    family_passed,
    finish_run,
    open_water_summary,
    policy_records,
    validation_record,
    validation_summary,
)
from learning.imitation.demonstrations import (
    DemoFormatError,
    LoadReport,
    Recording,
    load_recordings,
    quality_check,
)
from learning.imitation.gail import GAILAgent, GAILStats, train_gail, train_gail_on_device
from learning.imitation.preprocess import (
    ExpertData,
    check_observations,
    expert_data,
    harsh_radar_runs,
)
from usvsim.common.fileio import atomic_open, remove_stale_temporaries
from usvsim.common.splits import selection_mode
from usvsim.evaluation.episodes import selection_episodes, validation_episodes
from usvsim.evaluation.likeness import ExpertReference, expert_reference, likeness
from usvsim.task.goal_mark import GoalMarkVectorEnv, with_goal_mark
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.radar_memory import RadarMemoryVectorEnv, stack_episode_frames
from usvsim.task.scenario import EpisodeSpec
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

__all__ = [
    "IL_CSV_FIELDS",
    "ILRunResult",
    "expert_pairs",
    "train_il",
    "validate_il",
]

ILRunResult = RunResult  # the outcome of train_il (the same record as an RL run's)

IL_CSV_FIELDS = (
    "iteration",
    "env_steps",
    "wall_time_s",
    "episodes",
    "env_return",
    *GAILStats.LOG_FIELDS,
    "val_successes",
    "val_mean_return",
    "val_min_pole_distance_m",
    "val_path_distance_m",
    "val_selection_successes",
    *TIME_FIELDS,
)

"""Columns of an IL run's ``log.csv``: :class:`learning.imitation.gail.GAILStats` (``env_return``
the handcrafted return of the finished training episodes, a diagnostic; ``mean_reward`` the mean
imitation reward; ``disc_*``, ``*_accuracy``, ``mean_d_*`` the discriminator's last Adam step),
then the validation's (filled on validation iterations): successes /15, mean handcrafted return,
closest pole approach (m), path distance to the expert's paths (m,
:mod:`usvsim.evaluation.likeness`) and successes on the 60 selection episodes
(:func:`usvsim.evaluation.episodes.selection_episodes`, the 15 among them); then where the
iteration's wall-clock went, s (:data:`learning.algorithms.loop.TIME_FIELDS`: rollout, batch,
policy step, critic, discriminator).
``wall_time_s`` counts from the start of GAIL (behavioural cloning included) and continues
across ``--resume``."""


def _checkpoint(
    agent: GAILAgent, setup: ILSetup, args: dict[str, Any], rec: Any, hist: Any
) -> Checkpoint:
    """The checkpoint of the policy agent (the discriminator goes to ``latest.gail.pt``)."""
    return Checkpoint.from_agent(
        agent.policy_agent,
        setup,
        train_args=args,
        validation=rec,
        history=hist,
    )


@selection_mode("validate_il")
def validate_il(
    agent: GAILAgent,
    setup: ILSetup,
    specs: Sequence[EpisodeSpec],
    reference: ExpertReference,
    extra_specs: Sequence[EpisodeSpec] = (),
) -> dict[str, float]:
    """The deterministic policy on ``specs`` (the 15 validation episodes):
    :func:`learning.experiments.validation.validation_summary` and the path distance to the
    expert (m); with ``extra_specs`` (run in the same batch) also ``selection_successes``, the
    successes on ``specs`` and ``extra_specs`` together; for an open-water setup also the
    family and crowded sets' ``family_*`` and ``crowded_*`` entries (a radar one also the
    harsh-radar set's ``radar_*``:
    :func:`learning.experiments.validation.open_water_summary`)."""
    recs = policy_records(agent, setup, [*specs, *extra_specs])
    val = {
        **validation_summary(recs[: len(specs)]),
        "path_distance_m": likeness(recs[: len(specs)], reference).path_distance_m,
    }
    if extra_specs:
        val["selection_successes"] = int(sum(r.success for r in recs))
    val.update(open_water_summary(agent, setup))
    return val


class _ILRun:
    """One GAIL run's bookkeeping: log rows, validations, checkpoints, milestones, stopping."""

    def __init__(
        self,
        setup: ILSetup,
        out: Path,
        *,
        train_args: dict[str, Any],
        last_iteration: int,
        validate_every: int,
        stop_after: int,
        time_budget_s: float,
        rows: list[dict[str, Any]],
        history: list[dict[str, Any]],
        say: Callable[[str], None],
        tensorboard: str | Path = "",
    ) -> None:
        """``train_args`` go into the checkpoints and ``summary.json``; the rest: train_il's."""
        self.setup, self.out, self.train_args, self.say = setup, out, train_args, say
        self.validate_every = validate_every or setup.validate_every
        self.last_iteration, self.stop_after = last_iteration, stop_after
        self.time_budget_s = time_budget_s
        self.log = RunLog(
            out,
            IL_CSV_FIELDS + open_water_fields(setup),
            setup.name,
            rows,
            "env_return",
            "env return (handcrafted,\nfinished episodes)",
            tensorboard=tensorboard,
        )
        self.history = list(history)
        self.milestones = Milestones()
        for h in history:
            self.milestones.add(h)
        self.best = max(history, key=_rank) if history else None
        self.wall_offset_s = float(history[-1]["wall_time_s"]) if history else 0.0
        self.start = time.perf_counter()
        self.stop_reason = "iterations"
        self.specs = validation_episodes()
        self.extra_specs = selection_episodes()[len(self.specs) :]
        self.reference = expert_reference(self.specs)

    def session_s(self) -> float:
        return time.perf_counter() - self.start

    def on_iteration(self, s: IterationStats, agent: GAILAgent) -> bool:
        wall = self.wall_offset_s + self.session_s()
        row: dict[str, Any] = {
            "iteration": s.iteration,
            "env_steps": s.env_steps,
            "wall_time_s": round(wall, 3),
            "episodes": s.episodes,
            "env_return": s.mean_return,
            **log_row(s.update),
            **time_row(s),
        }
        self.log.rows.append(row)
        stop = False
        if s.iteration % self.validate_every == 0 or s.iteration == self.last_iteration:
            stop = self._validate(s, agent, row, wall)
        if not stop and 0 < self.time_budget_s <= wall:  # the run's wall-clock, resumes included
            self.stop_reason, stop = "time budget", True
        return stop

    def _validate(
        self, s: IterationStats, agent: GAILAgent, row: dict[str, Any], wall: float
    ) -> bool:
        val = validate_il(agent, self.setup, self.specs, self.reference, self.extra_specs)
        u = s.update
        assert isinstance(u, GAILStats)
        rec = validation_record(
            row,
            wall,
            val,
            env_return=s.mean_return,
            kl=s.kl,
            entropy=s.entropy,
            expert_accuracy=u.expert_accuracy,
            policy_accuracy=u.policy_accuracy,
            goal_rate=u.goal_rate,
        )
        self.milestones.add(rec)
        self.say(
            f"it {s.iteration:4d} {rec['wall_time_s']:6.0f}s val {rec['successes']:2d}/15 "
            f"min d_pole {rec['min_pole_distance_m']:5.1f} m  D acc E/π "
            f"{u.expert_accuracy:.2f}/{u.policy_accuracy:.2f}  goal {u.goal_rate:.2f}  "
            f"path-to-expert {rec['path_distance_m']:4.1f} m"
        )
        ck = _checkpoint(agent, self.setup, self.train_args, rec, [*self.history, rec])
        if self.best is None or _rank(rec) > _rank(self.best):
            self.best = rec
            save_checkpoint(ck, self.out / "best.pt")
        save_checkpoint(ck, self.out / "latest.pt")
        # only now: summary.json's checkpoint_iteration (history[-1]) must be what latest.pt holds
        # even when a Ctrl-C lands inside the save
        self.history.append(rec)
        with atomic_open(self.out / "latest.gail.pt", "wb") as handle:
            torch.save(agent.trainer.state_dict(), handle)
        self.log.write(plot=self.log.plot_due())
        reason = self.milestones.stop_reason(self.stop_after) if family_passed(val) else ""
        self.stop_reason = reason or self.stop_reason
        return bool(reason)

    def result(self, iterations: int, env_steps: int, wall_s: float) -> RunResult:
        """Write ``summary.json`` (JSON without NaN: null); the run's :class:`ILRunResult`."""
        summary = {
            "setup": self.setup.name,
            "seed": self.train_args["seed"],
            "command": self.train_args["command"],
            "iterations": iterations,
            "env_steps": env_steps,
            "wall_time_s": wall_s,
            "stop_reason": self.stop_reason,
            "interrupted": self.stop_reason == "interrupted",
            "checkpoint_iteration": int(self.history[-1]["iteration"]) if self.history else None,
            "first_14_of_15": self.milestones.first_14_of_15,
            "first_15_of_15": self.milestones.first_full,
            "best": self.best,
            "study_success": self.setup.study_success,
            "study_iterations": self.setup.study_iterations,
            "threads": torch.get_num_threads(),
            "demonstrations": self.train_args["demos"],
            "demonstrations_folder": self.train_args.get("demos_dir", ""),
            "demonstrations_skipped": self.train_args.get("demos_skipped", 0),
        }
        return finish_run(
            self.out,
            summary,
            self.best,
            self.history,
            (iterations, env_steps, wall_s),
            self.stop_reason,
            self.milestones.first_full,
        )


@selection_mode("train_il")  # training, validations, best.pt and early stops: no test episode
def train_il(
    setup: ILSetup,
    out_dir: str | Path,
    *,
    seed: int = 0,
    iterations: int | None = None,
    resume: bool = False,
    threads: int = 1,
    validate_every: int = 0,
    stop_after: int = 0,
    time_budget_s: float = 0.0,
    quiet: bool = True,
    command: str = "",
    demos_dirs: Sequence[str | Path] | None = None,
    log: Callable[[str], None] = print,
    tensorboard: str | Path = "",
    device: str = "cpu",
) -> ILRunResult:
    """Train ``setup`` by GAIL, writing into ``out_dir`` the files of ``usvsim train``
    (:mod:`learning.cli.train`; ``log.csv`` columns :data:`IL_CSV_FIELDS`).

    ``best.pt`` is the best validation checkpoint (most successes on the 60 selection episodes,
    then on the 15 validation episodes, then the smallest path distance to the expert,
    :mod:`usvsim.evaluation.likeness`; :func:`_rank`), ``latest.pt`` the last one and
    ``latest.gail.pt`` its discriminator state; ``resume`` continues from those two with the
    setup, hyperparameters and seed stored there, and keeps ``log.csv`` up to their iteration.
    Validation every ``validate_every`` iterations (0: the setup's) and at the last one; the
    run stops after ``stop_after`` consecutive 15/15 validations (0: never) or once the run
    has taken ``time_budget_s`` of wall-clock (0: no limit; ``log.csv``'s ``wall_time_s``,
    a resumed part counted on from its checkpoint's). ``quiet``: no progress bar; ``log``
    prints one line per validation. ``threads``: torch CPU threads (on 2 shared cores, 2
    threads made an iteration 20× slower than 1 when measured). ``tensorboard`` (a folder; "":
    none): also every ``log.csv`` row as TensorBoard scalars there
    (:class:`learning.experiments.run_log.RunLog`). ``device`` (``"cpu"``, ``"torch-cpu"`` or
    ``"cuda"``): where the env steps and GAIL trains (:func:`il_device_env_maker`,
    :func:`learning.imitation.gail.train_gail_on_device`); validation stays on the CPU env.

    Raises ``CheckpointError`` when ``resume`` finds no usable checkpoint of ``setup``, and
    ``NonFiniteError`` / ``NonFiniteWeightsError`` (after writing ``log.csv``) when an update
    goes non-finite; nothing is saved after such a failure.
    """
    torch.set_num_threads(max(1, threads))
    folders = tuple(Path(d) for d in (setup.demos_dirs if demos_dirs is None else demos_dirs))
    out = Path(out_dir)
    state: dict[str, Any] | None = None
    history: list[dict[str, Any]] = []
    rows: list[dict[str, Any]] = []
    if resume:
        setup, state, history = _resume_state(setup, out / "latest.pt")
        seed = int(state["agent"]["config"]["seed"])
        rows = read_log_rows(out / "log.csv", int(state["agent"]["iteration"]))
    check_cpu_only_options(setup, device)  # before any file is written or demo read
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(out)  # half-written files of a killed earlier run
    data, n_demos, n_skipped = expert_pairs(setup, folders, log)
    cfg = setup.run_config(seed, iterations)
    train_args = {
        "seed": seed,
        "iterations": iterations,
        "demos": n_demos,
        "demos_dir": " + ".join(str(d) for d in folders),
        "demos_skipped": n_skipped,
        "validate_every": validate_every,
        "stop_after": stop_after,
        "time_budget_s": time_budget_s,
        "command": command
        or f"learning.experiments.train_il.train_il({setup.name!r}, seed={seed})",
    }
    start_iteration = int(state["agent"]["iteration"]) if state is not None else 0
    bar = progress_bar(cfg.iterations, start_iteration, setup.name, quiet)

    def say(message: str) -> None:
        with bar.external_write_mode():
            log(message)

    run = _ILRun(
        setup,
        out,
        train_args=train_args,
        last_iteration=cfg.iterations,
        validate_every=validate_every,
        stop_after=stop_after,
        time_budget_s=time_budget_s,
        rows=rows,
        history=history,
        say=say,
        tensorboard=tensorboard,
    )

    def callback(s: IterationStats, agent: GAILAgent) -> bool:
        stop = run.on_iteration(s, agent)
        run.log.write_scalars()  # the iteration's row, complete (validation included)
        advance(bar, s.mean_return, s.kl, run.history[-1] if run.history else None)
        return stop

    view = setup.gail.disc_observation

    def make_env(n: int) -> VectorEnv:
        env: VectorEnv
        if setup.task == "open-water":
            env = OpenWaterVectorEnv(
                n,
                observation=setup.observation,
                action=setup.action,
                family=setup.training_family,
                info_observation=None if view == "policy" else view,
            )
        else:
            env = PoleAvoidanceVectorEnv(n, observation=setup.observation, action=setup.action)
        if setup.radar_frames > 1:
            env = RadarMemoryVectorEnv(env, setup.radar_frames)
        return GoalMarkVectorEnv(env) if setup.goal_mark else env

    trainer: Any = train_gail
    if device != "cpu":
        trainer, make_env = train_gail_on_device, il_device_env_maker(setup, device)
    run.start = time.perf_counter()  # the clock counts GAIL, warm start included
    try:
        agent = trainer(
            setup.gail,
            cfg,
            make_env,
            data,
            callback=callback,
            state=state,
        )
        done = (agent.iteration, agent.env_steps)
    except KeyboardInterrupt:  # Ctrl-C / SIGTERM: a stop rule (checkpoints are the last ones)
        run.stop_reason = "interrupted"
        last = run.log.rows[-1] if run.log.rows else {"iteration": start_iteration, "env_steps": 0}
        done = (int(last["iteration"]), int(last["env_steps"]))
    finally:
        bar.close()
        run.log.write()
        run.log.close()
    return run.result(*done, run.wall_offset_s + run.session_s())


def expert_pairs(
    setup: ILSetup, demos_dirs: str | Path | Sequence[str | Path], log: Callable[[str], None]
) -> tuple[ExpertData, int, int]:
    """The (s, a) pairs of the demonstrations in the folders ``demos_dirs`` (their runs
    together) that pass the quality check, in
    ``setup``'s observation and action kinds; how many demonstrations that is, and how many
    files were skipped as unreadable or implausible (each named in a warning through ``log``).

    Raises
    ------
    DemoFormatError
        If no demonstration is left (the folder is empty, or every file is bad or rejected).
    """
    if isinstance(demos_dirs, str | Path):  # one folder
        demos_dirs = (demos_dirs,)
    where = " + ".join(str(d) for d in demos_dirs)
    recordings: list[Recording] = []
    errors: dict[str, str] = {}
    for folder in demos_dirs:
        found = load_recordings(folder)
        recordings += found.recordings
        errors.update(found.errors)
    plausible = []
    for rec in recordings:
        try:
            check_observations(
                expert_data([rec], setup.observation, setup.action), setup.observation
            )
        except (DemoFormatError, ValueError) as err:  # ValueError: streams too short to use
            errors[rec.source] = str(err)
            continue
        plausible.append(rec)
    for path, why in errors.items():
        log(f"warning: skipping {path}: {why}")
    report = LoadReport(plausible, errors)
    kept = [r for r in report.recordings if not quality_check(r)]
    total = len(report.recordings) + len(report.errors)
    if not kept:
        raise DemoFormatError(
            f"{where}: no usable demonstration (demo_*.csv files: {total}, unreadable or "
            f"implausible: {len(report.errors)}, rejected by the quality filter: "
            f"{len(report.recordings)})"
        )
    if setup.harsh_radar_copies:  # each run again at the harshest radar level (ILSetup)
        kept = kept + harsh_radar_runs(kept, setup.harsh_radar_copies)
    data = expert_data(kept, setup.observation, setup.action)
    if setup.gail.disc_observation != "policy":  # an asymmetric discriminator's view
        disc = expert_data(kept, setup.gail.disc_observation, setup.action)
        data = dataclasses.replace(data, disc_obs=disc.obs)
    if setup.radar_frames > 1:  # the images of each run stacked as the policy's memory will
        assert isinstance(data.obs, dict)
        stacked = stack_episode_frames(data.obs["radar"], data.episode, setup.radar_frames)
        data = dataclasses.replace(data, obs={**data.obs, "radar": stacked})
    if setup.goal_mark:  # the mark after the memory's channels, as GoalMarkVectorEnv draws it
        assert isinstance(data.obs, dict)
        data = dataclasses.replace(data, obs=with_goal_mark(data.obs))
    n_runs = len(kept) // (setup.harsh_radar_copies + 1)
    copies = (
        f", each also {setup.harsh_radar_copies}× at the harshest radar level"
        if setup.harsh_radar_copies
        else ""
    )
    log(
        f"{setup.name}: using {n_runs} of {total} demonstrations in {where} "
        f"({len(report.errors)} skipped as unreadable or implausible, "
        f"{len(report.recordings) - n_runs} rejected by the quality filter{copies}), "
        f"{len(data)} pairs"
    )
    return data, n_runs, len(report.errors)


def _resume_state(
    setup: ILSetup, path: Path
) -> tuple[ILSetup, dict[str, Any], list[dict[str, Any]]]:
    """The setup stored in ``path`` (a ``latest.pt`` of ``setup``), the agent and
    discriminator state to resume, and the validation history."""
    ck = load_checkpoint(path)
    if ck.setup != setup.name:
        raise CheckpointError(
            f"{path}: checkpoint is for setup {ck.setup!r}, expected {setup.name!r}"
        )
    gail_path = path.with_suffix(".gail.pt")
    if not gail_path.is_file():
        raise CheckpointError(f"{gail_path} is missing (the discriminator of {path.name})")
    stored = setup_from_params(setup, ck.setup_params)
    gail_state = torch.load(gail_path, weights_only=True)
    return stored, {"agent": ck.agent, "gail": gail_state}, ck.history


def _rank(rec: dict[str, Any]) -> tuple[int, int, float]:
    """Most successes on the 60 selection episodes first (the 15 validation episodes among
    them; :func:`usvsim.evaluation.episodes.selection_episodes` says why 15 are too few to
    choose among many 15/15 checkpoints), then on the 15, then the most expert-like path (the
    point of IL). A record from before the selection set (a resumed older run) ranks as if it
    had failed every extra episode. An open-water run's record (``family_successes``) ranks by
    the selection's, the family set's, the crowded set's and (radar) the harsh-radar set's
    successes together, then
    the 15's, then the mean return: never by likeness, which its closing comparison measures
    (issue 18)."""
    selection = int(rec.get("selection_successes", rec["successes"]))
    if "family_successes" in rec:
        total = selection + extra_successes(rec)
        return total, int(rec["successes"]), float(rec["mean_return"])
    d = rec.get("path_distance_m", math.inf)
    return selection, int(rec["successes"]), -d if math.isfinite(d) else -math.inf
