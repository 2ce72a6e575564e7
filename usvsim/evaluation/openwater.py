"""Judging helmsmen on open-water episodes: :func:`evaluate_open_water`, :class:`OpenWaterRecord`.

Mirrors :func:`usvsim.evaluation.episodes.evaluate`: every episode of a set in ONE batch
(:class:`usvsim.task.openwater_batch.OpenWaterBatch`, no autoreset; a finished boat's later
actions are ignored), one record each, with the metric names the bench summaries read
(``success``, ``collision``, ``min_pole_distance_m`` — here the pole-equivalent distance to the
nearest obstacle, :mod:`usvsim.task.openwater` —, ``time_to_goal_s``, ``path_length_m``,
``smoothness_rad``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.helm.protocol import Helmsman
from usvsim.task.batch import ActionKind
from usvsim.task.observations import ObservationKind
from usvsim.task.openwater import OpenWaterEpisode
from usvsim.task.openwater_batch import OpenWaterBatch

__all__ = ["OpenWaterRecord", "evaluate_open_water"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OpenWaterRecord:
    """Outcome and trace of one open-water episode (true state).

    ``trajectory`` (K + 1, 3): true [x_N, y_E, ψ] from the start to the episode's end.
    """

    episode: OpenWaterEpisode
    success: bool
    reached_goal: bool
    collision: bool
    out_of_area: bool
    time_limit: bool
    min_pole_distance_m: float  # pole-equivalent distance to the nearest obstacle, m
    time_to_goal_s: float  # NaN if not reached
    path_length_m: float
    smoothness_rad: float
    duration_s: float
    trajectory: FloatArray
    actions_rad: FloatArray

    @property
    def outcome(self) -> str:
        """One word: success, collision, goal-unsafe, out-of-area or time-limit."""
        if self.success:
            return "success"
        if self.collision:
            return "collision"
        if self.reached_goal:
            return "goal-unsafe"
        return "out-of-area" if self.out_of_area else "time-limit"


def evaluate_open_water(
    helmsman: Helmsman,
    episodes: Sequence[OpenWaterEpisode],
    *,
    observation: ObservationKind = "positional",
    action: ActionKind = "gaussian",
    on_decision: Callable[[OpenWaterBatch, int], Any] | None = None,
    **batch_kwargs: Any,
) -> list[OpenWaterRecord]:
    """Run ``helmsman`` on every episode (all in one batch) and record each one.

    ``batch_kwargs`` go to :class:`usvsim.task.openwater_batch.OpenWaterBatch` (plant, radar).
    ``on_decision(batch, k)``, optional, runs after decision step k (0-based) before the next
    action; it may steer the scene (e.g. reactive target vessels,
    :mod:`usvsim.evaluation.colreg_rollout`) and return the observation the helmsman sees next
    (None: the step's own).
    """
    n = len(episodes)
    if n == 0:
        raise ValueError("evaluate_open_water needs at least one episode")
    sim = OpenWaterBatch(n, observation=observation, action=action, **batch_kwargs)
    sc = sim.base
    T = sc.steps_per_decision
    K = max(math.ceil(e.time_limit_s / sc.decision_period_s - 1e-9) for e in episodes)
    obs = sim.reset(None, list(episodes))
    helmsman.reset(n)
    traj = np.empty((n, K * T + 1, 3))
    traj[:, 0] = sim.inner.state.eta
    actions = np.zeros((n, K))
    n_dec = np.zeros(n, dtype=np.int64)
    n_steps = np.zeros(n, dtype=np.int64)
    final: dict[str, NDArray[Any]] = {}
    active = np.ones(n, dtype=bool)
    for k in range(K):
        res = sim.step(helmsman.act(obs))
        traj[:, 1 + k * T : 1 + (k + 1) * T] = res.trajectory[:, :, 0:3]
        actions[:, k] = res.heading_change_rad
        ended = active & (res.terminated | res.truncated)
        n_dec[ended] = k + 1
        n_steps[ended] = k * T + res.end_step[ended]
        for key in ("is_success", "reached_goal", "collision", "out_of_area", "time_limit",
                    "min_distance_m", "time_to_goal_s"):  # fmt: skip
            value = getattr(res, key)
            final.setdefault(key, np.zeros_like(value))[ended] = value[ended]
        active &= ~ended
        if not active.any():
            break
        obs = res.observation
        if on_decision is not None:
            replaced = on_decision(sim, k)
            obs = obs if replaced is None else replaced
    records = []
    for i in range(n):
        path = traj[i, : n_steps[i] + 1]
        acts = actions[i, : n_dec[i]].copy()
        t_goal = float(final["time_to_goal_s"][i])
        records.append(
            OpenWaterRecord(
                episode=episodes[i],
                success=bool(final["is_success"][i]),
                reached_goal=bool(final["reached_goal"][i]),
                collision=bool(final["collision"][i]),
                out_of_area=bool(final["out_of_area"][i]),
                time_limit=bool(final["time_limit"][i]),
                min_pole_distance_m=float(final["min_distance_m"][i]),
                time_to_goal_s=t_goal if math.isfinite(t_goal) else math.nan,
                path_length_m=float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T))),
                smoothness_rad=float(np.sum(np.abs(np.diff(acts)))),
                duration_s=float(n_dec[i] * sc.decision_period_s),
                trajectory=path.copy(),
                actions_rad=acts,
            )
        )
    return records
