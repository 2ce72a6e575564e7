"""Validation of a policy during training, shared by RL and IL runs: the deterministic policy on
the study's 15 validation episodes (:func:`usvsim.evaluation.episodes.validation_episodes`), its
summary, and the record a validation leaves in the checkpoints' history and ``summary.json``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.algorithms.base import Agent
from learning.experiments.checkpoint import PolicyHelmsman
from usvsim.common.fileio import atomic_write_text, json_safe
from usvsim.evaluation.episodes import EpisodeRecord, evaluate, validation_episodes
from usvsim.task.scenario import EpisodeSpec

__all__ = ["RunResult", "validate", "validation_record", "validation_summary"]


def validate(
    agent: Agent, setup: Any, specs: Sequence[EpisodeSpec] | None = None
) -> dict[str, float]:
    """The deterministic policy of ``agent`` on ``specs`` (default: the 15 validation episodes)
    in ``setup``'s observation and action kinds: :func:`validation_summary`."""
    return validation_summary(policy_records(agent, setup, specs))


def policy_records(
    agent: Agent, setup: Any, specs: Sequence[EpisodeSpec] | None = None
) -> list[EpisodeRecord]:
    """The episode records of ``agent``'s deterministic policy on ``specs`` (default: the 15
    validation episodes)."""
    return evaluate(
        PolicyHelmsman(agent, setup.observation, setup.action),
        validation_episodes() if specs is None else specs,
        observation=setup.observation,
        action=setup.action,
    )


def validation_summary(records: Sequence[EpisodeRecord]) -> dict[str, float]:
    """Successes, episodes, mean return and the closest pole approach (m) of ``records``."""
    returns = [float(np.sum(r.reward_pole) + np.sum(r.reward_goal)) for r in records]
    return {
        "successes": int(sum(r.success for r in records)),
        "n_episodes": len(records),
        "mean_return": float(np.mean(returns)),
        "min_pole_distance_m": float(min(r.min_pole_distance_m for r in records)),
    }


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


@dataclass
class RunResult:
    """The outcome of a training run (RL or IL): validation records, checkpoints, where and
    why it ended."""

    best: dict[str, Any] | None
    history: list[dict[str, Any]]
    best_path: Path
    last_path: Path
    iterations: int
    env_steps: int
    wall_time_s: float
    stop_reason: str
    first_full: dict[str, Any] | None  # the first 15/15 validation record


def finish_run(
    out: Path,
    summary: dict[str, Any],
    best: dict[str, Any] | None,
    history: list[dict[str, Any]],
    progress: tuple[int, int, float],
    stop_reason: str,
    first_full: dict[str, Any] | None,
) -> RunResult:
    """Write ``out/summary.json`` atomically (strict JSON: NaN and inf as ``null``) and return
    the run's :class:`RunResult`; ``progress`` is (iterations, env steps, wall-clock s)."""
    text = json.dumps(json_safe(summary), indent=2, allow_nan=False)
    atomic_write_text(out / "summary.json", text + "\n")
    iterations, env_steps, wall_s = progress
    return RunResult(
        best,
        history,
        out / "best.pt",
        out / "latest.pt",
        iterations,
        env_steps,
        wall_s,
        stop_reason,
        first_full,
    )
