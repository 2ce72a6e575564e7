"""Stable-Baselines3: make_vec_env with defaults, check_env, the native-batch adapter, PPO."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import usvsim
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO
from stable_baselines3.common.env_checker import check_env
from stable_baselines3.common.env_util import make_vec_env

from usvsim.task.sb3 import SB3Helmsman, SB3VecEnv, make_sb3_vec_env


@pytest.fixture(autouse=True)
def sb3_logs_in_tmp_path(tmp_path, monkeypatch):
    """SB3 makes a log folder per ``learn`` call, by default a new tempdir/SB3-<time>: here the
    test's own temporary folder, which pytest cleans up."""
    monkeypatch.setenv("SB3_LOGDIR", str(tmp_path / "sb3"))


def test_make_vec_env_with_defaults_steps_and_renders():
    env = make_vec_env(usvsim.ENV_ID, n_envs=4, seed=0)
    obs = env.reset()
    assert obs.shape == (4, 4) and env.render_mode == "rgb_array"
    episodes = 0
    for _ in range(80):
        obs, reward, done, infos = env.step(np.zeros((4, 1), dtype=np.float32))
        assert np.isfinite(reward).all()
        episodes += int(done.sum())
    assert episodes >= 4  # straight ahead: every boat hits its pole within 80 decisions
    assert "episode" in infos[0] or episodes  # SB3's Monitor wrapper is there
    assert env.render().shape == (800, 800, 3)  # SB3 tiles the four 400 × 400 frames


@pytest.mark.parametrize("observation", ["positional", "radar", "radar+goal"])
@pytest.mark.parametrize("action", ["gaussian", "categorical"])
@pytest.mark.parametrize("normalize", [False, True])
def test_sb3_check_env_is_clean(observation, action, normalize):
    env = gym.make(
        usvsim.ENV_ID,
        observation=observation,
        action=action,
        normalize_observation=normalize,
        render_mode="rgb_array",
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, warn=True)
    assert [str(w.message) for w in caught] == []


def test_adapter_equals_the_vector_env_and_reports_episode_ends():
    adapter = make_sb3_vec_env(3, action="categorical", seed=11)
    native = PoleAvoidanceVectorEnv(
        3, action="categorical", reward_horizon="fixed", normalize_observation=True
    )
    np.testing.assert_array_equal(adapter.reset(), native.reset(seed=11)[0])
    ended = 0
    for k in range(80):
        act = np.array([20, 20 + k % 7, 14])
        obs, reward, done, infos = adapter.step(act)
        n_obs, n_reward, terminated, truncated, info = native.step(act)
        np.testing.assert_array_equal(obs, n_obs)
        np.testing.assert_array_equal(reward, n_reward.astype(np.float32))
        np.testing.assert_array_equal(done, terminated | truncated)
        for i in np.flatnonzero(done):
            ended += 1
            np.testing.assert_array_equal(infos[i]["terminal_observation"], info["final_obs"][i])
            assert infos[i]["TimeLimit.truncated"] == bool(truncated[i] and not terminated[i])
            assert infos[i]["episode"]["l"] >= 1
            assert infos[i]["is_success"] == info["is_success"][i]
    assert ended >= 3


def test_adapter_rejects_what_it_cannot_do():
    with pytest.raises(ValueError, match="wraps a PoleAvoidanceVectorEnv"):
        SB3VecEnv(gym.make_vec(usvsim.ENV_ID, num_envs=2, vectorization_mode="sync"))
    env = make_sb3_vec_env(2)
    with pytest.raises(RuntimeError, match="render_mode='rgb_array'"):
        env.get_images()
    assert make_sb3_vec_env(2, render_mode="rgb_array").render().shape == (800, 400, 3)


def test_ppo_collects_full_rollouts_on_the_adapter():
    env = make_sb3_vec_env(4, seed=0)
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=64, n_epochs=1, seed=0)
    model.learn(256)
    assert model.num_timesteps == 256
    buffer = model.rollout_buffer
    assert (buffer.buffer_size, buffer.n_envs) == (32, 4)
    assert buffer.observations.shape == (128, 4)  # flattened for the update: 32 steps × 4 boats


@pytest.mark.slow
def test_sb3_ppo_with_default_hyperparameters_learns_the_task():
    """SB3 PPO, its defaults, 8 boats; measured (seed 0): 15/15 first at 102k-115k env steps,
    ~35-45 s (benchmarks/train_sb3.py). Stops at the first ≥ 14/15."""
    import torch

    from usvsim.evaluation.episodes import evaluate, validation_episodes

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    env = make_sb3_vec_env(8, seed=0)
    model = PPO("MlpPolicy", env, seed=0)
    best = 0
    try:
        for _ in range(12):  # 12 × 16,384 env steps at most
            model.learn(8 * 2048, reset_num_timesteps=False)
            records = evaluate(SB3Helmsman(model), validation_episodes())
            best = max(best, sum(r.success for r in records))
            if best >= 14:
                break
    finally:
        torch.set_num_threads(threads)
    assert best >= 14
