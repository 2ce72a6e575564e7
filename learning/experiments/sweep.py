"""Training sweeps: setups × seeds × hyperparameters, each trial one ``usvsim train`` run, under
Ray Tune (Liaw et al. 2018, "Tune: a research platform for distributed model selection and
training").

A sweep is a :class:`SweepSpec` (frozen: setups, seeds, a grid and/or random distributions over
any training field, the search algorithm, the run options, the rule that picks the shipped seed).
:func:`run_sweep` runs it into ``<root>`` (default ``usvsim-results/sweep/<name>``):

====================  ======================================================================
path                  contents
====================  ======================================================================
``sweep.json``        the spec, written before the first trial starts (the shipped-model rule
                      is fixed there, before any result exists)
``runs/<trial>/``     one ``usvsim train`` run folder per trial (``log.csv``, ``curve.png``,
                      ``latest.pt``, ``best.pt``, ``summary.json``) plus ``heldout.json``
``tune/``             Ray Tune's experiment state (what :meth:`ray.tune.Tuner.restore` reads)
``trials.json``       every trial's status (finished, crashed with its error, not run)
``sessions.json``     wall-clock of each session of the sweep
``report.md/.json``   the across-seed statistics (:mod:`learning.experiments.sweep_report`)
====================  ======================================================================

Each trial is :func:`run_trial`: it trains with :func:`learning.experiments.train_rl.train_rl` or
:func:`learning.experiments.train_il.train_il` (so the run folder is the one of ``usvsim train``),
continues from ``latest.pt`` when the folder has one (an interrupted trial resumes), skips
training when ``summary.json`` says the run ended, then evaluates ``best.pt`` on the held-out
episodes (:func:`usvsim.evaluation.episodes.heldout_episodes`) into ``heldout.json``. The
held-out result is *not* reported to Tune: the search objective (:data:`OBJECTIVE`) and the
shipped-model rule see validation only. Re-running the same sweep continues it
(:func:`ray.tune.Tuner.restore`, crashed trials retried from their ``latest.pt``). Ctrl-C and
SIGTERM stop it through Tune's own graceful stop. A local sweep (no ``address``) always starts a
Ray of its own (``ray.init(address="local")``), whatever other Ray runs on the machine.

Why this module is long: the run folder's layout, the trial function Ray calls, resuming and
the shipped-seed rule are one contract with ``usvsim sweep``; split, each part needs the others.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import itertools
import json
import math
import os
import signal
import threading
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

from learning.experiments.il_setups import ILSetup
from learning.experiments.run_log import VALIDATION_EPISODES
from learning.experiments.sweep_spec import (
    SETUP_GROUPS,
    Distribution,
    SweepSpec,
    apply_overrides,
    base_setup,
    expand_setups,
    parse_seeds,
    trial_dir_name,
)
from usvsim.common.fileio import atomic_write_text, remove_stale_temporaries
from usvsim.common.splits import selection_mode

__all__ = [
    "OBJECTIVE",
    "REPORT_EVERY_S",
    "SETUP_GROUPS",
    "Distribution",
    "SweepRun",
    "SweepSpec",
    "apply_overrides",
    "expand_setups",
    "expected_trials",
    "parse_seeds",
    "progress_metrics",
    "remove_trial_temporaries",
    "run_sweep",
    "run_trial",
    "trial_dir_name",
    "trial_metrics",
    "trial_resources",
    "validation_curve",
]

REPORT_EVERY_S = 2.0  # a running trial's progress report to Tune, s
OBJECTIVE = "val_auc"  # mean validation success rate over a run's validations (higher is better)


def validation_curve(log_csv: Path) -> list[dict[str, float]]:
    """The validations of a run's ``log.csv``: iteration, env steps, wall-clock (s), successes."""
    with log_csv.open(newline="") as handle:
        rows = [r for r in csv.DictReader(handle) if r.get("val_successes", "") != ""]
    return [
        {
            "iteration": int(r["iteration"]),
            "env_steps": int(r["env_steps"]),
            "wall_time_s": float(r["wall_time_s"]),
            "successes": int(r["val_successes"]),
        }
        for r in rows
    ]


def train_trial(config: Mapping[str, Any], out: Path) -> None:
    """Train (or resume) one trial's run into ``out``: the library behind ``usvsim train``."""
    import torch

    from learning.experiments.train_il import train_il
    from learning.experiments.train_rl import train_rl

    threads = int(config["threads"])
    torch.set_num_threads(threads)
    overrides = dict(config.get("overrides") or {})
    setup = apply_overrides(base_setup(config["setup"]), overrides)
    opts = dict(config["options"])
    if opts["n_envs"]:
        setup = setup.with_num_envs(int(opts["n_envs"]))
    resume = (out / "latest.pt").is_file()
    flags = [f"--seed {config['seed']}", f"--out {out}", f"--threads {threads}", "--quiet"]
    device = str(opts.pop("device", "cpu"))
    flags += [f"--{k.replace('_', '-')} {v}" for k, v in opts.items() if v and k != "stop_after"]
    flags += [f"--device {device}"] if device != "cpu" else []
    flags += [f"--stop-after {opts['stop_after']}"] + (["--resume"] if resume else [])
    command = f"usvsim train {config['setup']} " + " ".join(flags)
    if overrides:
        command = f"usvsim sweep trial ({command}; overrides {json.dumps(overrides)})"
    common: dict[str, Any] = {
        "seed": int(config["seed"]),
        "iterations": int(opts["iterations"]) or None,
        "resume": resume,
        "validate_every": int(opts["validate_every"]),
        "stop_after": int(opts["stop_after"]),
        "time_budget_s": float(opts["time_budget_s"]),
        "quiet": True,
        "command": command,
    }
    board = str(config.get("tensorboard", ""))  # _trainable's; "": none
    if isinstance(setup, ILSetup):
        train_il(setup, out, threads=threads, log=lambda _: None, tensorboard=board,
                 device=device, **common)  # fmt: skip
    else:
        args = {**common, "overrides": overrides, "device": device}
        train_rl(setup, out, train_args=args, tensorboard=board, device=device, **common)


def _evaluate_heldout(out: Path, n: int) -> dict[str, Any]:
    """``best.pt`` on the first ``n`` held-out episodes, written to ``out/heldout.json``."""
    path = out / "heldout.json"
    if path.is_file():
        cached = json.loads(path.read_text())
        if cached["episodes"] == n and cached["best_mtime"] == (out / "best.pt").stat().st_mtime:
            return dict(cached)
    from usvsim.evaluation.episodes import evaluate, heldout_episodes
    from usvsim.helm.registry import helmsman_kinds, make_helmsman

    if not (out / "best.pt").is_file():
        raise FileNotFoundError(
            f"{out / 'best.pt'} missing: the run stopped before its first validation (time budget?)"
        )
    helmsman = make_helmsman(str(out / "best.pt"))
    observation, action = helmsman_kinds(helmsman)
    records = evaluate(helmsman, heldout_episodes(n=n), observation=observation, action=action)
    successes = int(sum(r.success for r in records))
    result = {
        "episodes": n,
        "successes": successes,
        "success_rate": successes / n,
        "collisions": int(sum(r.collision for r in records)),
        "best_mtime": (out / "best.pt").stat().st_mtime,
    }
    atomic_write_text(path, json.dumps(result, indent=2) + "\n")
    return result


def run_trial(config: dict[str, Any]) -> dict[str, Any]:
    """One trial (module docstring): train or resume, evaluate ``best.pt`` on held-out; the
    *validation* metrics that go to Tune (:func:`trial_metrics`)."""
    out = Path(config["root"]) / "runs" / config["dir"]
    out.mkdir(parents=True, exist_ok=True)
    if not (out / "summary.json").is_file():
        train_trial(config, out)
    _evaluate_heldout(out, int(config["heldout"]))
    return trial_metrics(out)


@selection_mode("sweep trial_metrics")
def trial_metrics(out: Path) -> dict[str, Any]:
    """The validation-only metrics of a finished run folder (what Tune and the search see)."""
    curve = validation_curve(out / "log.csv")
    summary = json.loads((out / "summary.json").read_text())
    successes = [c["successes"] for c in curve]
    first = summary.get("first_15_of_15")
    return {
        OBJECTIVE: sum(successes) / (VALIDATION_EPISODES * len(successes)) if curve else 0.0,
        "val_best_successes": max(successes, default=0),
        "iterations": int(summary["iterations"]),
        "env_steps": int(summary["env_steps"]),
        "train_wall_s": float(summary["wall_time_s"]),
        "first_full_iteration": int(first["iteration"]) if first else -1,
    }


@dataclass(frozen=True)
class SweepRun:
    """Where and how a sweep runs (not part of its definition)."""

    root: Path  # the sweep folder
    address: str = ""  # an existing Ray cluster (ray://host:10001 or host:6379); "": local
    max_concurrent: int = 0  # trials at once; 0: as many as the CPUs allow
    progress_every_s: float = 30.0
    say: Any = field(default=print)  # one line of progress
    # a folder: each trial also writes TensorBoard scalars into <tensorboard>/<trial> ("": none;
    # learning.experiments.run_log.RunLog)
    tensorboard: str = ""
    # the share of a GPU each trial asks Ray for (Tune resources; 0.25: four trials a GPU);
    # 0: none (a cuda sweep asks for it)
    gpus_per_trial: float = 0.0


def _param_space(spec: SweepSpec, root: Path) -> dict[str, Any]:
    from ray import tune

    overrides: dict[str, Any] = {k: tune.grid_search(list(v)) for k, v in spec.grid}
    overrides.update({k: d.to_tune() for k, d in spec.random})
    options = {
        "iterations": spec.iterations,
        "validate_every": spec.validate_every,
        "stop_after": spec.stop_after,
        "n_envs": spec.n_envs,
        "time_budget_s": spec.time_budget_s,
        "device": spec.device,
    }
    space = {
        "setup": spec.setups[0] if spec.search == "optuna" else tune.grid_search(list(spec.setups)),
        "seed": spec.seeds[0] if spec.search == "optuna" else tune.grid_search(list(spec.seeds)),
        "overrides": overrides,
        "options": options,
        "root": str(root),
        "threads": spec.threads,
        "heldout": spec.heldout,
        "search": spec.search,
    }
    return space


def _trainable(spec: SweepSpec, tensorboard: str = "", gpus: float = 0.0) -> Any:
    """The Tune function of a trial: :func:`run_trial` in a daemon thread, a progress report
    to Tune every :data:`REPORT_EVERY_S` (so Tune can stop the trial between two reports: a
    Ctrl-C ends the sweep within seconds, the run keeps its last ``latest.pt``), then the
    final metrics. An exception of the run fails the trial (Tune: ERROR, reported).
    ``tensorboard`` (a folder, :attr:`SweepRun.tensorboard`): the trial's TensorBoard scalars
    go to its subfolder named as the trial's run folder. ``gpus``: the GPU share a trial asks
    Ray for (:attr:`SweepRun.gpus_per_trial`), beside its ``threads`` CPUs."""
    from ray import tune

    board = str(Path(tensorboard).resolve()) if tensorboard else ""  # trials run elsewhere

    def trial(config: dict[str, Any]) -> None:
        config = dict(config)
        config["dir"] = trial_dir_name(
            config["setup"], int(config["seed"]), config["overrides"], config["search"]
        )
        if board:
            config["tensorboard"] = str(Path(board) / config["dir"])
        out = Path(config["root"]) / "runs" / config["dir"]
        outcome: dict[str, Any] = {}

        def work() -> None:
            try:
                outcome["metrics"] = run_trial(config)
            except BaseException as err:  # handed to the trial's thread below, re-raised there
                outcome["error"] = err

        worker = threading.Thread(target=work, name=f"trial {config['dir']}", daemon=True)
        worker.start()
        while worker.is_alive():
            worker.join(REPORT_EVERY_S)
            if worker.is_alive():
                tune.report(progress_metrics(out))
        if "error" in outcome:
            raise outcome["error"]
        tune.report(outcome["metrics"])

    return tune.with_resources(trial, trial_resources(spec, gpus))


def trial_resources(spec: SweepSpec, gpus: float = 0.0) -> dict[str, float]:
    """What a trial asks Ray for: its ``threads`` CPUs, and ``gpus`` of a GPU where > 0."""
    resources: dict[str, float] = {"cpu": spec.threads}
    if gpus > 0:
        resources["gpu"] = gpus
    return resources


def progress_metrics(out: Path) -> dict[str, Any]:
    """What a running trial reports to Tune: its last iteration and validations so far."""
    try:
        curve = validation_curve(out / "log.csv")
    except (OSError, KeyError, ValueError):  # no log yet, or one being replaced
        curve = []
    successes = [c["successes"] for c in curve]
    return {
        OBJECTIVE: sum(successes) / (VALIDATION_EPISODES * len(successes)) if curve else 0.0,
        "val_best_successes": max(successes, default=0),
        "iterations": curve[-1]["iteration"] if curve else 0,
    }


def _init_ray(spec: SweepSpec, where: SweepRun) -> bool:
    """Connect to ``where.address`` or start a Ray of the sweep's own; True if this call started
    a local Ray (the sweep shuts it down when it ends), False if Ray was already initialised or
    is a cluster's."""
    import logging

    import ray

    if ray.is_initialized():
        return False
    if where.address:
        ray.init(address=where.address, log_to_driver=False, logging_level=logging.WARNING)
        return False
    cpus = os.cpu_count() or 1
    if where.max_concurrent:
        cpus = min(cpus, where.max_concurrent * spec.threads) or spec.threads
    ray.init(
        address="local",  # a Ray of its own, even where another runs or a stale one is recorded
        num_cpus=max(cpus, spec.threads),
        include_dashboard=False,
        log_to_driver=False,
        logging_level=logging.WARNING,
        configure_logging=False,
    )
    return True


def _tuner(spec: SweepSpec, where: SweepRun) -> Any:
    from ray import tune

    from learning.experiments.sweep_progress import Progress
    from learning.experiments.sweep_search import (
        SessionLimitedGenerator,
        SessionLimiter,
        set_session_limit,
    )

    # this session's --max-concurrent, also for a continued sweep (Tune restores the first
    # session's search algorithm; sweep_search says why its cap is read from here)
    set_session_limit(where.max_concurrent)
    storage = where.root / "tune"
    if tune.Tuner.can_restore(str(storage / "sweep")):
        where.say(f"continuing the sweep in {where.root} (Tune state in {storage})")
        return tune.Tuner.restore(
            str(storage / "sweep"),
            trainable=_trainable(spec, where.tensorboard, where.gpus_per_trial),
            resume_unfinished=True,
            resume_errored=True,
        )
    if spec.search == "optuna":
        from ray.tune.search.optuna import OptunaSearch

        search_alg: Any = OptunaSearch(metric=OBJECTIVE, mode="max", seed=spec.search_seed)
        search_alg = SessionLimiter(search_alg, max_concurrent=max(1, where.max_concurrent))
    else:
        search_alg = SessionLimitedGenerator(random_state=spec.search_seed)
    return tune.Tuner(
        _trainable(spec, where.tensorboard, where.gpus_per_trial),
        param_space=_param_space(spec, where.root),
        tune_config=tune.TuneConfig(
            search_alg=search_alg,
            num_samples=spec.samples,
            metric=OBJECTIVE,
            mode="max",
        ),
        run_config=tune.RunConfig(
            name="sweep",
            storage_path=str(storage.resolve()),
            verbose=0,
            callbacks=[
                Progress(where.root, where.say, where.progress_every_s, expected_trials(spec))
            ],
            failure_config=tune.FailureConfig(max_failures=0),
        ),
    )


def run_sweep(spec: SweepSpec, where: SweepRun) -> list[dict[str, Any]]:
    """Run (or continue) ``spec`` into ``where.root``; the status of every trial.

    Writes ``sweep.json`` first; a folder holding a different spec raises ``ValueError``.
    Returns one dict per trial: ``setup``, ``seed``, ``overrides``, ``dir``, ``status``
    (``finished``, ``crashed`` or ``not run``) and ``error``; also written to ``trials.json``.
    """
    root = where.root.resolve()
    where = dataclasses.replace(where, root=root)
    root.mkdir(parents=True, exist_ok=True)
    stored = root / "sweep.json"
    if stored.is_file():
        old = json.loads(stored.read_text())
        if old != spec.to_json():
            raise ValueError(
                f"{stored} holds a different sweep; use another --name or the same options"
            )
    else:
        atomic_write_text(stored, json.dumps(spec.to_json(), indent=2) + "\n")
    own_ray = _init_ray(spec, where)
    t0 = time.time()
    with _sigterm_as_ctrl_c():
        results = _tuner(spec, where).fit()
    if own_ray:  # end the trials' worker processes before cleaning up after them
        import ray

        ray.shutdown()
    remove_trial_temporaries(root)
    trials = []
    for result in results:
        config = result.config or {}
        if "setup" not in config:
            continue
        dir_name = trial_dir_name(
            config["setup"], int(config["seed"]), config["overrides"], config["search"]
        )
        done = (root / "runs" / dir_name / "heldout.json").is_file()
        status = "finished" if done and result.error is None else "not run"
        if result.error is not None:
            status = "crashed"
        trials.append(
            {
                "setup": config["setup"],
                "seed": int(config["seed"]),
                "overrides": dict(config["overrides"]),
                "dir": dir_name,
                "status": status,
                "error": "" if result.error is None else _one_line(result.error),
            }
        )
    trials += _never_started(spec, {t["dir"] for t in trials})
    atomic_write_text(root / "trials.json", json.dumps(trials, indent=2) + "\n")
    sessions_path = root / "sessions.json"
    sessions = json.loads(sessions_path.read_text()) if sessions_path.is_file() else []
    finished = sum(t["status"] == "finished" for t in trials)
    sessions.append({"start": t0, "wall_s": time.time() - t0, "finished_trials": finished})
    atomic_write_text(sessions_path, json.dumps(sessions, indent=2) + "\n")
    return trials


def remove_trial_temporaries(root: Path) -> list[Path]:
    """Remove what stopped trials were writing when their workers were killed (a
    ``.curve.png.*.tmp`` of a plot in progress, a staging folder) from every run folder under
    ``root/runs``, so an interrupted sweep leaves only whole files (``latest.pt`` and ``log.csv``
    are written atomically and stay). Returns what was removed."""
    runs = root / "runs"
    if not runs.is_dir():
        return []
    return [p for run in sorted(runs.iterdir()) for p in remove_stale_temporaries(run)]


@contextlib.contextmanager
def _sigterm_as_ctrl_c() -> Iterator[None]:
    """SIGTERM stops the sweep as Ctrl-C does: Tune's own graceful stop (its state saved, the
    trials ended at their last report, ``trials.json`` written). Outside the main thread (where
    Tune catches no signal either) nothing changes."""

    def forward(signum: int, frame: FrameType | None) -> None:
        signal.raise_signal(signal.SIGINT)  # Tune's SIGINT handler, installed during fit()

    try:
        previous = signal.signal(signal.SIGTERM, forward)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def expected_trials(spec: SweepSpec) -> int:
    """How many trials ``spec`` runs: setups × seeds × grid points × samples (optuna: samples)."""
    if spec.search == "optuna":
        return spec.samples
    points = math.prod(len(v) for _, v in spec.grid)
    return len(spec.setups) * len(spec.seeds) * points * spec.samples


def _never_started(spec: SweepSpec, known: set[str]) -> list[dict[str, Any]]:
    """The trials Tune had not created yet when a sweep was interrupted: named for a grid,
    anonymous (``dir`` "") for random draws not drawn yet."""
    if spec.search != "grid":
        return [_pending("", 0, {}, "")] * max(0, expected_trials(spec) - len(known))
    keys = [k for k, _ in spec.grid]
    out = []
    for setup, seed, *values in itertools.product(
        spec.setups, spec.seeds, *(v for _, v in spec.grid)
    ):
        overrides = dict(zip(keys, values, strict=True))
        name = trial_dir_name(setup, seed, overrides, "grid")
        if name not in known:
            out.append(_pending(setup, seed, overrides, name))
    return out


def _pending(setup: str, seed: int, overrides: dict[str, Any], name: str) -> dict[str, Any]:
    return {
        "setup": setup,
        "seed": seed,
        "overrides": overrides,
        "dir": name,
        "status": "not run",
        "error": "",
    }


def _one_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    last = [line for line in text if line.strip()][-1] if text else type(error).__name__
    return last[:300]
