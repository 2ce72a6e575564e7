"""PPO: clipped surrogate, old log-probabilities, early stop, checkpoints, determinism, learning."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium import spaces

from learning.algorithms import ppo
from learning.algorithms.base import Agent, UpdateStats, log_row
from learning.algorithms.loop import IterationStats, iterate
from learning.algorithms.networks import NetworkConfig
from learning.algorithms.rollout import NonFiniteError, RolloutBatch, RolloutCollector, flatten_obs
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.experiments.checkpoint import PolicyHelmsman
from learning.experiments.setups import get_setup
from usvsim.evaluation.episodes import evaluate, validation_episodes

SMALL = NetworkConfig(hidden=(64, 64))
CARTPOLE = ppo.PPOConfig(
    seed=0,
    iterations=30,
    num_envs=8,
    steps_per_env=256,
    minibatch_size=256,
    critic_minibatch=256,
    network=SMALL,
)


@pytest.fixture(autouse=True)
def _one_thread() -> Iterator[None]:
    """One torch thread: two crawl on a shared, loaded 2-core machine (measured 155 s against
    2 s for the CartPole test at load 5)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def _cartpole(n: int) -> gym.vector.VectorEnv:
    return gym.make_vec("CartPole-v1", n, vectorization_mode="sync")


def _pendulum(n: int) -> gym.vector.VectorEnv:
    return gym.make_vec("Pendulum-v1", n, vectorization_mode="sync")


def _rollout(
    make_env: Callable[[int], gym.vector.VectorEnv], config: ppo.PPOConfig
) -> tuple[ppo.PPOAgent, RolloutBatch]:
    env = make_env(config.num_envs)
    agent = ppo.PPOAgent(env.single_observation_space, env.single_action_space, config)
    batch = RolloutCollector(env, seed=config.seed).collect(agent.sample, config.steps_per_env)
    env.close()
    return agent, batch


def _train(
    config: ppo.PPOConfig,
    make_env: Callable[[int], gym.vector.VectorEnv],
    callback: Callable[[IterationStats, ppo.PPOAgent], bool | None] | None = None,
) -> ppo.PPOAgent:
    """``config.iterations`` iterations of the generic loop (no registry entry needed)."""
    env = make_env(config.num_envs)
    try:
        agent = ppo.PPOAgent(env.single_observation_space, env.single_action_space, config)
        return iterate(agent, env, callback)
    finally:
        env.close()


def _params(module: torch.nn.Module) -> list[torch.Tensor]:
    return [p.detach().clone() for p in module.parameters()]


def _same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


# --- exact pieces ------------------------------------------------------------------------------


def test_clipped_surrogate_hand_computed() -> None:
    """min(r Â, clip(r, 0.8, 1.2) Â) (PPO, Eq. 7) and its gradient: zero where the clip binds."""
    r = torch.tensor([0.5, 1.0, 1.1, 1.5, 0.5, 0.9, 1.5], dtype=torch.float64, requires_grad=True)
    a = torch.tensor([1.0, 2.0, 1.0, 1.0, -1.0, -2.0, -1.0], dtype=torch.float64)
    value = ppo.clipped_surrogate(r, a, 0.2)
    # Â > 0: the clip caps a rise (1.5 → 1.2), a fall passes (0.5); Â < 0 the other way round
    expected = [0.5, 2.0, 1.1, 1.2, -0.8, -1.8, -1.5]
    np.testing.assert_allclose(value.detach().numpy(), expected, rtol=0, atol=1e-15)
    value.sum().backward()
    assert r.grad is not None
    assert r.grad.tolist() == [1.0, 2.0, 1.0, 0.0, 0.0, -2.0, -1.0]


def test_first_minibatch_ratio_is_exactly_one(monkeypatch: pytest.MonkeyPatch) -> None:
    """log π_old is recomputed over the first epoch's minibatches: r = 1 bit for bit there."""
    ratios: list[torch.Tensor] = []
    original = ppo.clipped_surrogate

    def spy(ratio: torch.Tensor, advantages: torch.Tensor, clip_range: float) -> torch.Tensor:
        ratios.append(ratio.detach().clone())
        return original(ratio, advantages, clip_range)

    monkeypatch.setattr(ppo, "clipped_surrogate", spy)
    config = dataclasses.replace(CARTPOLE, steps_per_env=64, update_epochs=2, minibatch_size=64)
    agent, batch = _rollout(_pendulum, config)
    stats = agent.update(batch)
    n_minibatches = math.ceil(8 * 64 / 64)
    assert len(ratios) == 2 * n_minibatches == stats.policy_step.steps
    assert torch.equal(ratios[0], torch.ones(64))
    assert not torch.equal(ratios[1], torch.ones(64))  # θ moved after the first step


def test_rollout_and_update_use_the_same_old_policy() -> None:
    """After an update the next rollout's log π(a|s) is what the next update recomputes: the
    normaliser and BatchNorm statistics change only between iterations."""
    config = dataclasses.replace(CARTPOLE, steps_per_env=64)
    env = _pendulum(config.num_envs)
    agent = ppo.PPOAgent(env.single_observation_space, env.single_action_space, config)
    collector = RolloutCollector(env, seed=0)
    agent.update(collector.collect(agent.sample, 64))
    batch = collector.collect(agent.sample, 64)
    env.close()
    obs = agent.policy_input(flatten_obs(batch.obs, 2))
    with torch.no_grad():
        logp = agent.policy(obs).log_prob(torch.as_tensor(batch.actions.reshape(-1, 1)))
    np.testing.assert_allclose(logp.numpy(), batch.log_probs.reshape(-1), rtol=0, atol=1e-5)


def test_target_kl_stops_the_epochs() -> None:
    config = dataclasses.replace(CARTPOLE, steps_per_env=32, update_epochs=5, minibatch_size=64)
    agent, batch = _rollout(_pendulum, dataclasses.replace(config, target_kl=0.0))
    stopped = agent.update(batch)
    assert stopped.epochs == 1 and stopped.early_stopped
    assert stopped.policy_step.steps == math.ceil(8 * 32 / 64)
    assert stopped.kl > 0.0
    agent, batch = _rollout(_pendulum, dataclasses.replace(config, target_kl=1e9))
    full = agent.update(batch)
    assert full.epochs == 5 and not full.early_stopped
    assert isinstance(full, UpdateStats)
    assert list(log_row(full)) == ["kl", "entropy", "clip_fraction", "epochs", "value_loss"]
    assert full.policy_step.steps == 5 * math.ceil(8 * 32 / 64)


def test_nan_observation_raises_and_leaves_networks_unchanged() -> None:
    agent, batch = _rollout(_pendulum, dataclasses.replace(CARTPOLE, steps_per_env=16))
    assert isinstance(batch.obs, np.ndarray)
    batch.obs[3, 2, 0] = np.nan
    before = _params(agent.policy) + _params(agent.critic)
    with pytest.raises(NonFiniteError):
        agent.update(batch)
    assert _same(before, _params(agent.policy) + _params(agent.critic))
    assert agent.iteration == 0


# --- checkpoints and determinism ---------------------------------------------------------------


def test_state_dict_round_trip_gives_identical_actions() -> None:
    agent = _train(dataclasses.replace(CARTPOLE, iterations=1, steps_per_env=64), _cartpole)
    protocol: Agent = agent  # mypy checks that PPOAgent meets the Agent protocol
    state = protocol.state_dict()
    assert state["format"] == "usvsim.learning.ppo/1"
    again = ppo.PPOAgent.from_state_dict(state)
    assert again.config == agent.config
    assert again.iteration == 1 and again.env_steps == agent.env_steps > 0
    obs = np.random.default_rng(0).normal(size=(20, 4)).astype(np.float32)
    np.testing.assert_array_equal(again.act(obs), agent.act(obs))
    np.testing.assert_array_equal(again.values(obs), agent.values(obs))
    a1, logp1 = agent.sample(obs)  # the generator state travels too
    a2, logp2 = again.sample(obs)
    np.testing.assert_array_equal(a1, a2)
    np.testing.assert_array_equal(logp1, logp2)
    other = ppo.PPOAgent(spaces.Box(-1, 1, (3,), np.float32), spaces.Discrete(2), agent.config)
    with pytest.raises(ValueError, match="observation_space"):
        other.load_state_dict(state)
    trpo = TRPOAgent(agent.observation_space, agent.action_space, TRPOConfig(network=SMALL))
    with pytest.raises(ValueError, match="not a PPO state"):
        agent.load_state_dict(trpo.state_dict())


def _curve(stats: list[IterationStats]) -> list[tuple[object, ...]]:
    timeless = [f.name for f in dataclasses.fields(IterationStats) if not f.name.endswith("_s")]
    return [tuple(getattr(s, n) for n in timeless) for s in stats]


def test_same_seed_same_update() -> None:
    config = dataclasses.replace(CARTPOLE, iterations=2, steps_per_env=64)
    runs = []
    for _ in range(2):
        stats: list[IterationStats] = []
        agent = _train(config, _cartpole, lambda s, a: stats.append(s))  # noqa: B023
        runs.append((_curve(stats), _params(agent.policy) + _params(agent.critic)))
    assert runs[0][0] == runs[1][0]
    assert _same(runs[0][1], runs[1][1])
    other: list[IterationStats] = []
    _train(dataclasses.replace(config, seed=1), _cartpole, lambda s, a: other.append(s))
    assert _curve(other) != runs[0][0]


# --- it learns ---------------------------------------------------------------------------------


@pytest.mark.slow
def test_ppo_solves_cartpole_within_ci_budget() -> None:
    """CartPole-v1: mean return ≥ 195 over one iteration's finished episodes within 30
    iterations of 2048 steps. Measured (minibatch 256, seeds 0-2): 6-7 iterations, 1.6-2.3 s at
    load 5 on 2 cores (minibatch 64: 6-20 iterations, 4-14 s)."""
    stats: list[IterationStats] = []

    def record(s: IterationStats, agent: ppo.PPOAgent) -> bool:
        stats.append(s)
        return s.mean_return >= 195.0

    _train(CARTPOLE, _cartpole, record)
    assert stats[0].mean_return < 50.0  # the random policy's level
    assert stats[-1].mean_return >= 195.0, [round(s.mean_return, 1) for s in stats]


def _validation_successes(agent: ppo.PPOAgent) -> int:
    setup = get_setup("rl-gaussian-positional")
    records = evaluate(
        PolicyHelmsman(agent, setup.observation, setup.action),
        validation_episodes(),
        observation=setup.observation,
        action=setup.action,
    )
    return sum(r.success for r in records)


@pytest.mark.slow
def test_ppo_learns_gaussian_positional() -> None:
    """rl-gaussian-positional with the setup's batch, γ, λ: first 15/15 validation within 20
    iterations from an untrained 0/15. Measured (seeds 0-4): 15/15 first at iterations 6-8."""
    setup = get_setup("rl-gaussian-positional")
    trpo = setup.algorithm_config
    config = ppo.PPOConfig(
        seed=0,
        iterations=20,
        num_envs=trpo.num_envs,
        steps_per_env=trpo.steps_per_env,
        gamma=trpo.gamma,
        gae_lambda=trpo.gae_lambda,
        network=trpo.network,
    )
    history: list[int] = []

    def record(s: IterationStats, agent: ppo.PPOAgent) -> bool:
        history.append(_validation_successes(agent))
        return history[-1] == 15

    env = setup.make_vector_env(config.num_envs)
    agent = ppo.PPOAgent(env.single_observation_space, env.single_action_space, config)
    untrained = _validation_successes(agent)
    iterate(agent, env, record)
    env.close()
    assert untrained == 0
    assert history[-1] == 15 and len(history) <= 20, history
