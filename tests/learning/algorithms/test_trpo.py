"""TRPO: conjugate gradient, Fisher-vector products, trust region, line search, learning."""

from __future__ import annotations

import copy
import dataclasses
import time
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium import spaces
from gymnasium.vector import AutoresetMode

from learning.algorithms.loop import IterationStats, train
from learning.algorithms.networks import NetworkConfig, make_policy
from learning.algorithms.rollout import NonFiniteError, RolloutBatch, RolloutCollector, flatten_obs
from learning.algorithms.trpo import TRPOAgent, TRPOConfig, trpo_step
from learning.algorithms.trust_region import (
    conjugate_gradient,
    fisher_vector_product,
    get_flat,
    jacobian_fisher_vector_product,
    kl_hessian_vector_product,
    line_search,
)

SMALL = NetworkConfig(hidden=(64, 64))
CARTPOLE = TRPOConfig(
    seed=0,
    iterations=40,
    num_envs=8,
    steps_per_env=256,
    max_kl=0.02,
    gae_lambda=0.95,
    fvp_fraction=0.25,
    network=SMALL,
)


def _cartpole(n: int) -> gym.vector.VectorEnv:
    return gym.make_vec("CartPole-v1", n, vectorization_mode="sync")


def _pendulum(n: int) -> gym.vector.VectorEnv:
    return gym.make_vec("Pendulum-v1", n, vectorization_mode="sync")


def _rollout(make_env, config: TRPOConfig) -> tuple[TRPOAgent, RolloutBatch]:  # type: ignore[no-untyped-def]
    env = make_env(config.num_envs)
    agent = TRPOAgent(env.single_observation_space, env.single_action_space, config)
    batch = RolloutCollector(env, seed=config.seed).collect(agent.sample, config.steps_per_env)
    env.close()
    return agent, batch


def _params(module: torch.nn.Module) -> list[torch.Tensor]:
    return [p.detach().clone() for p in module.parameters()]


def _same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


# --- exact pieces ------------------------------------------------------------------------------


def test_conjugate_gradient_solves_spd_system() -> None:
    rng = np.random.default_rng(0)
    m = rng.normal(size=(12, 12))
    A = m @ m.T + 0.5 * np.eye(12)
    b = rng.normal(size=12)
    At = torch.tensor(A)
    x = conjugate_gradient(lambda v: At @ v, torch.tensor(b), iters=12)
    np.testing.assert_allclose(x.numpy(), np.linalg.solve(A, b), rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize(
    "product",
    [fisher_vector_product, kl_hessian_vector_product, jacobian_fisher_vector_product],
    ids=["chosen", "double-backward", "jacobian"],
)
@pytest.mark.parametrize("trunk", ["mlp", "cnn"])
@pytest.mark.parametrize(
    "action_space",
    [spaces.Box(-2.0, 2.0, (2,), np.float32), spaces.Discrete(5)],
    ids=["gaussian", "categorical"],
)
def test_fisher_vector_product_equals_hessian_of_mean_kl(
    action_space: spaces.Space, trunk: str, product: Any
) -> None:
    torch.manual_seed(0)
    if trunk == "mlp":
        obs_space = spaces.Box(-1.0, 1.0, (3,), np.float32)
        obs = torch.randn(6, 3, dtype=torch.float64)
    else:  # a small image: conv 2 × 3×3 stride 2 → ReLU → BatchNorm (eval, set statistics)
        obs_space = spaces.Box(0, 255, (1, 7, 7), np.uint8)
        obs = torch.rand(6, 1, 7, 7, dtype=torch.float64)
    cfg = NetworkConfig(hidden=(4,), conv_kernels=2, conv_size=3, conv_stride=2)
    policy = make_policy(obs_space, action_space, cfg).double()
    with torch.no_grad():  # a head that is not almost zero, so the Hessian is non-trivial
        policy.head.weight.normal_()
        for m in policy.modules():
            if isinstance(m, torch.nn.BatchNorm2d):
                for value, (low, high) in zip(
                    (m.running_mean, m.running_var, m.weight, m.bias),
                    ((0.1, 0.3), (0.5, 2.0), (0.5, 1.5), (-0.2, 0.2)),
                    strict=True,
                ):
                    value.uniform_(low, high)
    names = [n for n, _ in policy.named_parameters()]
    shapes = [p.shape for p in policy.parameters()]
    theta = get_flat(list(policy.parameters()))
    old = policy(obs).detach()

    def mean_kl(flat: torch.Tensor) -> torch.Tensor:
        chunks = torch.split(flat, [int(np.prod(s)) for s in shapes])
        params = {n: c.view(s) for n, c, s in zip(names, chunks, shapes, strict=True)}
        return old.kl(torch.func.functional_call(policy, params, (obs,))).mean()

    H = torch.autograd.functional.hessian(mean_kl, theta)
    v = torch.randn_like(theta)
    fvp = product(policy, obs, damping=0.0)
    torch.testing.assert_close(fvp(v), H @ v, rtol=1e-9, atol=1e-12)
    torch.testing.assert_close(
        product(policy, obs, damping=0.3)(v), H @ v + 0.3 * v, rtol=1e-9, atol=1e-12
    )
    assert float(H.abs().max()) > 1e-3  # the comparison is not 0 == 0


def test_line_search_restores_parameters_exactly_when_nothing_is_accepted() -> None:
    policy = make_policy(spaces.Box(-1, 1, (3,), np.float32), spaces.Discrete(4), SMALL)
    params = list(policy.parameters())
    before = _params(policy)
    trials: list[float] = []

    def worse() -> tuple[float, float]:  # the surrogate can never improve
        trials.append(float(get_flat(params)[0]))
        return -1.0, 0.0

    step = torch.randn_like(get_flat(params))
    result = line_search(params, step, worse, surrogate_old=0.0, max_kl=0.01, steps=7, decay=0.5)
    assert not result.accepted and result.trials == 7 and result.step_fraction == 0.0
    assert len(set(trials)) == 7  # seven different points were tried
    assert _same(before, _params(policy))


def test_line_search_takes_first_fraction_within_trust_region() -> None:
    policy = make_policy(spaces.Box(-1, 1, (3,), np.float32), spaces.Discrete(4), SMALL)
    params = list(policy.parameters())
    theta = get_flat(params)
    step = torch.ones_like(theta)
    kls = iter([0.5, 0.02, 0.005])  # too far, too far, inside δ = 0.01
    result = line_search(params, step, lambda: (1.0, next(kls)), 0.0, 0.01, 10, 0.5)
    assert result.accepted and result.trials == 3 and result.step_fraction == 0.25
    assert result.kl == 0.005 and result.improvement == 1.0
    torch.testing.assert_close(get_flat(params), theta + 0.25 * step, rtol=0, atol=1e-6)


@pytest.mark.parametrize("make_env", [_cartpole, _pendulum], ids=["categorical", "gaussian"])
def test_mean_kl_after_update_within_trust_region(make_env) -> None:  # type: ignore[no-untyped-def]
    config = dataclasses.replace(CARTPOLE, max_kl=0.01, steps_per_env=128)
    agent, batch = _rollout(make_env, config)
    raw = flatten_obs(batch.obs, 2)[batch.valid.reshape(-1)]  # type: ignore[index]
    obs = agent.policy_input(raw)  # normalised as in the update (before the statistics refresh)
    old_policy = copy.deepcopy(agent.policy)
    step = agent.update(batch).policy_step
    assert step.line_search.accepted
    with torch.no_grad():
        kl = float(old_policy(obs).kl(agent.policy(obs)).mean())
    assert 0.0 < kl <= config.max_kl * 1.5
    assert kl == pytest.approx(step.line_search.kl, rel=1e-4)
    assert step.line_search.improvement > 0


# --- bad input ---------------------------------------------------------------------------------


def test_nan_observation_in_batch_raises_and_leaves_networks_unchanged() -> None:
    agent, batch = _rollout(_cartpole, dataclasses.replace(CARTPOLE, steps_per_env=32))
    policy, critic = _params(agent.policy), _params(agent.critic)
    assert isinstance(batch.obs, np.ndarray)
    batch.obs[5, 2, 1] = np.nan
    with pytest.raises(NonFiniteError, match="non-finite"):
        agent.update(batch)
    assert _same(policy, _params(agent.policy)) and _same(critic, _params(agent.critic))
    assert agent.iteration == 0


def test_nan_reward_raises_and_leaves_networks_unchanged() -> None:
    agent, batch = _rollout(_cartpole, dataclasses.replace(CARTPOLE, steps_per_env=32))
    policy, critic = _params(agent.policy), _params(agent.critic)
    batch.rewards[3, 0] = np.nan
    with pytest.raises(NonFiniteError, match="advantages or returns"):
        agent.update(batch)
    assert _same(policy, _params(agent.policy)) and _same(critic, _params(agent.critic))


def test_nan_loss_in_policy_step_raises_before_any_change() -> None:
    policy = make_policy(spaces.Box(-1, 1, (3,), np.float32), spaces.Discrete(4), SMALL)
    before = _params(policy)
    adv = torch.ones(16)
    adv[4] = float("nan")
    with pytest.raises(NonFiniteError, match="surrogate"):
        trpo_step(
            policy,
            torch.randn(16, 3),
            torch.zeros(16, dtype=torch.long),
            adv,
            TRPOConfig(),
            torch.Generator().manual_seed(0),
        )
    assert _same(before, _params(policy))


# --- checkpoints -------------------------------------------------------------------------------


def test_state_dict_round_trip_and_mismatch() -> None:
    config = dataclasses.replace(CARTPOLE, iterations=1, steps_per_env=64)
    agent = train(config, _cartpole)
    state = agent.state_dict()
    again = TRPOAgent.from_state_dict(state)
    assert again.iteration == 1 and again.env_steps == agent.env_steps
    obs = np.random.default_rng(0).normal(size=(20, 4)).astype(np.float32)
    np.testing.assert_array_equal(again.act(obs), agent.act(obs))
    np.testing.assert_array_equal(again.values(obs), agent.values(obs))
    other = TRPOAgent(spaces.Box(-1, 1, (3,), np.float32), spaces.Discrete(2), config)
    with pytest.raises(ValueError, match="observation_space"):
        other.load_state_dict(state)


def test_resume_continues_counting() -> None:
    config = dataclasses.replace(CARTPOLE, iterations=2, steps_per_env=64)
    state = train(config, _cartpole).state_dict()
    seen: list[int] = []
    resumed = train(
        dataclasses.replace(config, iterations=3),
        _cartpole,
        state=state,
        callback=lambda s, a: seen.append(s.iteration) is None and False,
    )
    assert seen == [3] and resumed.iteration == 3


# --- it learns ---------------------------------------------------------------------------------


def _curve(stats: list[IterationStats]) -> list[tuple[float, ...]]:
    timeless = [f.name for f in dataclasses.fields(IterationStats) if not f.name.endswith("_s")]
    return [tuple(getattr(s, n) for n in timeless) for s in stats]


def test_same_seed_same_curve() -> None:
    config = dataclasses.replace(CARTPOLE, iterations=3, steps_per_env=128)
    runs = []
    for _ in range(2):
        stats: list[IterationStats] = []
        agent = train(config, _cartpole, callback=lambda s, a: stats.append(s))  # noqa: B023
        runs.append((_curve(stats), _params(agent.policy)))
    assert runs[0][0] == runs[1][0]
    assert _same(runs[0][1], runs[1][1])
    other: list[IterationStats] = []
    train(dataclasses.replace(config, seed=1), _cartpole, callback=lambda s, a: other.append(s))
    assert _curve(other) != runs[0][0]


@pytest.mark.slow
def test_trpo_solves_cartpole_within_ci_budget() -> None:
    """CartPole-v1 mean return ≥ 195 (finished episodes of one iteration) within 40 iterations
    of 2048 steps and 60 s of wall time, and ≥ 195 for the deterministic policy on 5 fresh
    episodes. Measured on 2 cores: 5 iterations (~10k steps), 0.6-1 s, for seeds 0-4."""
    stats: list[IterationStats] = []

    def record(s: IterationStats, agent: TRPOAgent) -> bool:
        stats.append(s)
        return s.mean_return >= 195.0

    start = time.perf_counter()
    agent = train(CARTPOLE, _cartpole, callback=record)
    elapsed = time.perf_counter() - start
    assert stats[-1].mean_return >= 195.0, [round(s.mean_return, 1) for s in stats]
    assert len(stats) <= 40 and elapsed < 60.0
    assert stats[0].mean_return < 50.0  # the random policy's level: learning did it
    # the deterministic policy (as a helmsman would use it) on fresh episodes
    returns = []
    for i in range(5):
        env = gym.make("CartPole-v1")
        obs, _ = env.reset(seed=1000 + i)
        total, done = 0.0, False
        while not done:
            obs, reward, terminated, truncated, _ = env.step(int(agent.act(obs[None])[0]))
            total, done = total + float(reward), terminated or truncated
        returns.append(total)
    assert np.mean(returns) >= 195.0, returns


def test_train_with_same_step_autoreset() -> None:
    def make(n: int) -> gym.vector.VectorEnv:
        return gym.make_vec(
            "CartPole-v1",
            n,
            vectorization_mode="sync",
            vector_kwargs={"autoreset_mode": AutoresetMode.SAME_STEP},
        )

    stats: list[IterationStats] = []
    agent = train(
        dataclasses.replace(CARTPOLE, iterations=2, steps_per_env=128),
        make,
        callback=lambda s, a: stats.append(s),
    )
    assert agent.env_steps == 2 * 8 * 128  # SAME_STEP: every step is a valid transition
    assert all(s.episodes > 0 and np.isfinite(s.mean_return) for s in stats)


@pytest.mark.slow
def test_trpo_learns_pendulum() -> None:
    """Pendulum-v1 (Gaussian head): mean return > -400 within 120 iterations (random ≈ -1200)."""
    config = TRPOConfig(
        seed=0,
        iterations=120,
        num_envs=8,
        steps_per_env=200,
        max_kl=0.02,
        gamma=0.95,
        gae_lambda=0.95,
        network=SMALL,
    )
    stats: list[IterationStats] = []
    train(config, _pendulum, callback=lambda s, a: stats.append(s) or s.mean_return > -400)
    assert stats[-1].mean_return > -400.0, [round(s.mean_return) for s in stats[-5:]]


@pytest.mark.parametrize("freeze", [False, True])
def test_fixed_input_stats_keep_the_normaliser(freeze: bool) -> None:
    """``fixed_input_stats`` (fine-tuning a loaded policy): the update changes the policy but
    not the observation statistics it was loaded with; without it they follow the rollouts."""
    config = dataclasses.replace(CARTPOLE, steps_per_env=64, fixed_input_stats=freeze)
    agent, batch = _rollout(_cartpole, config)
    stats = agent.normalizer.stats
    before = {k: (s.mean.copy(), s.var.copy()) for k, s in stats.items()}
    params = _params(agent.policy)
    agent.update(batch)
    same = all(
        np.array_equal(before[k][0], s.mean) and np.array_equal(before[k][1], s.var)
        for k, s in stats.items()
    )
    assert same == freeze
    assert not _same(params, _params(agent.policy))
