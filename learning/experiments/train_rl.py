"""One RL training run (``usvsim train rl-*``): the setup's algorithm (TRPO) through the generic
loop (:func:`learning.algorithms.loop.train`), validation every ``validate_every`` iterations,
checkpoints, early stop, and the run's files (``log.csv``, ``curve.png``, ``latest.pt``,
``best.pt``, ``summary.json``; table in :mod:`learning.cli.train`).

``log.csv`` columns (:func:`csv_fields`): :data:`COMMON_FIELDS`, then the algorithm's
``UpdateStats.LOG_FIELDS`` (TRPO: kl, entropy, surrogate_improvement, line_search_accepted,
value_loss), then :data:`VALIDATION_FIELDS` (filled on validation iterations), then
:data:`TIME_FIELDS`: where the iteration's wall-clock went, s (rollout, batch, policy step,
critic; :mod:`learning.algorithms.loop`), and for a setup on the open-water family
:data:`FAMILY_FIELDS` (its family validation set, :mod:`learning.experiments.validation`) and
:data:`CROWDED_FIELDS` (its crowded set), for a radar one there also :data:`RADAR_FIELDS` (its
harsh-radar validation set); see
:func:`open_water_fields`.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import torch

from learning.algorithms.base import Agent, log_row
from learning.algorithms.loop import IterationStats, time_row, train
from learning.algorithms.registry import get_algorithm
from learning.algorithms.rollout import NonFiniteError
from learning.experiments.checkpoint import (
    Checkpoint,
    CheckpointError,
    NonFiniteWeightsError,
    load_checkpoint,
    save_checkpoint,
    starting_policy,
)
from learning.experiments.memory_start import check_cpu_only_options
from learning.experiments.run_log import Milestones, RunLog, advance, progress_bar, read_log_rows
from learning.experiments.setups import RLSetup, setup_from_params
from learning.experiments.validation import (
    RunResult,
    family_passed,
    finish_run,
    selection_key,
    validate,
    validation_record,
)
from usvsim.common.fileio import remove_stale_temporaries
from usvsim.common.splits import selection_mode

__all__ = [
    "COMMON_FIELDS",
    "CROWDED_FIELDS",
    "DEVICES",
    "FAMILY_FIELDS",
    "RADAR_FIELDS",
    "TIME_FIELDS",
    "VALIDATION_FIELDS",
    "csv_fields",
    "device_env_maker",
    "env_maker",
    "first_policy",
    "il_device_env_maker",
    "open_water_fields",
    "train_rl",
]

COMMON_FIELDS = ("iteration", "env_steps", "wall_time_s", "episodes", "mean_return", "mean_length")
VALIDATION_FIELDS = ("val_successes", "val_mean_return", "val_min_pole_distance_m")
TIME_FIELDS = ("rollout_s", "batch_s", "policy_step_s", "critic_s")  # of loop.TIME_FIELDS
FAMILY_FIELDS = (  # open-water setups: validation.family_summary
    "val_family_successes",
    "val_family_n_episodes",
    "val_family_collisions",
    "val_family_min_distance_m",
)
CROWDED_FIELDS = tuple(f.replace("_family_", "_crowded_") for f in FAMILY_FIELDS)
RADAR_FIELDS = tuple(f.replace("_family_", "_radar_") for f in FAMILY_FIELDS)  # radar setups


DEVICES = ("cpu", "torch-cpu", "cuda")  # where ``train_rl(device=...)`` steps the env and trains
DEVICE_DTYPES = {"torch-cpu": "float64", "cuda": "float32"}  # the torch env's simulation type


#: Episodes each boat of an open-water torch env draws at its reset (its table then cycles)
#: for at most this many boats in all; at least 16 a boat (host draws: ~0.1 ms an episode).
OPEN_WATER_TABLE_EPISODES = 1 << 16


def device_env_maker(setup: RLSetup, device: str) -> Any:
    """``make_env(num_envs)`` of the torch env for ``setup`` on ``device`` (``"torch-cpu"`` or
    ``"cuda"``: :mod:`learning.algorithms.device_loop`): the study task's for the positional
    setups, the open-water one for the open-water scene and radar+goal setups (the setup's
    training family, drawn on the host at reset as the CPU env draws it,
    :data:`OPEN_WATER_TABLE_EPISODES` episodes in all; the fixed reward horizon with each
    episode's own time limit; the setup's COLREG reward terms, :mod:`usvsim.task.torch_colreg`;
    reactive targets steered on the host, :mod:`usvsim.evaluation.torch_reactive`).
    ``ValueError`` for a setup it cannot train (the study task's radar, PPO, a safety-margin
    reward)."""
    if device not in DEVICE_DTYPES:
        raise ValueError(f"device must be one of {DEVICES}, got {device!r}")
    trainable = setup.algorithm == "trpo" and (
        (setup.task != "open-water" and setup.observation == "positional")
        or (setup.task == "open-water" and setup.observation in ("scene", "radar+goal"))
    )
    if not trainable:
        raise ValueError(
            f"--device {device} is for the TRPO positional setups (rl-gaussian-positional, "
            "rl-categorical-positional) and the open-water scene and radar setups (rl-*-scene-ow, "
            f"rl-*-radar-ow and their -ft, -cont; the -colreg setups), not {setup.name!r}"
        )
    if setup.safety_reward or setup.success_reward or setup.aim_reward:
        raise ValueError(
            f"--device {device}: the torch env has no safety-margin, success or aim reward "
            f"(RLSetup.safety_reward, success_reward, aim_reward; {setup.name!r}); train it "
            "with --device cpu"
        )
    if setup.task == "open-water":
        from usvsim.evaluation.torch_reactive import DeviceReactiveTargets
        from usvsim.task.torch_openwater import TorchOpenWaterEnv

        def make_open_water(num_envs: int) -> Any:
            return TorchOpenWaterEnv(
                num_envs,
                family=setup.training_family,
                per_boat=max(16, OPEN_WATER_TABLE_EPISODES // num_envs),
                device=device,
                dtype=DEVICE_DTYPES[device],
                action=setup.action,
                observation=setup.observation,
                reward_horizon="fixed",
                gamma=setup.algorithm_config.gamma,
                colreg_reward=setup.colreg_weights,
                on_decision=DeviceReactiveTargets() if setup.reactive_targets else None,
            )

        return make_open_water
    from usvsim.task.torch_env import TorchPoleAvoidanceEnv

    def make_env(num_envs: int) -> Any:
        return TorchPoleAvoidanceEnv(
            num_envs,
            device=device,
            dtype=DEVICE_DTYPES[device],
            action=setup.action,
            observation=setup.observation,
        )

    return make_env


def il_device_env_maker(setup: Any, device: str) -> Any:
    """``make_env(num_envs)`` of the torch env a GAIL run of ``setup`` steps on ``device``
    (``"torch-cpu"`` or ``"cuda"``): the study task's for the positional setups, the open-water
    one on the setup's training family for the ``-ow`` and ``-colreg`` setups, episode rewards
    (GAIL replaces them), with the scene in ``info`` where the discriminator sees it
    (``disc_observation="scene"``). ``ValueError`` for a setup it cannot train: the study
    task's radar."""
    if device not in DEVICE_DTYPES:
        raise ValueError(f"device must be one of {DEVICES}, got {device!r}")
    open_water = setup.task == "open-water" and setup.observation in ("scene", "radar+goal")
    study = setup.task != "open-water" and setup.observation == "positional"
    if not (open_water or study):
        raise ValueError(
            f"--device {device} trains GAIL for the IL positional and open-water setups "
            f"(il-*-positional, il-*-ow, il-*-colreg), not {setup.name!r}"
        )
    dtype = DEVICE_DTYPES[device]
    if open_water:
        from usvsim.task.torch_openwater import TorchOpenWaterEnv

        return lambda n: TorchOpenWaterEnv(
            n, family=setup.training_family, per_boat=max(16, OPEN_WATER_TABLE_EPISODES // n),
            device=device, dtype=dtype, action=setup.action, observation=setup.observation,
            info_observation=None if setup.gail.disc_observation == "policy" else "scene",
        )  # fmt: skip
    from usvsim.task.torch_env import TorchPoleAvoidanceEnv

    return lambda n: TorchPoleAvoidanceEnv(
        n, device=device, dtype=dtype, action=setup.action, observation=setup.observation
    )


def open_water_fields(setup: Any) -> tuple[str, ...]:
    """The validation columns a setup on the open-water family adds (RL and IL): the family
    and crowded sets', and for a radar observation the harsh-radar set's; () for the pole
    task."""
    if setup.task != "open-water":
        return ()
    radar = RADAR_FIELDS if setup.observation.startswith("radar") else ()
    return FAMILY_FIELDS + CROWDED_FIELDS + radar


def csv_fields(setup: RLSetup) -> tuple[str, ...]:
    """The ``log.csv`` columns of a run of ``setup`` (module docstring)."""
    stats = get_algorithm(setup.algorithm).stats_type
    fields = COMMON_FIELDS + stats.LOG_FIELDS + VALIDATION_FIELDS + TIME_FIELDS
    return fields + open_water_fields(setup)


class _Run:
    """State of one training run: files, log rows, validation history, the stopping rule."""

    def __init__(
        self,
        setup: RLSetup,
        out: Path,
        rows: list[dict[str, Any]],
        *,
        train_args: dict[str, Any],
        validate_every: int,
        stop_after: int,
        time_budget_s: float,
        tensorboard: str | Path = "",
    ) -> None:
        self.setup, self.out, self.train_args = setup, out, train_args
        self.log = RunLog(out, csv_fields(setup), setup.name, rows, tensorboard=tensorboard)
        self.rows = self.log.rows
        self.history: list[dict[str, Any]] = []
        self.best: tuple[bool, int, float] | None = None
        self.milestones = Milestones()
        self.stop_reason = "iterations"
        self.wall_offset_s = 0.0  # wall-clock of the run before a resume
        self.validate_every = validate_every or setup.validate_every
        self.stop_after, self.time_budget_s = stop_after, time_budget_s

    def restore(self, history: list[dict[str, Any]]) -> None:
        """Continue the validation bookkeeping of a resumed run from its stored history."""
        self.history = list(history)
        self.wall_offset_s = float(history[-1]["wall_time_s"]) if history else 0.0
        for h in history:
            self.milestones.add(h)
            key = selection_key(h)
            self.best = key if self.best is None or key > self.best else self.best

    def on_iteration(self, stats: IterationStats, agent: Agent) -> bool:
        wall = self.wall_offset_s + stats.wall_time_s
        row: dict[str, Any] = {
            "iteration": stats.iteration,
            "env_steps": stats.env_steps,
            "wall_time_s": round(wall, 3),
            "episodes": stats.episodes,
            "mean_return": stats.mean_return,
            "mean_length": stats.mean_length,
            **log_row(stats.update),
            **time_row(stats, TIME_FIELDS),
        }
        self.rows.append(row)
        stop = False
        if stats.iteration % self.validate_every == 0:
            stop = self._validate(stats, agent, row, wall)
        if not stop and 0 < self.time_budget_s <= wall:  # the run's wall-clock, resumes included
            self.stop_reason, stop = "time budget", True
        return stop

    def _validate(
        self, stats: IterationStats, agent: Agent, row: dict[str, Any], wall: float
    ) -> bool:
        val = validate(agent, self.setup)
        record = validation_record(row, wall, val, kl=stats.kl, entropy=stats.entropy)
        self.milestones.add(record)
        ckpt = Checkpoint.from_agent(
            agent,
            self.setup,
            train_args=self.train_args,
            validation=record,
            history=[*self.history, record],
        )
        save_checkpoint(ckpt, self.out / "latest.pt")
        # only now: summary.json's checkpoint_iteration (history[-1]) must be what latest.pt holds
        # even when a Ctrl-C lands inside the save
        self.history.append(record)
        key = selection_key(val)
        if self.best is None or key > self.best:
            self.best = key
            save_checkpoint(ckpt, self.out / "best.pt")
        self.log.write(plot=self.log.plot_due())
        reason = self.milestones.stop_reason(self.stop_after) if family_passed(val) else ""
        if reason:
            self.stop_reason = reason
            return True
        return False

    def result(
        self, iterations: int, env_steps: int, wall_s: float, seed: int, command: str
    ) -> RunResult:
        """Write ``summary.json`` (JSON without NaN: null); the run's :class:`RunResult`."""
        best = None
        if self.best is not None:
            best = {"successes": self.best[1], "mean_return": self.best[2]}
        summary = {
            "setup": self.setup.name,
            "seed": seed,
            "command": command,
            "iterations": iterations,
            "env_steps": env_steps,
            "wall_time_s": wall_s,
            "stop_reason": self.stop_reason,
            "interrupted": self.stop_reason == "interrupted",
            "checkpoint_iteration": int(self.history[-1]["iteration"]) if self.history else None,
            "first_15_of_15": self.milestones.first_full,
            "best": best,
            "study_iterations": self.setup.study_iterations,
            "threads": torch.get_num_threads(),
        }
        return finish_run(
            self.out,
            summary,
            best,
            self.history,
            (iterations, env_steps, wall_s),
            self.stop_reason,
            self.milestones.first_full,
        )


def env_maker(setup: RLSetup) -> Any:
    """The training env maker: ``setup.make_vector_env``, for a setup with
    ``reactive_targets`` with the targets steered by vo
    (:class:`usvsim.evaluation.colreg_rollout.TrainingReactiveTargets`, the env's
    ``on_decision`` hook; the setups module may not import the evaluation)."""
    if not setup.reactive_targets:
        return setup.make_vector_env
    from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets

    def make_env(num_envs: int, **env_kwargs: Any) -> Any:
        env_kwargs.setdefault("on_decision", TrainingReactiveTargets())
        return setup.make_vector_env(num_envs, **env_kwargs)

    return make_env


def first_policy(setup: RLSetup, init_policy: str | Path = "") -> dict[str, Any] | None:
    """The agent state a new run of ``setup`` starts from (:func:`train_rl`), or None; raises
    :class:`CheckpointError` where that file cannot start it."""
    from usvsim.helm.registry import model_path

    if init_policy:
        return starting_policy(init_policy, setup)
    if setup.init_policy:  # a shipped model, by its setup's name (a former name)
        return starting_policy(model_path(setup.init_policy), setup)
    return None


@selection_mode("train_rl")  # training, validations, best.pt and early stops: no test episode
def train_rl(
    setup: RLSetup,
    out_dir: str | Path,
    *,
    seed: int = 0,
    iterations: int | None = None,
    resume: bool = False,
    validate_every: int = 0,
    stop_after: int = 3,
    time_budget_s: float = 0.0,
    quiet: bool = True,
    train_args: dict[str, Any] | None = None,
    command: str = "",
    init_policy: str | Path = "",
    tensorboard: str | Path = "",
    device: str = "cpu",
) -> RunResult:
    """Train ``setup`` into ``out_dir`` (module docstring).

    ``device`` (:data:`DEVICES`): ``"cpu"`` steps the CPU env with NumPy arrays (the
    default); ``"torch-cpu"`` / ``"cuda"`` train a TRPO positional setup with the study task's
    torch env, rollouts, GAE and the update on that device
    (:func:`learning.algorithms.device_loop.train_on_device`); validation stays on the CPU env.

    A new run starts from the policy of ``init_policy`` (a checkpoint file; "": the setup's
    ``init_policy``, a shipped model's name; both empty: new networks), with its own critic.

    Validation every ``validate_every`` iterations (0: the setup's); the run stops after
    ``stop_after`` consecutive 15/15 validations (0: never) or once the run has taken
    ``time_budget_s`` of wall-clock (0: no limit), counted as ``log.csv``'s ``wall_time_s``:
    from the run's start, a resumed part added to the time up to the checkpoint it resumed
    from (as ``iterations`` counts the run's iterations, not a session's). ``resume``
    continues from ``out_dir/latest.pt`` with the setup, hyperparameters and seed stored
    there (the ``seed`` argument is then ignored; ``summary.json`` records the seed really
    used) and keeps ``log.csv`` up to its iteration.
    ``train_args`` go into the checkpoints, ``command`` into ``summary.json``. ``tensorboard``
    (a folder; "": none): also every ``log.csv`` row as TensorBoard scalars there
    (:class:`learning.experiments.run_log.RunLog`).

    Ctrl-C (``KeyboardInterrupt``, also SIGTERM under ``usvsim``) ends the run like a stop rule:
    ``log.csv`` and ``summary.json`` are written (stop reason ``"interrupted"``,
    ``"interrupted": true``), ``latest.pt`` and ``best.pt`` stay those of the last validation
    (``checkpoint_iteration``), and the result is returned.

    Raises ``CheckpointError`` when ``resume`` finds no usable full checkpoint of ``setup``, and
    ``NonFiniteError`` / ``NonFiniteWeightsError`` (after writing ``log.csv``, naming the
    iteration) when an update goes non-finite; nothing is saved after such a failure.
    """
    out = Path(out_dir)
    state: dict[str, Any] | None = None
    rows: list[dict[str, Any]] = []
    history: list[dict[str, Any]] = []
    if resume:
        ckpt = load_checkpoint(out / "latest.pt", expected_setup=setup)
        if ckpt.slim:
            raise CheckpointError(f"{out / 'latest.pt'}: slim checkpoint (no critic)")
        setup = setup_from_params(setup, ckpt.setup_params)
        state, history = ckpt.agent, ckpt.history
        rows = read_log_rows(out / "log.csv", int(state["iteration"]))
    config = setup.run_config(seed, iterations)
    if state is not None:
        config = dataclasses.replace(config, seed=int(state["config"]["seed"]))
    start = first_policy(setup, init_policy) if state is None else None
    trainer: Any = train
    make_env: Any = env_maker(setup)
    check_cpu_only_options(setup, device)
    if device != "cpu":
        from learning.algorithms.device_loop import train_on_device

        trainer, make_env = train_on_device, device_env_maker(setup, device)
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(out)  # half-written files of a killed earlier run
    r = _Run(
        setup,
        out,
        rows,
        train_args=dict(train_args or {}),
        validate_every=validate_every,
        stop_after=stop_after,
        time_budget_s=time_budget_s,
        tensorboard=tensorboard,
    )
    r.restore(history)
    start_iteration = int(state["iteration"]) if state is not None else 0
    bar = progress_bar(config.iterations, start_iteration, setup.name, quiet)

    def callback(stats: IterationStats, agent: Agent) -> bool:
        stop = r.on_iteration(stats, agent)
        r.log.write_scalars()  # the iteration's row, complete (validation included)
        advance(bar, stats.mean_return, stats.kl, r.history[-1] if r.history else None)
        return stop

    t0 = time.perf_counter()
    try:
        agent = trainer(config, make_env, callback=callback, state=state, warm_start=start)
        iterations, env_steps = agent.iteration, agent.env_steps
    except (NonFiniteError, NonFiniteWeightsError) as err:
        r.log.write()
        r.log.close()
        raise type(err)(f"{err}; stopped at iteration {len(r.rows) + 1}") from err
    except KeyboardInterrupt:
        r.stop_reason = "interrupted"
        stored_steps = int(state.get("env_steps", 0)) if state is not None else 0
        last = r.rows[-1] if r.rows else {"iteration": start_iteration, "env_steps": stored_steps}
        iterations, env_steps = int(last["iteration"]), int(last["env_steps"])
    finally:
        bar.close()
    wall = r.wall_offset_s + time.perf_counter() - t0
    r.log.write()
    r.log.close()
    return r.result(iterations, env_steps, wall, config.seed, command)
