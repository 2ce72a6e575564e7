"""The device rollout and update (issue 40): each piece equals its CPU twin, and a rollout
never reads a tensor back to the host."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import torch

from learning.algorithms.device_loop import device_update
from learning.algorithms.device_rollout import (
    DeviceNormalizer,
    DeviceRolloutCollector,
    device_gae,
    fixed_horizon,
    normalize,
)
from learning.algorithms.gae import gae
from learning.algorithms.normalization import ObservationNormalizer, RunningMeanStd
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from usvsim.task.horizon import apply_reward_horizon
from usvsim.task.scenario import Scenario
from usvsim.task.torch_env import TorchPoleAvoidanceEnv


def test_fixed_horizon_equals_the_cpu_envs() -> None:
    rng = np.random.default_rng(0)
    sc, n = Scenario(), 400
    reward = -rng.uniform(0.0, 3.0, n)
    terminated = rng.random(n) < 0.3
    truncated = ~terminated & (rng.random(n) < 0.4)
    out_of_area = truncated & (rng.random(n) < 0.5)
    time_s = rng.integers(1, sc.max_decisions + 1, n) * sc.decision_period_s
    want = apply_reward_horizon(
        "fixed", 0.99, sc, reward, terminated, truncated, out_of_area, time_s
    )
    got = fixed_horizon(
        0.99,
        sc.max_decisions,
        sc.decision_period_s,
        *(torch.as_tensor(a) for a in (reward, terminated, truncated, out_of_area, time_s)),
    )
    np.testing.assert_allclose(got[0].numpy(), want[0], rtol=1e-14)
    np.testing.assert_array_equal(got[1].numpy(), want[1])
    np.testing.assert_array_equal(got[2].numpy(), want[2])
    assert want[1].sum() > terminated.sum()  # some boats left the area: now terminated


def test_device_gae_equals_gae() -> None:
    rng = np.random.default_rng(1)
    T, N = 37, 9
    r, v, nv = (rng.normal(size=(T, N)).astype(np.float32) for _ in range(3))
    term = rng.random((T, N)) < 0.1
    end = term | (rng.random((T, N)) < 0.1)
    adv, ret = gae(r, v, nv, term, end, 0.99, 0.97)
    d_adv, d_ret = device_gae(*(torch.as_tensor(a) for a in (r, v, nv, term, end)), 0.99, 0.97)
    np.testing.assert_array_equal(d_adv.numpy(), adv)
    np.testing.assert_array_equal(d_ret.numpy(), ret)


def test_merged_moments_equal_the_running_statistics() -> None:
    rng = np.random.default_rng(2)
    a, b = RunningMeanStd((4,)), RunningMeanStd((4,))
    for size in (7, 300, 1):
        x = rng.normal(3.0, 2.0, (size, 4))
        a.update(x)
        b.merge(x.mean(0), x.var(0), float(size))
    np.testing.assert_allclose(b.mean, a.mean, rtol=1e-13)
    np.testing.assert_allclose(b.var, a.var, rtol=1e-13)
    assert b.count == a.count == 308


def test_device_normalisation_equals_the_normaliser() -> None:
    env = TorchPoleAvoidanceEnv(8)
    norm = ObservationNormalizer(env.single_observation_space)
    x = np.random.default_rng(3).normal(50.0, 30.0, (500, 4)).astype(np.float32)
    norm.update(x[:100])
    s = norm.stats[""]
    mean, std = torch.as_tensor(s.mean), torch.as_tensor(np.sqrt(s.var + norm.eps))
    np.testing.assert_array_equal(normalize(torch.as_tensor(x), mean, std, 10.0).numpy(), norm(x))


def test_device_scene_standardisation_equals_the_normaliser() -> None:
    """``scaling="scene"``: the fixed constants, empty slots all zeros, then clipped, as the
    NumPy normaliser (on the torch open-water env's observations, some slots empty)."""
    from usvsim.task.torch_openwater import TorchOpenWaterEnv

    env = TorchOpenWaterEnv(16, observation="scene")
    obs, _ = env.reset(seed=1)
    rows = [obs]
    for _ in range(4):
        obs, *_ = env.step(torch.zeros((16, 1), dtype=torch.float64))
        rows.append(obs)
    x = torch.cat(rows)
    assert bool((x[:, 4 + 5 :: 6] == 0).any()) and bool((x[:, 4 + 5 :: 6] == 1).any())
    norm = ObservationNormalizer(env.single_observation_space, scaling="scene")
    got = DeviceNormalizer(norm, torch.device("cpu"))
    assert got.kind == "scene"
    np.testing.assert_array_equal(got(x).numpy(), norm(x.numpy()))


def _refuse_host_reads(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every way to read a tensor's value back to the host raises until ``monkeypatch.undo()``."""

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a tensor was read back to the host during a rollout")

    for name in ("__bool__", "item", "tolist", "numpy", "cpu", "__int__", "__float__"):
        monkeypatch.setattr(torch.Tensor, name, refuse)


def test_device_radar_goal_normalisation_equals_the_normaliser() -> None:
    """radar+goal: the image scaled by float32(1/255), the goal running-normalised, as NumPy."""
    from usvsim.task.torch_openwater import TorchOpenWaterEnv

    env = TorchOpenWaterEnv(8, observation="radar+goal")
    obs, _ = env.reset(seed=2)
    obs, *_ = env.step(torch.zeros((8, 1), dtype=torch.float64))
    norm = ObservationNormalizer(env.single_observation_space)
    norm.update({k: v.numpy() for k, v in obs.items()})
    got = DeviceNormalizer(norm, torch.device("cpu"))(obs)
    want = norm({k: v.numpy() for k, v in obs.items()})
    assert set(got) == set(want) == {"radar", "goal"} and bool((obs["radar"] > 0).any())
    for key in want:
        np.testing.assert_array_equal(got[key].numpy(), want[key])


def test_an_open_water_radar_rollout_never_reads_back_and_updates(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """radar+goal on the torch open-water env: 12 steps of 8 boats read nothing back to the
    host; the batch's dict parts keep their shapes and the update stays in the trust region."""
    from usvsim.task.torch_openwater import TorchOpenWaterEnv

    env = TorchOpenWaterEnv(8, observation="radar+goal", per_boat=4, reward_horizon="fixed")
    cfg = TRPOConfig(num_envs=8, steps_per_env=12, max_kl=0.01, critic_minibatch=32)
    agent = TRPOAgent(env.single_observation_space, env.single_action_space, cfg)
    collector = DeviceRolloutCollector(env, 0.99, seed=0)
    normalise = DeviceNormalizer(agent.normalizer, torch.device("cpu"))

    _refuse_host_reads(monkeypatch)
    batch = collector.collect(agent.policy, normalise, 12)
    monkeypatch.undo()
    assert isinstance(batch.obs, dict) and isinstance(batch.next_obs, dict)
    assert batch.obs["radar"].shape == (12, 8, 1, 50, 119) and batch.obs["goal"].shape == (12, 8, 2)
    stats = device_update(agent, batch)
    assert stats.line_search_accepted and 0.0 < stats.kl <= 0.01
    assert agent.normalizer.stats["goal"].count >= 96


def _agent(env: TorchPoleAvoidanceEnv, **kw: object) -> TRPOAgent:
    cfg = TRPOConfig(num_envs=env.num_envs, steps_per_env=20, **kw)  # type: ignore[arg-type]
    return TRPOAgent(env.single_observation_space, env.single_action_space, cfg)


def test_a_rollout_never_reads_a_tensor_back_to_the_host(monkeypatch: pytest.MonkeyPatch) -> None:
    """20 steps of 32 boats (policy, sampling, env, fixed horizon, buffers, episode sums) with
    every way to read a tensor's value raising; episodes end inside the watched steps."""
    env = TorchPoleAvoidanceEnv(32, action="categorical")
    agent = _agent(env)
    agent.normalizer.update(np.random.default_rng(0).normal(size=(64, 4)))
    collector = DeviceRolloutCollector(env, 0.99, seed=0)
    normalise = DeviceNormalizer(agent.normalizer, torch.device("cpu"))

    _refuse_host_reads(monkeypatch)
    batch = collector.collect(agent.policy, normalise, 20)
    monkeypatch.undo()
    assert batch.obs.shape == batch.next_obs.shape == (20, 32, 4)
    assert batch.actions.shape == batch.log_probs.shape == batch.rewards.shape == (20, 32)
    ended = int(batch.episode_end.sum())
    assert ended >= 1 and int(batch.episode_sums[0]) == ended
    # s'_t is s_{t+1} wherever the episode went on
    go_on = ~batch.episode_end[:-1]
    assert torch.equal(batch.next_obs[:-1][go_on], batch.obs[1:][go_on])


@pytest.mark.parametrize("action", ["categorical", "gaussian"])
def test_a_device_update_stays_in_the_trust_region(action: str) -> None:
    env = TorchPoleAvoidanceEnv(16, action=action)  # type: ignore[arg-type]
    agent = _agent(env, max_kl=0.01)
    normalise = DeviceNormalizer(agent.normalizer, torch.device("cpu"))
    batch = DeviceRolloutCollector(env, 0.99, seed=0).collect(agent.policy, normalise, 20)
    stats = device_update(agent, batch)
    assert stats.line_search_accepted and 0.0 < stats.kl <= 0.01
    assert agent.iteration == 1 and agent.env_steps == 320
    assert agent.normalizer.stats[""].count == 320


@pytest.mark.parametrize("action", ["categorical", "gaussian"])
def test_the_torch_envs_action_space_is_the_cpu_envs(action: str) -> None:
    from usvsim.task.batch import action_space

    env = TorchPoleAvoidanceEnv(2, action=action)  # type: ignore[arg-type]
    assert env.single_action_space == action_space(action)  # type: ignore[arg-type]


def test_device_training_runs_without_casadi_scipy_or_filterpy() -> None:
    """What a GPU machine has (gpu_check.sh's train-bench): torch, NumPy and gymnasium."""
    code = (
        "import sys\n"
        "sys.modules.update(casadi=None, scipy=None, control=None, filterpy=None)\n"
        "from learning.algorithms.device_loop import train_on_device\n"
        "from learning.algorithms.trpo import TRPOConfig\n"
        "from usvsim.task.torch_env import TorchPoleAvoidanceEnv\n"
        "cfg = TRPOConfig(iterations=1, num_envs=4, steps_per_env=8)\n"
        "agent = train_on_device(cfg, lambda n: TorchPoleAvoidanceEnv(n, action='categorical'))\n"
        "print(agent.iteration, agent.env_steps)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout.split()
    assert out == ["1", "32"]


def test_same_seed_same_device_training_on_the_cpu() -> None:
    from learning.algorithms.device_loop import train_on_device

    def run(seed: int) -> tuple[list[tuple[float, float, float]], torch.Tensor]:
        curve: list[tuple[float, float, float]] = []
        cfg = TRPOConfig(seed=seed, iterations=2, num_envs=8, steps_per_env=16)
        agent = train_on_device(
            cfg,
            lambda n: TorchPoleAvoidanceEnv(n, action="categorical"),
            callback=lambda s, a: curve.append((s.mean_return, s.kl, s.update.value_loss)),
        )
        return curve, torch.cat([p.detach().flatten() for p in agent.policy.parameters()])

    (curve_a, weights_a), (curve_b, weights_b) = run(0), run(0)
    np.testing.assert_array_equal(np.array(curve_a), np.array(curve_b))  # NaN: no episode ended
    assert torch.equal(weights_a, weights_b)
    assert not torch.equal(run(1)[1], weights_a)
