"""GAE on hand-computed cases, value bootstrapping, and rollouts under both autoreset modes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from learning.algorithms.gae import gae
from learning.algorithms.rollout import (
    NonFiniteError,
    RolloutBatch,
    RolloutCollector,
    attach_values,
)


def test_gae_hand_computed_truncated_and_terminated() -> None:
    # Two envs, three steps, γ = 0.9, λ = 0.5.
    # env 0: steps 0, 1 form an episode TRUNCATED at t = 1 (bootstrap V(s_final) = 4);
    #        step 2 starts a new episode, bootstrapped at the batch end with V(s_3) = 2.
    # env 1: TERMINATED at t = 1 (no bootstrap although next_values says 100);
    #        step 2 starts a new episode, bootstrapped with V(s_3) = 1.
    gamma, lam = 0.9, 0.5
    rewards = np.array([[1.0, 2.0], [0.0, 1.0], [3.0, -1.0]])
    values = np.array([[0.5, 1.0], [1.0, 2.0], [0.0, 0.0]])
    next_values = np.array([[1.0, 2.0], [4.0, 100.0], [2.0, 1.0]])
    terminated = np.array([[False, False], [False, True], [False, False]])
    truncated = np.array([[False, False], [True, False], [False, False]])
    adv, ret = gae(rewards, values, next_values, terminated, terminated | truncated, gamma, lam)

    # env 0, by hand
    d02 = 3.0 + 0.9 * 2.0 - 0.0  # 4.8
    d01 = 0.0 + 0.9 * 4.0 - 1.0  # 2.6 (bootstrap on truncation)
    d00 = 1.0 + 0.9 * 1.0 - 0.5  # 1.4
    a02, a01 = d02, d01  # the recursion stops at the episode end
    a00 = d00 + 0.9 * 0.5 * a01  # 1.4 + 0.45 · 2.6 = 2.57
    # env 1, by hand
    d12 = -1.0 + 0.9 * 1.0 - 0.0  # -0.1
    d11 = 1.0 - 2.0  # -1.0 (terminated: no bootstrap)
    d10 = 2.0 + 0.9 * 2.0 - 1.0  # 2.8
    a12, a11 = d12, d11
    a10 = d10 + 0.45 * a11  # 2.35
    expected = np.array([[a00, a10], [a01, a11], [a02, a12]], dtype=np.float32)
    np.testing.assert_allclose(adv, expected, rtol=1e-6)
    np.testing.assert_allclose(ret, expected + values, rtol=1e-6)
    assert adv.dtype == np.float32 and ret.dtype == np.float32


def test_gae_lambda_one_is_discounted_return_minus_value() -> None:
    rewards = np.array([[1.0], [2.0], [3.0]])
    values = np.array([[0.3], [0.2], [0.1]])
    next_values = np.array([[0.2], [0.1], [5.0]])
    none = np.zeros((3, 1), dtype=bool)
    adv, _ = gae(rewards, values, next_values, none, none, gamma=0.5, lam=1.0)
    mc = 1.0 + 0.5 * 2.0 + 0.25 * 3.0 + 0.125 * 5.0  # Monte-Carlo return, bootstrapped at the end
    assert adv[0, 0] == pytest.approx(mc - 0.3, rel=1e-6)


def test_gae_rejects_mismatched_shapes() -> None:
    with pytest.raises(ValueError, match="values"):
        gae(
            np.zeros((3, 2)),
            np.zeros((3, 1)),
            np.zeros((3, 2)),
            np.zeros((3, 2), bool),
            np.zeros((3, 2), bool),
            0.9,
            0.9,
        )


def _batch(
    obs: np.ndarray,
    last: np.ndarray,
    final_obs: np.ndarray | None,
    final_index: list[tuple[int, int]],
    end: np.ndarray,
) -> RolloutBatch:
    T, N = obs.shape[:2]
    z = np.zeros((T, N), dtype=np.float32)
    return RolloutBatch(
        obs=obs,
        actions=z,
        log_probs=z,
        rewards=z,
        terminated=np.zeros_like(end),
        truncated=end,
        valid=np.ones((T, N), bool),
        last_obs=last,
        final_obs=final_obs,
        final_index=np.array(final_index, dtype=np.intp).reshape(-1, 2),
    )


def test_attach_values_uses_final_observation_of_same_step_autoreset() -> None:
    # V(s) = s[0]. Env 1 is truncated at t = 0; its final observation (7) replaced by a reset (9).
    obs = np.array([[[1.0], [2.0]], [[3.0], [9.0]]])
    end = np.array([[False, True], [False, False]])
    batch = _batch(obs, np.array([[5.0], [6.0]]), np.array([[7.0]]), [(0, 1)], end)
    calls: list[int] = []

    def value_fn(o: np.ndarray) -> np.ndarray:
        calls.append(len(o))
        return o[:, 0].astype(np.float32)

    attach_values(batch, value_fn)
    assert calls == [4 + 2 + 1]  # one batched call
    np.testing.assert_array_equal(batch.values, [[1.0, 2.0], [3.0, 9.0]])
    np.testing.assert_array_equal(batch.next_values, [[3.0, 7.0], [5.0, 6.0]])


def _collect(mode: AutoresetMode, steps: int) -> RolloutBatch:
    env = gym.make_vec(
        "CartPole-v1", 2, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}
    )
    collector = RolloutCollector(env, seed=3)
    batch = collector.collect(
        lambda o: (np.ones(len(o), dtype=np.int64), np.zeros(len(o), np.float32)), steps
    )
    env.close()
    return batch


def test_next_step_autoreset_masks_the_reset_step() -> None:
    batch = _collect(AutoresetMode.NEXT_STEP, 40)  # always push right: episodes of ~10 steps
    end = batch.episode_end
    assert end.sum() >= 4
    t, n = np.nonzero(end[:-1])
    assert not batch.valid[t + 1, n].any()  # the step after an end only resets
    assert batch.valid.sum() == batch.valid.size - len(t)
    assert batch.rewards[~batch.valid].sum() == 0.0
    assert batch.final_obs is None
    # CartPole pays 1 per step: each finished episode's return is its length.
    assert batch.episode_returns == [float(n) for n in batch.episode_lengths]


def test_same_step_and_next_step_see_the_same_episodes() -> None:
    nxt = _collect(AutoresetMode.NEXT_STEP, 40)
    same = _collect(AutoresetMode.SAME_STEP, 40)
    assert same.valid.all()
    assert same.final_obs is not None and len(same.final_index) == same.episode_end.sum()
    # Same seeds, same (constant) actions: the same episodes, NEXT_STEP just spends reset steps.
    assert sorted(nxt.episode_lengths) == sorted(same.episode_lengths[: len(nxt.episode_lengths)])
    # The final observation of an episode is the obs NEXT_STEP shows right after its end.
    t_n, _ = np.nonzero(nxt.episode_end[:-1, :1])
    t_s = same.final_index[same.final_index[:, 1] == 0, 0]
    first_final_next = nxt.obs[t_n[0] + 1, 0]
    first_final_same = same.final_obs[np.flatnonzero(same.final_index[:, 1] == 0)[0]]
    assert t_s[0] == t_n[0]
    np.testing.assert_array_equal(first_final_next, first_final_same)


class _NaNEnv(gym.Env[np.ndarray, int]):
    observation_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    action_space = gym.spaces.Discrete(2)

    def reset(self, *, seed: int | None = None, options: dict | None = None):  # type: ignore[override]
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(2, np.float32), {}

    def step(self, action: int):  # type: ignore[override]
        self.t += 1
        obs = np.full(2, np.nan if self.t == 3 else 0.0, np.float32)
        return obs, 0.0, False, False, {}


def test_nan_observation_from_env_raises() -> None:
    env = gym.vector.SyncVectorEnv([_NaNEnv, _NaNEnv])
    collector = RolloutCollector(env, seed=0)
    with pytest.raises(NonFiniteError, match="observations at step 2"):
        collector.collect(lambda o: (np.zeros(len(o), np.int64), np.zeros(len(o), np.float32)), 5)


class _StrictBoxEnv(gym.Env[np.ndarray, np.ndarray]):
    """Raises on actions outside [-1, 1], as usvsim's vector env does."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict | None = None):  # type: ignore[override]
        super().reset(seed=seed)
        return np.zeros(2, np.float32), {}

    def step(self, action: np.ndarray):  # type: ignore[override]
        if not self.action_space.contains(np.asarray(action, np.float32)):
            raise ValueError(f"action {action} out of bounds")
        return np.zeros(2, np.float32), float(action[0]), False, False, {}


def test_box_actions_are_clipped_for_the_env_but_stored_unclipped() -> None:
    env = gym.vector.SyncVectorEnv([_StrictBoxEnv, _StrictBoxEnv])
    collector = RolloutCollector(env, seed=0)
    samples = np.array([[3.0], [-0.25]], np.float32)
    batch = collector.collect(lambda o: (samples, np.zeros(2, np.float32)), 3)
    np.testing.assert_array_equal(batch.actions[2], samples)
    np.testing.assert_array_equal(batch.rewards[2], [1.0, -0.25])
