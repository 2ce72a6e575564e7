"""Env options: the fixed reward horizon (single and vector env alike), observation normalisation,
and the registered vector entry point."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import usvsim
from usvsim.task.env import PoleAvoidanceEnv
from usvsim.task.horizon import apply_reward_horizon
from usvsim.task.observations import POSITIONAL_STANDARDIZATION
from usvsim.task.scenario import EpisodeSpec, Scenario
from usvsim.task.vector_env import PoleAvoidanceVectorEnv
from usvsim.vessel.plant import Plant

STRAIGHT = np.full(2, 20)  # categorical 20: 0°, straight at the pole → collision


@pytest.fixture(scope="module")
def plant():
    return Plant()


def test_fixed_horizon_adds_the_remaining_discounted_reward(plant):
    gamma = 0.99
    env = PoleAvoidanceVectorEnv(
        2, action="categorical", reward_horizon="fixed", gamma=gamma, plant=plant
    )
    K = env.sim.scenario.max_decisions
    env.reset(seed=0)
    for _ in range(K):
        _, reward, terminated, _, info = env.step(STRAIGHT)
        if terminated.any():
            break
    assert np.array_equal(terminated, info["collision"]) and terminated.any()
    m = K - np.rint(info["time_s"] / 2.0)
    plain = info["reward_pole"] + info["reward_goal"]
    expected = np.where(terminated, plain * (1 + gamma * (1 - gamma**m) / (1 - gamma)), plain)
    np.testing.assert_allclose(reward, expected)
    assert (reward[terminated] < -40).all()  # ~ -2.5 for each decision left


def test_single_env_has_the_same_fixed_horizon_as_the_vector_env(plant):
    kinds = {"action": "categorical", "reward_horizon": "fixed", "plant": plant}
    vec = PoleAvoidanceVectorEnv(1, **kinds)
    single = PoleAvoidanceEnv(**kinds)
    vec.reset(seed=4)
    single.reset(seed=4)
    for _ in range(75):
        _, rv, tv, uv, _ = vec.step(STRAIGHT[:1])
        _, rs, ts, us, _ = single.step(20)
        assert rs == rv[0] and (ts, us) == (tv[0], uv[0])
        if ts or us:
            break
    assert ts and rs < -40


def test_episode_horizon_is_the_plain_reward(plant):
    env = PoleAvoidanceEnv(action="categorical", plant=plant)
    env.reset(seed=0)
    while True:
        _, reward, terminated, truncated, info = env.step(20)
        assert reward == info["reward_pole"] + info["reward_goal"]
        if terminated or truncated:
            break
    assert terminated and reward > -5


def test_leaving_the_area_terminates_only_on_the_fixed_horizon(plant):
    spec = EpisodeSpec(
        pole_index=0, start_distance_m=90.0, start_bearing_rad=0.0, heading_offset_rad=np.pi
    )  # heading away from the pole
    flags = {}
    for horizon in ("episode", "fixed"):
        env = PoleAvoidanceEnv(reward_horizon=horizon, plant=plant)
        env.reset(options={"episode": spec})
        while True:
            _, _, terminated, truncated, info = env.step(np.zeros(1, dtype=np.float32))
            if terminated or truncated:
                break
        assert info["out_of_area"]
        flags[horizon] = (terminated, truncated)
    assert flags == {"episode": (False, True), "fixed": (True, False)}


def test_time_limit_stays_a_truncation():
    sc = Scenario()
    reward, terminated, truncated = apply_reward_horizon(
        "fixed",
        0.99,
        sc,
        np.array([-1.0]),
        np.array([False]),
        np.array([True]),
        np.array([False]),
        np.array([sc.time_limit_s]),
    )
    assert reward.tolist() == [-1.0] and not terminated[0] and truncated[0]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"reward_horizon": "forever"}, r"reward_horizon must be one of \('episode', 'fixed'\)"),
        ({"reward_horizon": "fixed", "gamma": 1.0}, r"gamma must lie in \[0, 1\)"),
        ({"normalize_observation": "yes"}, "normalize_observation must be True or False"),
    ],
)
def test_bad_options_raise(kwargs, match, plant):
    with pytest.raises(ValueError, match=match):
        PoleAvoidanceEnv(plant=plant, **kwargs)
    with pytest.raises(ValueError, match=match):
        PoleAvoidanceVectorEnv(2, plant=plant, **kwargs)


def test_normalized_observation_is_the_standardised_raw_one(plant):
    raw = PoleAvoidanceVectorEnv(3, plant=plant)
    norm = PoleAvoidanceVectorEnv(3, normalize_observation=True, plant=plant)
    a, _ = raw.reset(seed=7)
    b, _ = norm.reset(seed=7)
    np.testing.assert_array_equal(b, POSITIONAL_STANDARDIZATION.apply(a))
    assert norm.single_observation_space.contains(b[0])
    assert np.all(np.abs(b) < 3.0)  # about unit spread (raw: ranges of 50-220 m)
    for _ in range(40):
        a, *_, ia = raw.step(np.zeros((3, 1)))
        b, *_, ib = norm.step(np.zeros((3, 1)))
        np.testing.assert_array_equal(b, POSITIONAL_STANDARDIZATION.apply(a))
        if "final_obs" in ia:
            i = int(np.flatnonzero(ia["_final_obs"])[0])
            np.testing.assert_array_equal(
                ib["final_obs"][i], POSITIONAL_STANDARDIZATION.apply(ia["final_obs"][i])
            )
    single = PoleAvoidanceEnv(normalize_observation=True, plant=plant)
    assert single.observation_space == norm.single_observation_space
    radar = PoleAvoidanceEnv("radar+goal", normalize_observation=True, plant=plant)
    assert radar.observation_space == PoleAvoidanceEnv("radar+goal", plant=plant).observation_space


def test_make_vec_returns_the_native_batch():
    for mode in (None, "vector_entry_point"):
        env = gym.make_vec(
            usvsim.ENV_ID,
            num_envs=5,
            vectorization_mode=mode,
            observation="radar+goal",
            reward_horizon="fixed",
        )
        assert type(env) is PoleAvoidanceVectorEnv
        assert env.num_envs == 5 and env.sim.n_boats == 5
        assert env.sim.observation_kind == "radar+goal"
        assert env.layer.options.reward_horizon == "fixed"
        obs, _ = env.reset(seed=0)
        assert obs["radar"].shape == (5, 1, 50, 119)
    sync = gym.make_vec(usvsim.ENV_ID, num_envs=2, vectorization_mode="sync")
    assert type(sync).__name__ == "SyncVectorEnv"
