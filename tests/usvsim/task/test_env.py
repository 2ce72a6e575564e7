"""Environments: Gymnasium contract, actions, episode ends, determinism, batch == singles."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import usvsim
from usvsim.task.batch import ACTION_KINDS, heading_change_rad, parse_action_kind, within_radius
from usvsim.task.env import PoleAvoidanceEnv
from usvsim.task.observations import OBSERVATION_KINDS, parse_observation_kind, relative_polar
from usvsim.task.scenario import EpisodeSpec, Scenario
from usvsim.task.vector_env import PoleAvoidanceVectorEnv
from usvsim.vessel.plant import Plant

MAX = math.radians(30.0)


@pytest.fixture(scope="module")
def plant():
    return Plant()


@pytest.mark.parametrize("observation", ["positional", "radar", "radar+goal", "scene"])
@pytest.mark.parametrize("action", ["gaussian", "categorical"])
def test_check_env_passes(observation, action):
    env = gym.make(usvsim.ENV_ID, observation=observation, action=action)
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)


def test_categorical_mapping():
    dpsi = heading_change_rad("categorical", np.array([0, 1, 20, 39, 40]), 5, MAX)
    np.testing.assert_allclose(np.degrees(dpsi), [-30.0, -28.5, 0.0, 28.5, 30.0], atol=1e-12)


def test_gaussian_scaling_is_linear():
    dpsi = heading_change_rad("gaussian", np.array([[-1.0], [-0.5], [0.0], [1.0]]), 4, MAX)
    np.testing.assert_allclose(np.degrees(dpsi), [-30.0, -15.0, 0.0, 30.0], atol=1e-12)


@pytest.mark.parametrize(
    ("action", "value", "match"),
    [
        ("gaussian", np.array([np.nan], dtype=np.float32), "NaN"),
        ("gaussian", np.array([1.5], dtype=np.float32), r"\[-1, 1\]"),
        ("gaussian", np.array([0.1, 0.2], dtype=np.float32), "shape"),
        ("gaussian", np.float32(0.1), "shape"),
        ("gaussian", np.array(["a"]), "numbers"),
        ("categorical", 41, "0..40"),
        ("categorical", -1, "0..40"),
        ("categorical", 2.0, "integers"),
        ("categorical", np.array([3]), "shape"),
    ],
)
def test_bad_actions_raise_clear_errors(action, value, match, plant):
    env = PoleAvoidanceEnv(action=action, plant=plant)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(value)


def test_reset_places_the_boat_as_specified(plant):
    env = PoleAvoidanceEnv(plant=plant)
    spec = EpisodeSpec(pole_index=0, start_distance_m=70.0, start_bearing_rad=math.pi)
    obs, info = env.reset(options={"episode": spec})
    np.testing.assert_allclose(env.sim.state.eta[0], [-70.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(info["goal_ne"], [150.0, 0.0], atol=1e-9)
    # the observation is the navigation estimate: GNSS-noisy, not the true geometry
    assert abs(obs[0] - 70.0) < 6.0 and abs(obs[2] - 220.0) < 6.0 and obs[0] != 70.0
    assert abs(obs[1]) < 0.15 and abs(obs[3]) < 0.15


def test_observation_uses_the_estimate_not_the_truth(plant):
    env = PoleAvoidanceEnv(plant=plant)
    env.reset(seed=3)
    obs, *_ = env.step(np.array([0.5], dtype=np.float32))
    est_pos, est_psi = env.sim.estimate
    r, b = relative_polar(est_pos, est_psi, env.sim.pole_ne)
    np.testing.assert_allclose(obs[:2], [r[0], b[0]], rtol=1e-6, atol=1e-6)
    true = env.sim.state.eta
    r_true, _ = relative_polar(true[:, :2], true[:, 2], env.sim.pole_ne)
    assert obs[0] != pytest.approx(r_true[0], abs=1e-3)


def test_straight_ahead_collides_and_terminates(plant):
    env = PoleAvoidanceEnv(plant=plant)
    env.reset(options={"episode": EpisodeSpec(0, 60.0, 1.0, 0.0, 4)})
    terminated = truncated = False
    while not (terminated or truncated):
        _, reward, terminated, truncated, info = env.step(np.zeros(1, np.float32))
    assert terminated and not truncated and info["collision"] and not info["is_success"]
    assert info["min_distance_to_pole_m"] < 1.0 + plant.vessel.half_beam_m
    # 60 m - 2.75 m at 3 m/s ≈ 19.1 s: the 10th decision
    assert info["time_s"] == 20.0
    assert reward == pytest.approx(info["reward_pole"] + info["reward_goal"], abs=1e-12)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(1, np.float32))


def test_time_limit_truncates(plant):
    env = PoleAvoidanceEnv(plant=plant, scenario=Scenario(time_limit_s=10.0))
    env.reset(seed=0)
    flags = [env.step(np.zeros(1, np.float32))[2:4] for _ in range(5)]
    assert flags[:4] == [(False, False)] * 4 and flags[4] == (False, True)


def test_leaving_the_area_truncates(plant):
    env = PoleAvoidanceEnv(plant=plant, scenario=Scenario(area_radius_m=110.0))
    env.reset(options={"episode": EpisodeSpec(0, 100.0, 0.0)})
    for _ in range(40):
        _, _, terminated, truncated, info = env.step(np.ones(1, np.float32))
        if truncated or terminated:
            break
    assert truncated and not terminated and info["out_of_area"] and not info["time_limit"]


def test_goal_checked_at_every_plant_step(plant):
    # a 215 m goal radius is reached after 5 m (1.7 s), inside the first decision period
    env = PoleAvoidanceEnv(plant=plant, scenario=Scenario(goal_radius_m=215.0))
    env.reset(options={"episode": EpisodeSpec(0, 80.0, 0.0)})
    _, _, terminated, truncated, info = env.step(np.zeros(1, np.float32))
    assert terminated and not truncated and info["reached_goal"] and info["is_success"]
    assert info["time_to_goal_s"] == pytest.approx(1.7, abs=0.15)


def test_custom_reward_is_pluggable(plant):
    from usvsim.task.reward import RewardTerms

    def reward(d_pole, d_goal):
        return RewardTerms(pole=-1.0 / d_pole, goal=-d_goal)

    env = PoleAvoidanceEnv(plant=plant, reward=reward)
    env.reset(seed=0)
    _, r, _, _, info = env.step(np.zeros(1, np.float32))
    assert info["reward_pole"] == pytest.approx(-1.0 / info["distance_to_pole_m"])
    assert r == pytest.approx(-1.0 / info["distance_to_pole_m"] - info["distance_to_goal_m"])


def _rollout(env, seed, actions):
    out = [env.reset(seed=seed)[0]]
    for a in actions:
        obs, r, te, tr, info = env.step(a)
        out.append((obs, r, te, tr, info))
        if te or tr:
            out.append(env.reset()[0])
    return out


def test_same_seed_same_episode(plant):
    actions = np.random.default_rng(1).uniform(-1, 1, (30, 1)).astype(np.float32)
    a = _rollout(PoleAvoidanceEnv(observation="radar+goal", plant=plant), 7, actions)
    b = _rollout(PoleAvoidanceEnv(observation="radar+goal", plant=plant), 7, actions)
    assert gym.utils.env_checker.data_equivalence(a, b, exact=True)
    c = _rollout(PoleAvoidanceEnv(observation="radar+goal", plant=plant), 8, actions)
    assert not gym.utils.env_checker.data_equivalence(a[0], c[0])


def test_batched_env_equals_n_single_envs(plant):
    n, steps, seed = 4, 120, 10
    actions = np.random.default_rng(2).integers(0, 41, (steps, n))
    vec = PoleAvoidanceVectorEnv(n, action="categorical", plant=plant)
    singles = [PoleAvoidanceEnv(action="categorical", plant=plant) for _ in range(n)]
    obs_v, _ = vec.reset(seed=seed)
    obs_s = np.stack([env.reset(seed=seed + i)[0] for i, env in enumerate(singles)])
    np.testing.assert_array_equal(obs_v, obs_s)
    n_done = 0
    for k in range(steps):
        obs_v, r_v, te_v, tr_v, info_v = vec.step(actions[k])
        for i, env in enumerate(singles):
            obs, r, te, tr, info = env.step(actions[k, i])
            assert (r, te, tr) == (r_v[i], te_v[i], tr_v[i])
            assert info["min_distance_to_pole_m"] == info_v["min_distance_to_pole_m"][i]
            if te or tr:
                n_done += 1
                np.testing.assert_array_equal(info_v["final_obs"][i], obs)
                assert info_v["final_info"]["collision"][i] == info["collision"]
                obs, _ = env.reset()
            np.testing.assert_array_equal(obs_v[i], obs)
    assert n_done >= n  # autoresets were exercised


def test_vector_env_spaces_and_episode_options(plant):
    vec = PoleAvoidanceVectorEnv(3, observation="radar+goal", plant=plant)
    specs = [EpisodeSpec(i % 2, 50.0 + 20 * i, 0.5 * i) for i in range(3)]
    obs, info = vec.reset(options={"episodes": specs})
    assert vec.observation_space.contains(obs)
    assert obs["radar"].shape == (3, 1, 50, 119) and obs["goal"].shape == (3, 2)
    np.testing.assert_allclose(
        np.linalg.norm(info["goal_ne"] - vec.sim.pole_ne, axis=1), [170.0, 150.0, 130.0]
    )
    assert vec.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    with pytest.raises(ValueError, match="unknown reset options"):
        vec.reset(options={"episode": specs[0]})


def test_batch_state_is_a_copy_of_the_true_state(plant):
    env = PoleAvoidanceVectorEnv(2, plant=plant)
    env.reset(seed=4)
    state = env.sim.state
    state.x[:] = np.nan
    assert np.all(np.isfinite(env.sim.state.x))
    env.step(np.zeros((2, 1), dtype=np.float32))
    assert np.all(np.isfinite(env.sim.state.x))


def test_kinds_parse_only_known_names():
    assert [parse_observation_kind(k) for k in OBSERVATION_KINDS] == [
        "positional",
        "radar",
        "radar+goal",
        "scene",
        "radar+nav",
    ]
    assert [parse_action_kind(k) for k in ACTION_KINDS] == ["gaussian", "categorical"]
    with pytest.raises(ValueError, match="observation must be one of"):
        parse_observation_kind("radar+gaol")
    with pytest.raises(ValueError, match="action must be one of"):
        parse_action_kind("gausian")


def test_goal_test_equals_hypot_at_the_boundary():
    r = 10.0
    edge = np.array([6.0, 8.0, 10.0, 0.0, 7.0710678118654755, np.nextafter(10.0, 11.0)])
    dx = np.concatenate([edge, -edge, [np.nan, np.inf, 1e300, 3.0]])
    dy = np.concatenate([edge[::-1], edge, [0.0, 0.0, 1e300, np.nan]])
    rng = np.random.default_rng(0)
    angle = rng.uniform(0, 2 * np.pi, 20_000)
    radius = r * (1.0 + rng.choice([-1e-16, 0.0, 1e-16, 1e-3], angle.size))
    dx = np.concatenate([dx, radius * np.cos(angle)])[None, :]
    dy = np.concatenate([dy, radius * np.sin(angle)])[None, :]
    expected = np.hypot(dx, dy) <= r
    np.testing.assert_array_equal(within_radius(dx, dy, r), expected)
    assert 0 < expected.sum() < expected.size
