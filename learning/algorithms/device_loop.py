"""TRPO trained on a torch device (issue 40): env, rollouts, GAE and the update stay there.

The twin of :func:`learning.algorithms.loop.train` for an env on a torch device
(:class:`usvsim.task.torch_env.TorchPoleAvoidanceEnv` or
:class:`usvsim.task.torch_openwater.TorchOpenWaterEnv`, ``"torch-cpu"`` or ``"cuda"``: the same
code). Per iteration:

1. :class:`learning.algorithms.device_rollout.DeviceRolloutCollector` rolls out π_θold for T
   steps on N boats with no host round trip per step;
2. :func:`device_update`: V(s_t) and V(s'_t) by the critic, GAE (:func:`device_gae`),
   advantages normalised, then the agent's own TRPO step
   (:func:`learning.algorithms.trpo.trpo_step`: conjugate gradient and line search on the
   device tensors) and critic fit (:func:`learning.algorithms.actor_critic.fit_critic`), then
   the observation statistics merged from the batch's mean and variance computed on the device;
3. one read-back: the iteration's episode count, return and length sums, for the callback.

The agent's networks live on the device during rollouts and updates and on the CPU while the
callback runs (validation on the CPU env, checkpoints readable anywhere). TRPO agents only;
observations: vectors (positional, running-normalised; scene, its fixed standardisation) or an
image with a vector (radar+goal: the image scaled, the goal running-normalised).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from torch import Tensor

from learning.algorithms.actor_critic import fit_critic
from learning.algorithms.base import Stopwatch
from learning.algorithms.device_rollout import (
    DeviceBatch,
    DeviceNormalizer,
    DeviceRolloutCollector,
    device_gae,
    flat_rows,
)
from learning.algorithms.loop import IterationStats
from learning.algorithms.networks import TensorObs, rows
from learning.algorithms.rollout import NonFiniteError
from learning.algorithms.trpo import TRPOAgent, TRPOConfig, TRPOUpdateStats, trpo_step

__all__ = ["device_update", "iterate_on_device", "place_agent", "train_on_device"]

VALUE_CHUNK = 1 << 20  # rows per critic pass for V(s_t), V(s'_t)
IMAGE_VALUE_CHUNK = 1 << 14  # the same with an image (radar+goal: 24 kB a row in float32)


def device_update(agent: TRPOAgent, batch: DeviceBatch) -> TRPOUpdateStats:
    """:meth:`TRPOAgent.update` on a :class:`DeviceBatch` (module docstring, step 2)."""
    cfg: TRPOConfig = agent.config
    clock = Stopwatch()
    T, N = batch.rewards.shape
    normalise = DeviceNormalizer(agent.normalizer, batch.rewards.device)
    raw = flat_rows(batch.obs)
    obs = normalise(raw)
    with torch.no_grad():  # in chunks: a GPU batch may hold millions of rows (images)
        values = torch.stack(
            [_values(agent, normalise, x, T * N) for x in (raw, flat_rows(batch.next_obs))]
        ).reshape(2, T, N)
    adv, ret = device_gae(
        batch.rewards,
        values[0],
        values[1],
        batch.terminated,
        batch.episode_end,
        cfg.gamma,
        cfg.gae_lambda,
    )
    adv, ret = adv.reshape(-1), ret.reshape(-1)
    actions = batch.actions.reshape(T * N, *batch.actions.shape[2:])
    vectors = [x for x in (obs.values() if isinstance(obs, dict) else [obs]) if x.ndim == 2]
    if not all(bool(torch.isfinite(x.sum(dtype=torch.float64))) for x in vectors):
        raise NonFiniteError("non-finite observation in the batch: no update made")
    if not (torch.isfinite(adv).all() and torch.isfinite(ret).all()):
        raise NonFiniteError("non-finite advantages or returns: no update made")
    if cfg.normalize_advantages and adv.numel() > 1:
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)
    clock.lap("batch_s")
    step = trpo_step(agent.policy, obs, actions, adv, cfg, agent.generator)
    clock.lap("policy_step_s")
    value_loss = fit_critic(
        agent.critic,
        agent.critic_optimizer,
        obs,
        ret,
        cfg.critic_epochs,
        cfg.critic_minibatch,
        agent.generator,
    )
    clock.lap("critic_s")
    if normalise.kind == "running" and not cfg.fixed_input_stats:
        for key, stats in agent.normalizer.stats.items():  # the vector parts
            x = (raw[key] if isinstance(raw, dict) else raw).to(torch.float64)
            moments = torch.stack([x.mean(0), x.var(0, unbiased=False)]).cpu().numpy()
            stats.merge(moments[0], moments[1], float(T * N))
    agent.iteration += 1
    agent.env_steps += T * N
    clock.lap("batch_s")
    return TRPOUpdateStats(step, value_loss, clock.times())


def _values(agent: TRPOAgent, normalise: DeviceNormalizer, raw: TensorObs, m: int) -> Tensor:
    """V(s) (m,) of raw rows, normalised and evaluated :data:`VALUE_CHUNK` rows at a time
    (:data:`IMAGE_VALUE_CHUNK` with an image)."""
    step = IMAGE_VALUE_CHUNK if isinstance(raw, dict) else VALUE_CHUNK
    return torch.cat(
        [agent.critic(normalise(rows(raw, slice(i, i + step)))) for i in range(0, m, step)]
    )


def place_agent(agent: TRPOAgent, device: torch.device) -> None:
    """Move a TRPO agent's networks and its critic optimiser's state to ``device``."""
    agent.policy.to(device)
    agent.critic.to(device)
    for state in agent.critic_optimizer.state.values():
        for key, value in state.items():
            if isinstance(value, torch.Tensor) and key != "step":
                state[key] = value.to(device)


def iterate_on_device(
    agent: Any,
    env: Any,
    callback: Callable[[IterationStats, Any], bool | None] | None = None,
) -> Any:
    """:func:`learning.algorithms.loop.iterate` on a torch env (module docstring). The env
    restarts with a reset seeded ``config.seed + agent.iteration``. ``agent``: a
    :class:`TRPOAgent`, or an agent with its own ``place(device)`` and
    ``update_on_device(batch)`` (:class:`learning.imitation.gail.GAILAgent`)."""
    cfg: TRPOConfig = agent.config
    device = torch.device(env.device)
    space = agent.action_space
    bounds = None
    if isinstance(space, spaces.Box):  # Gaussian actions: clipped on the way to the env
        bounds = (float(np.min(space.low)), float(np.max(space.high)))
    collector = DeviceRolloutCollector(
        env, cfg.gamma, cfg.seed + agent.iteration, bounds, info_keys=tuple(agent.info_keys),
        env_reward=getattr(agent, "env_reward", True),
        obs_info_keys=tuple(getattr(agent, "obs_info_keys", ())),
    )  # fmt: skip
    # an agent with its own update on the device (GAIL: its discriminator too) places itself
    place = getattr(agent, "place", None) or (lambda d: place_agent(agent, d))
    update_on_device = getattr(agent, "update_on_device", None) or (
        lambda b: device_update(agent, b)
    )
    start = time.perf_counter()
    while agent.iteration < cfg.iterations:
        place(device)
        t0 = time.perf_counter()
        agent.policy.eval()
        normalise = DeviceNormalizer(agent.normalizer, device)
        batch = collector.collect(agent.policy, normalise, cfg.steps_per_env)
        t1 = time.perf_counter()
        update = update_on_device(batch)
        n, ret_sum, len_sum = batch.episode_sums.tolist()  # the iteration's one read-back
        t2 = time.perf_counter()
        place(torch.device("cpu"))
        stats = IterationStats(
            iteration=agent.iteration,
            env_steps=agent.env_steps,
            episodes=int(n),
            mean_return=ret_sum / n if n else float("nan"),
            mean_length=len_sum / n if n else float("nan"),
            update=update,
            rollout_time_s=t1 - t0,
            update_time_s=t2 - t1,
            wall_time_s=t2 - start,
        )
        if callback is not None and callback(stats, agent):
            break
    place(torch.device("cpu"))
    return agent


def train_on_device(
    config: TRPOConfig,
    make_env: Callable[[int], Any],
    *,
    callback: Callable[[IterationStats, Any], bool | None] | None = None,
    state: dict[str, Any] | None = None,
    warm_start: dict[str, Any] | None = None,
) -> TRPOAgent:
    """:func:`learning.algorithms.loop.train` for TRPO on a torch env: ``make_env(num_envs)``
    builds it (``single_observation_space``, ``single_action_space``, ``device``); ``state``
    resumes a run, ``warm_start`` gives a new one its first policy and normaliser."""
    if not isinstance(config, TRPOConfig):
        raise ValueError(f"training on a torch device is for TRPO, not {type(config).__name__}")
    env = make_env(config.num_envs)
    agent = TRPOAgent(env.single_observation_space, env.single_action_space, config)
    if state is not None:
        agent.load_state_dict(state)
    elif warm_start is not None:
        agent.load_policy(warm_start)
    return iterate_on_device(agent, env, callback)
