"""Validation of a policy during training, shared by RL and IL runs: the deterministic policy on
the study's 15 validation episodes (:func:`usvsim.evaluation.episodes.validation_episodes`), its
summary, and the record a validation leaves in the checkpoints' history and ``summary.json``.

A setup trained on the open-water family (``task="open-water"``, issue 18) is validated on the
15 episodes (the reported validation) *and* on a fixed family set
(:func:`family_validation_episodes`: :data:`FAMILY_VALIDATION_SIZE` episodes of
:data:`usvsim.task.openwater_env.OPEN_WATER_FAMILY` from their own seed, never a stress set's),
whose ``family_*`` entries join the validation record. Such a run keeps as ``best.pt`` the
checkpoint with the most successes over both sets together among those that pass all 15 (any
checkpoint while none does), then the higher mean return (:func:`selection_key`;
``summary.json``'s ``best.successes`` is that sum), and stops early
only at a validation that also passes :data:`FAMILY_STOP_RATE` of the family set
(:func:`family_passed`).

A radar setup on the family is also validated on a harsh-radar set
(:func:`radar_validation_episodes`: :data:`RADAR_VALIDATION_SIZE` family episodes, every radar
degradation at the family's strongest level, the level of the stress suite's ``radar-noise``
set, from their own seed). Uniform draws put few family episodes near that corner, so the family
set alone cannot tell a checkpoint that holds up under the strongest noise from one that does
not (session 7: two checkpoints of one run with the same 15 + family successes scored 98 % and
89 % on ``radar-noise``). Its ``radar_*`` entries join the record, its successes the selection
key, and an early stop also needs :data:`RADAR_STOP_RATE` of it.

Every setup on the family is also validated on a crowded set (:func:`crowded_validation_episodes`:
:data:`CROWDED_VALIDATION_SIZE` episodes of :func:`crowded_family`, each member with its most
obstacles and vessels, the study's lone pole left out, from their own seed). Of 2,000 family
episodes 13 % carry seven or more discs and vessels and 2 % the most (nine), so the family set
barely tells a checkpoint that threads a crowd from one that does not (session 10: the stress
suite's ``everything`` set was the one set the best scene policy missed). Its ``crowded_*``
entries join the record and its successes the selection key; the early stop does not look at it.
"""

from __future__ import annotations

import functools
import json
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from learning.algorithms.base import Agent
from learning.experiments.checkpoint import PolicyHelmsman
from learning.experiments.memory_start import setup_goal_mark
from usvsim.common.fileio import atomic_write_text, json_safe
from usvsim.common.splits import selection_mode
from usvsim.evaluation.episodes import EpisodeRecord, evaluate, validation_episodes
from usvsim.evaluation.openwater import OpenWaterRecord, evaluate_open_water
from usvsim.task.openwater import OpenWaterEpisode
from usvsim.task.openwater_env import (
    OPEN_WATER_FAMILY,
    crowded_family,
    draw_family,
    harsh_radar_family,
)
from usvsim.task.scenario import EpisodeSpec

__all__ = [
    "CROWDED_VALIDATION_SEED",
    "CROWDED_VALIDATION_SIZE",
    "FAMILY_STOP_RATE",
    "FAMILY_VALIDATION_SEED",
    "FAMILY_VALIDATION_SIZE",
    "RADAR_STOP_RATE",
    "RADAR_VALIDATION_SEED",
    "RADAR_VALIDATION_SIZE",
    "RunResult",
    "crowded_family",
    "crowded_validation_episodes",
    "family_passed",
    "family_validation_episodes",
    "harsh_radar_family",
    "open_water_summary",
    "radar_validation_episodes",
    "selection_key",
    "validate",
    "validation_record",
    "validation_summary",
]

# the family set's seed: the CRC-32 of its name, as the stress sets' (usvsim.evaluation.stress),
# so it is none of theirs
FAMILY_VALIDATION_SEED = zlib.crc32(b"family-validation")
FAMILY_VALIDATION_SIZE = 100  # episodes; Wilson 95 % interval about ±5 points near 95 %
FAMILY_STOP_RATE = 0.95  # -, family success an early stop needs (module docstring)
RADAR_VALIDATION_SEED = zlib.crc32(b"radar-validation")  # none of the stress sets' seeds either
RADAR_VALIDATION_SIZE = 50  # episodes: about 8 s of a radar validation on this CPU
RADAR_STOP_RATE = 0.90  # -, harsh-radar success an early stop needs (issue 18's radar bar)
CROWDED_VALIDATION_SEED = zlib.crc32(b"crowded-validation")  # none of the stress sets' seeds
CROWDED_VALIDATION_SIZE = 50  # episodes


@functools.lru_cache(maxsize=4)
def family_validation_episodes(n: int = FAMILY_VALIDATION_SIZE) -> tuple[OpenWaterEpisode, ...]:
    """The fixed family validation set: ``n`` episodes of the training family, episode k from
    ``default_rng([FAMILY_VALIDATION_SEED, k])`` (:func:`usvsim.task.openwater_env.draw_family`)."""
    return draw_family(OPEN_WATER_FAMILY, FAMILY_VALIDATION_SEED, n)


@functools.lru_cache(maxsize=4)
def radar_validation_episodes(n: int = RADAR_VALIDATION_SIZE) -> tuple[OpenWaterEpisode, ...]:
    """The fixed harsh-radar validation set (module docstring): ``n`` episodes of
    :func:`harsh_radar_family`, episode k from ``default_rng([RADAR_VALIDATION_SEED, k])``."""
    return draw_family(harsh_radar_family(), RADAR_VALIDATION_SEED, n)


@functools.lru_cache(maxsize=4)
def crowded_validation_episodes(n: int = CROWDED_VALIDATION_SIZE) -> tuple[OpenWaterEpisode, ...]:
    """The fixed crowded validation set (module docstring): ``n`` episodes of
    :func:`crowded_family`, episode k from ``default_rng([CROWDED_VALIDATION_SEED, k])``."""
    return draw_family(crowded_family(), CROWDED_VALIDATION_SEED, n)


def _on_family(setup: Any) -> bool:
    return getattr(setup, "task", "pole") == "open-water"


def _sees_radar(setup: Any) -> bool:
    return _on_family(setup) and str(setup.observation).startswith("radar")


@selection_mode("validate")
def validate(
    agent: Agent, setup: Any, specs: Sequence[EpisodeSpec] | None = None
) -> dict[str, float]:
    """The deterministic policy of ``agent`` on ``specs`` (default: the 15 validation episodes)
    in ``setup``'s observation and action kinds: :func:`validation_summary`; with the family
    set's ``family_*`` entries for an open-water setup (module docstring) when ``specs`` is
    None."""
    summary = validation_summary(policy_records(agent, setup, specs))
    if specs is None:
        summary.update(open_water_summary(agent, setup))
    return summary


@selection_mode("open_water_summary")
def open_water_summary(agent: Agent, setup: Any) -> dict[str, float]:
    """The family set's ``family_*`` and the crowded set's ``crowded_*`` entries for a setup on
    the open-water family, and the harsh-radar set's ``radar_*`` entries for a radar one (module
    docstring); {} otherwise."""
    out: dict[str, float] = {}
    if _on_family(setup):
        out.update(family_summary(family_records(agent, setup)))
        crowded = family_records(agent, setup, crowded_validation_episodes())
        out.update(family_summary(crowded, "crowded_"))
    if _sees_radar(setup):
        harsh = family_records(agent, setup, radar_validation_episodes())
        out.update(family_summary(harsh, "radar_"))
    return out


def family_records(
    agent: Agent, setup: Any, episodes: Sequence[OpenWaterEpisode] | None = None
) -> list[OpenWaterRecord]:
    """The records of ``agent``'s deterministic policy on ``episodes`` (default:
    :func:`family_validation_episodes`)."""
    return evaluate_open_water(
        PolicyHelmsman(agent, setup.observation, setup.action, goal_mark=setup_goal_mark(setup)),
        family_validation_episodes() if episodes is None else episodes,
        observation=setup.observation,
        action=setup.action,
    )


def family_summary(records: Sequence[OpenWaterRecord], prefix: str = "family_") -> dict[str, float]:
    """Successes, episodes, collisions and the closest approach (pole-equivalent, m) of an
    open-water set, each key prefixed ``prefix``."""
    return {
        f"{prefix}successes": int(sum(r.success for r in records)),
        f"{prefix}n_episodes": len(records),
        f"{prefix}collisions": int(sum(r.collision for r in records)),
        f"{prefix}min_distance_m": float(min(r.min_pole_distance_m for r in records)),
    }


def selection_key(val: dict[str, Any]) -> tuple[bool, int, float]:
    """How validations rank for ``best.pt``: a validation that passes every one of the study's
    episodes first (issue 18's bar for an RL policy on the family is 15/15), then successes (the
    study's 15, plus the family set's, the crowded set's and the harsh-radar set's where
    validated on them), then the mean return on the 15.

    Without the first entry a run on the family could keep a 12/15 checkpoint whose other sets
    made up the difference (2026-12-03, ``rl-gaussian-scene-ow`` with ``crowded_share=0.5``,
    seed 0: iteration 645, 12 + 78 + 36, over iteration 630, 15 + 75 + 36)."""
    successes = int(val["successes"])
    passed = successes >= int(val.get("n_episodes", successes))
    return passed, successes + extra_successes(val), float(val["mean_return"])


def extra_successes(val: dict[str, Any]) -> int:
    """Successes of a validation on the family's sets (family, crowded, harsh radar; 0 for
    those it was not validated on): the part of the selection key beyond the study's sets."""
    return sum(int(val.get(f"{prefix}_successes", 0)) for prefix in ("family", "crowded", "radar"))


def family_passed(val: dict[str, Any]) -> bool:
    """True without a family set, else whether its success rate reaches :data:`FAMILY_STOP_RATE`
    and, with a harsh-radar set, that set's reaches :data:`RADAR_STOP_RATE`."""
    if "family_successes" not in val:
        return True
    if int(val["family_successes"]) < FAMILY_STOP_RATE * int(val["family_n_episodes"]):
        return False
    if "radar_successes" not in val:
        return True
    return int(val["radar_successes"]) >= RADAR_STOP_RATE * int(val["radar_n_episodes"])


def policy_records(
    agent: Agent, setup: Any, specs: Sequence[EpisodeSpec] | None = None
) -> list[EpisodeRecord]:
    """The episode records of ``agent``'s deterministic policy on ``specs`` (default: the 15
    validation episodes)."""
    return evaluate(
        PolicyHelmsman(agent, setup.observation, setup.action, goal_mark=setup_goal_mark(setup)),
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
