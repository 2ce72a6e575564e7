"""The on-policy training loop, generic over :class:`learning.algorithms.base.Agent`.

Per iteration: roll out the agent's :meth:`~learning.algorithms.base.Agent.sample` on N envs
for T steps (:class:`learning.algorithms.rollout.RolloutCollector`), then one
:meth:`~learning.algorithms.base.Agent.update` on that batch; a callback sees the
:class:`IterationStats` and may stop the run. The algorithm comes from the config's type
(:func:`learning.algorithms.registry.algorithm_for`).

Where an iteration's wall-clock goes (:func:`time_row`, the ``log.csv`` columns
:data:`TIME_FIELDS`, s, measured with ``time.perf_counter``): ``rollout_s`` the rollout, then the
update's :class:`learning.algorithms.base.UpdateTimes`: ``batch_s`` (values, GAE, statistics
refresh), ``policy_step_s``, ``critic_s`` and, for GAIL, ``discriminator_s``. Their sum is at
most the iteration's wall-clock (what is left: the update's own bookkeeping and the callback).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from gymnasium.vector import VectorEnv

from learning.algorithms.base import Agent, AlgorithmConfig, UpdateStats
from learning.algorithms.registry import algorithm_for
from learning.algorithms.rollout import RolloutCollector

__all__ = ["TIME_FIELDS", "IterationStats", "iterate", "time_row", "train"]

A = TypeVar("A", bound=Agent)

TIME_FIELDS = ("rollout_s", "batch_s", "policy_step_s", "critic_s", "discriminator_s")


@dataclass(frozen=True)
class IterationStats:
    """What one iteration did (handed to the callback of :func:`train` and :func:`iterate`)."""

    iteration: int  # 1-based count of completed iterations
    env_steps: int  # transitions learned from so far (valid ones)
    episodes: int  # episodes finished in this iteration's rollout
    mean_return: float  # of those episodes (NaN if none finished)
    mean_length: float
    update: UpdateStats  # the algorithm's own statistics (UpdateStats.LOG_FIELDS)
    rollout_time_s: float
    update_time_s: float
    wall_time_s: float  # since the loop started

    @property
    def kl(self) -> float:
        return self.update.kl

    @property
    def entropy(self) -> float:
        return self.update.entropy


def time_row(stats: IterationStats, fields: tuple[str, ...] = TIME_FIELDS) -> dict[str, float]:
    """The time-split columns ``fields`` (of :data:`TIME_FIELDS`) of one iteration, s (0.1 ms)."""
    times = {"rollout_s": stats.rollout_time_s, **dataclasses.asdict(stats.update.times)}
    return {name: round(times[name], 4) for name in fields}


def iterate(
    agent: A,
    env: VectorEnv,
    callback: Callable[[IterationStats, A], bool | None] | None = None,
) -> A:
    """Iterate ``agent`` on ``env`` until ``agent.config.iterations`` or ``callback`` returns True.

    The env restarts with a reset seeded ``config.seed + agent.iteration`` (env state is not
    part of a checkpoint), so a resumed run is reproducible, though not identical to an
    uninterrupted one. Same config and seed on the same machine → identical statistics.
    """
    config = agent.config
    collector = RolloutCollector(
        env,
        seed=config.seed + agent.iteration,
        info_keys=agent.info_keys,
        obs_info_keys=getattr(agent, "obs_info_keys", ()),  # optional (an asymmetric GAIL's)
    )
    start = time.perf_counter()
    while agent.iteration < config.iterations:
        t0 = time.perf_counter()
        batch = collector.collect(agent.sample, config.steps_per_env)
        t1 = time.perf_counter()
        update = agent.update(batch)
        t2 = time.perf_counter()
        rets = batch.episode_returns
        stats = IterationStats(
            iteration=agent.iteration,
            env_steps=agent.env_steps,
            episodes=len(rets),
            mean_return=float(np.mean(rets)) if rets else float("nan"),
            mean_length=float(np.mean(batch.episode_lengths)) if rets else float("nan"),
            update=update,
            rollout_time_s=t1 - t0,
            update_time_s=t2 - t1,
            wall_time_s=t2 - start,
        )
        if callback is not None and callback(stats, agent):
            break
    return agent


def train(
    config: AlgorithmConfig,
    make_vector_env: Callable[[int], VectorEnv],
    *,
    callback: Callable[[IterationStats, Any], bool | None] | None = None,
    state: dict[str, Any] | None = None,
    warm_start: dict[str, Any] | None = None,
) -> Any:
    """Train the registered algorithm whose config ``config`` is, for ``config.iterations``.

    ``make_vector_env(num_envs)`` builds the (gymnasium 1.x) vector env; it is closed at the
    end. ``state`` (the agent's ``state_dict``) resumes a run: networks, optimisers, normaliser,
    random generator and counters continue (:func:`iterate` for the envs). ``warm_start`` (an
    agent ``state_dict``, e.g. of a GAIL run) gives a new run its first policy and normaliser
    (``Agent.load_policy``); it is ignored when ``state`` resumes one. Returns the agent.
    """
    algorithm = algorithm_for(config)
    env = make_vector_env(config.num_envs)
    try:
        agent = algorithm.make_agent(env.single_observation_space, env.single_action_space, config)
        if state is not None:
            agent.load_state_dict(state)
        elif warm_start is not None:
            agent.load_policy(warm_start)
        return iterate(agent, env, callback)
    finally:
        env.close()
