"""Judging helmsmen on fixed episode sets: the episode sets and ``evaluate``.

A *helmsman* (:class:`usvsim.helm.protocol.Helmsman`) steers N boats at once from their
observations. :func:`evaluate` runs every episode
of a set in ONE batch (:class:`usvsim.task.batch.PoleAvoidanceBatch`, no autoreset; a finished
boat's later observations and actions are ignored) and returns one :class:`EpisodeRecord` each.
Because every episode carries its own noise stream (:class:`usvsim.task.scenario.BoatNoise`), a
record does not depend on which other episodes share the batch.

Episode sets
------------
* :func:`validation_episodes` — the study's 15 fixed validation episodes, a deterministic
  stratified grid: episode k (0..14) starts at bearing ``k · 24°`` from its pole (0°…336°, evenly
  covering the circle) and distance ``50 + 12.5 · (k mod 5)`` m (50, 62.5, 75, 87.5, 100 m, each
  three times, 120° apart); its pole and noise seed come from a fixed seed (``VALIDATION_SEED``).
* :func:`heldout_episodes` — 200 episodes drawn by :func:`usvsim.task.scenario.draw_episode` from a
  separate seed (``HELDOUT_SEED``); never used for model selection.
* :func:`selection_episodes` — the 15 validation episodes followed by 45 more drawn from a third
  seed (``SELECTION_SEED``): what an IL run ranks its checkpoints on (``best.pt``). Fifteen
  episodes cannot tell a 94 % policy from a 99 % one (it scores 15/15 with probability
  0.94^15 = 0.39), and an IL run has many 15/15 checkpoints to choose from; on 60 episodes the
  94 % policy is perfect with probability 0.024.

Success is strict (issue 3): within 10 m of the goal before the time limit, and never closer
than 10 m to the pole (true positions, every 0.1 s plant step).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.splits import check_test_draw
from usvsim.helm.protocol import Helmsman
from usvsim.task.batch import ActionKind, PoleAvoidanceBatch
from usvsim.task.observations import ObservationKind
from usvsim.task.scenario import EpisodeSpec, Scenario, draw_episodes

__all__ = [
    "HELDOUT_SEED",
    "SELECTION_SEED",
    "VALIDATION_SEED",
    "EpisodeRecord",
    "EvaluationSummary",
    "evaluate",
    "format_records",
    "heldout_episodes",
    "selection_episodes",
    "summarize",
    "validation_episodes",
]

VALIDATION_SEED = 20190015  # seeds the validation set's poles and noise
HELDOUT_SEED = 20190200  # seeds the held-out set (a separate stream)
SELECTION_SEED = 20190060  # seeds the selection set's 45 extra episodes (a third stream)
FloatArray = NDArray[np.float64]


def validation_episodes(scenario: Scenario | None = None) -> tuple[EpisodeSpec, ...]:
    """The 15 fixed validation episodes (module docstring), inside the scenario's ranges."""
    scenario = scenario or Scenario()
    rng = np.random.default_rng(VALIDATION_SEED)
    lo, hi = scenario.start_distance_range_m
    specs = []
    for k in range(15):
        pole = int(rng.integers(len(scenario.poles_ne)))
        seed = int(rng.integers(2**63))
        distance = lo + (hi - lo) * (k % 5) / 4
        specs.append(EpisodeSpec(pole, distance, math.radians(24.0 * k), 0.0, seed))
    return tuple(specs)


def selection_episodes(
    scenario: Scenario | None = None, n_extra: int = 45
) -> tuple[EpisodeSpec, ...]:
    """The 15 validation episodes, then ``n_extra`` drawn from ``SELECTION_SEED`` (module
    docstring): a larger set to choose checkpoints on, disjoint from the held-out stream."""
    scenario = scenario or Scenario()
    extra = draw_episodes(np.random.default_rng(SELECTION_SEED), scenario, n_extra)
    return validation_episodes(scenario) + tuple(extra)


def heldout_episodes(scenario: Scenario | None = None, n: int = 200) -> tuple[EpisodeSpec, ...]:
    """``n`` held-out episodes drawn from their own seed (``HELDOUT_SEED``): a test split,
    refused inside :func:`usvsim.common.splits.selection_mode`."""
    check_test_draw("study held-out")
    return draw_episodes(np.random.default_rng(HELDOUT_SEED), scenario or Scenario(), n)


@dataclass(frozen=True)
class EpisodeRecord:
    """Outcome and trace of one episode (true state unless named ``est``).

    ``trajectory`` (K + 1, 3): true [x_N, y_E, ψ] at the start and after every 0.1 s plant step
    up to the episode's end (a collision or goal step ends it mid-period); per-decision arrays
    (D,): ``actions_rad`` (heading changes), ``reward_pole``, ``reward_goal``; ``est_pose``
    (D + 1, 3): the navigation estimate [x_N, y_E, ψ] the helmsman saw at each decision (and at
    the end).
    """

    spec: EpisodeSpec
    success: bool
    reached_goal: bool
    collision: bool
    out_of_area: bool
    time_limit: bool
    min_pole_distance_m: float
    final_goal_distance_m: float
    time_to_goal_s: float  # NaN if the goal was not reached
    path_length_m: float
    smoothness_rad: float  # Σ |Δψ_k − Δψ_{k−1}| over consecutive decisions
    duration_s: float
    pole_ne: FloatArray
    goal_ne: FloatArray
    trajectory: FloatArray
    actions_rad: FloatArray
    reward_pole: FloatArray
    reward_goal: FloatArray
    est_pose: FloatArray

    @property
    def n_decisions(self) -> int:
        return int(self.actions_rad.size)

    @property
    def outcome(self) -> str:
        """One word: success, collision, goal-unsafe, out-of-area or time-limit."""
        if self.success:
            return "success"
        if self.collision:
            return "collision"
        if self.reached_goal:
            return "goal-unsafe"  # reached the goal but passed within the safety distance
        if self.out_of_area:
            return "out-of-area"
        return "time-limit"


def evaluate(
    helmsman: Helmsman,
    episodes: Sequence[EpisodeSpec],
    *,
    observation: ObservationKind = "positional",
    action: ActionKind = "gaussian",
    **batch_kwargs: Any,
) -> list[EpisodeRecord]:
    """Run ``helmsman`` on every episode (all in one batch) and record each one.

    ``batch_kwargs`` go to :class:`usvsim.task.batch.PoleAvoidanceBatch` (scenario, reward,
    radar, nav, plant, vessel, ...).
    """
    n = len(episodes)
    if n == 0:
        raise ValueError("evaluate needs at least one episode")
    sim = PoleAvoidanceBatch(n, observation=observation, action=action, **batch_kwargs)
    sc = sim.scenario
    K, T = sc.max_decisions, sc.steps_per_decision
    obs = sim.reset(None, list(episodes))
    helmsman.reset(n)
    traj = np.empty((n, K * T + 1, 3))
    traj[:, 0] = sim.state.eta
    est = np.empty((n, K + 1, 3))
    pos, psi = sim.estimate
    est[:, 0, :2], est[:, 0, 2] = pos, psi
    actions, r_pole, r_goal = (np.zeros((n, K)) for _ in range(3))
    n_dec = np.zeros(n, dtype=np.int64)
    n_steps = np.zeros(n, dtype=np.int64)  # plant steps up to each episode's end
    final: dict[str, NDArray[Any]] = {}
    active = np.ones(n, dtype=bool)
    for k in range(K):
        res = sim.step(helmsman.act(obs))
        traj[:, 1 + k * T : 1 + (k + 1) * T] = res.trajectory[:, :, 0:3]
        est[:, k + 1, :2], est[:, k + 1, 2] = res.est_pos_ne, res.est_psi_rad
        actions[:, k], r_pole[:, k], r_goal[:, k] = (
            res.heading_change_rad,
            res.terms.pole,
            res.terms.goal,
        )
        ended = active & (res.terminated | res.truncated)
        n_dec[ended] = k + 1
        n_steps[ended] = k * T + res.end_step[ended]
        for key, value in res.info_arrays().items():
            final.setdefault(key, np.zeros_like(value))[ended] = value[ended]
        active &= ~ended
        if not active.any():
            break
        obs = res.observation
    return [
        _record(
            i,
            episodes[i],
            sim,
            final,
            traj[i, : n_steps[i] + 1],
            est,
            actions,
            r_pole,
            r_goal,
            int(n_dec[i]),
            sc.decision_period_s,
        )
        for i in range(n)
    ]


def _record(
    i: int,
    spec: EpisodeSpec,
    sim: PoleAvoidanceBatch,
    final: dict[str, NDArray[Any]],
    traj: FloatArray,
    est: FloatArray,
    actions: FloatArray,
    r_pole: FloatArray,
    r_goal: FloatArray,
    d: int,
    period_s: float,
) -> EpisodeRecord:
    path = traj
    acts = actions[i, :d].copy()
    t_goal = float(final["time_to_goal_s"][i])
    return EpisodeRecord(
        spec=spec,
        success=bool(final["is_success"][i]),
        reached_goal=bool(final["reached_goal"][i]),
        collision=bool(final["collision"][i]),
        out_of_area=bool(final["out_of_area"][i]),
        time_limit=bool(final["time_limit"][i]),
        min_pole_distance_m=float(final["min_distance_to_pole_m"][i]),
        final_goal_distance_m=float(final["distance_to_goal_m"][i]),
        time_to_goal_s=t_goal if math.isfinite(t_goal) else math.nan,
        path_length_m=float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T))),
        smoothness_rad=float(np.sum(np.abs(np.diff(acts)))),
        duration_s=d * period_s,
        pole_ne=sim.pole_ne[i].copy(),
        goal_ne=sim.goal_ne[i].copy(),
        trajectory=path.copy(),
        actions_rad=acts,
        reward_pole=r_pole[i, :d].copy(),
        reward_goal=r_goal[i, :d].copy(),
        est_pose=est[i, : d + 1].copy(),
    )


@dataclass(frozen=True)
class EvaluationSummary:
    """Aggregates over a set of records (rates in [0, 1], distances in m)."""

    n_episodes: int
    success_rate: float
    collision_rate: float
    hit_rate: float  # collision or closer than the safety distance (10 m) to the pole
    mean_min_pole_distance_m: float
    worst_min_pole_distance_m: float
    mean_time_to_goal_s: float  # over episodes that reached the goal; NaN if none


def summarize(
    records: Sequence[EpisodeRecord], safety_distance_m: float = 10.0
) -> EvaluationSummary:
    """Success, collision and hit rates and pole distances of ``records``."""
    min_d = np.array([r.min_pole_distance_m for r in records])
    t_goal = np.array([r.time_to_goal_s for r in records])
    return EvaluationSummary(
        n_episodes=len(records),
        success_rate=float(np.mean([r.success for r in records])),
        collision_rate=float(np.mean([r.collision for r in records])),
        hit_rate=float(
            np.mean([r.collision or r.min_pole_distance_m < safety_distance_m for r in records])
        ),
        mean_min_pole_distance_m=float(min_d.mean()),
        worst_min_pole_distance_m=float(min_d.min()),
        mean_time_to_goal_s=float(np.nanmean(t_goal)) if np.isfinite(t_goal).any() else math.nan,
    )


def format_records(records: Sequence[EpisodeRecord]) -> str:
    """A compact fixed-width table, one line per episode."""
    lines = ["  # pole  d0 m  brg°  outcome      min d_pole m  d_goal m  t_goal s  path m  Σ|Δa|°"]
    for k, r in enumerate(records):
        lines.append(
            f"{k:3d} {r.spec.pole_index:5d} {r.spec.start_distance_m:6.1f} "
            f"{math.degrees(r.spec.start_bearing_rad):5.0f}  {r.outcome:12s} "
            f"{r.min_pole_distance_m:12.2f} {r.final_goal_distance_m:9.1f} "
            f"{r.time_to_goal_s:9.1f} {r.path_length_m:7.1f} "
            f"{math.degrees(r.smoothness_rad):7.1f}"
        )
    return "\n".join(lines)
