"""The open-water training env (``usvsim/OpenWater-v0``): the vector-env contract, autoreset,
seeding, the reward on the scene, and the study's episodes equal to the pole task's env."""

from __future__ import annotations

import math
from dataclasses import replace

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils import seeding
from gymnasium.utils.env_checker import data_equivalence

import usvsim
from baselines.avoid import AvoidHelmsman
from usvsim.common.angles import ssa
from usvsim.evaluation.episodes import validation_episodes
from usvsim.task.observations import POSITIONAL_STANDARDIZATION
from usvsim.task.openwater import OpenWaterScenario, Vessel, draw_open_water, from_pole_episodes
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.openwater_env import (
    OPEN_WATER_FAMILY,
    OpenWaterVectorEnv,
    ScenarioMixture,
    draw_family,
    draw_family_episode,
    goal_approach_family,
    goal_islet_family,
)
from usvsim.task.reward import GaussianReward, GoalAimReward, SafetyMarginReward, SuccessReward
from usvsim.task.vector_env import PoleAvoidanceVectorEnv
from usvsim.vessel.plant import Plant

KINDS = ("positional", "scene", "radar", "radar+goal")


@pytest.fixture(scope="module")
def plant():
    return Plant()


def test_registered_as_a_vector_env(plant):
    env = gym.make_vec(usvsim.OPEN_WATER_ENV_ID, num_envs=3, observation="scene", plant=plant)
    assert isinstance(env, OpenWaterVectorEnv) and env.num_envs == 3
    assert env.single_observation_space.shape == (52,)
    assert env.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP


@pytest.mark.parametrize(
    ("observation", "action"),
    [(k, "gaussian") for k in KINDS] + [("scene", "categorical")],
)
def test_vector_env_contract(observation, action, plant):
    """What gymnasium's env checker asks of an env, per boat of the batch: observations in the
    space after reset and step, typed returns, fresh arrays at every step."""
    n = 3
    env = OpenWaterVectorEnv(n, observation=observation, action=action, plant=plant)
    env.action_space.seed(0)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and isinstance(info, dict)
    previous = obs
    for _ in range(4):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
        assert reward.shape == (n,) and reward.dtype == np.float64 and np.all(reward <= 0)
        assert terminated.dtype == bool and truncated.dtype == bool
        assert terminated.shape == truncated.shape == (n,)
        for key in ("reward_pole", "reward_goal", "distance_to_obstacle_m", "is_success"):
            assert info[key].shape == (n,) and info[f"_{key}"].all()
        np.testing.assert_allclose(reward, info["reward_pole"] + info["reward_goal"])
        parts = (obs, previous) if not isinstance(obs, dict) else (obs["radar"], previous["radar"])
        assert not np.shares_memory(*parts)  # not reused (gymnasium's data-reuse check)
        previous = obs


def test_bad_arguments_are_one_line_errors(plant):
    with pytest.raises(ValueError, match="render_mode must be None"):
        OpenWaterVectorEnv(2, render_mode="rgb_array", plant=plant)
    with pytest.raises(ValueError, match="reward_horizon"):
        OpenWaterVectorEnv(2, reward_horizon="forever", plant=plant)  # type: ignore[arg-type]
    env = OpenWaterVectorEnv(2, plant=plant)
    with pytest.raises(ValueError, match="unknown reset options"):
        env.reset(options={"episode": None})
    with pytest.raises(ValueError, match="one episode per boat"):
        env.reset(options={"episodes": draw_open_water(OpenWaterScenario(), 0, 1)})
    with pytest.raises(ValueError, match="need 2 seeds"):
        env.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="one weight per member"):
        ScenarioMixture((OpenWaterScenario(),), (0.5, 0.5))
    with pytest.raises(ValueError, match="positive sum"):
        ScenarioMixture((OpenWaterScenario(),), (0.0,))


def _rollout(env, seed, steps):
    """[obs0, then per step obs, reward, terminated, truncated, final_obs (0 if none)]; every
    boat turns by the same sequence of actions."""
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for k in range(steps):
        obs, reward, terminated, truncated, info = env.step(
            np.full((env.num_envs, 1), 0.8 * math.sin(0.7 * k), dtype=np.float32)
        )
        out += [obs, reward, terminated, truncated, info["final_obs"] if "final_obs" in info else 0]
    return out


def test_same_seed_same_trajectories_other_seed_others(plant):
    make = lambda: OpenWaterVectorEnv(4, observation="scene", plant=plant)  # noqa: E731
    a, b, c = _rollout(make(), 7, 40), _rollout(make(), 7, 40), _rollout(make(), 8, 40)
    assert data_equivalence(a, b, exact=True)
    assert not np.array_equal(a[0], c[0])
    assert sum(isinstance(x, np.ndarray) and x.dtype == object for x in a) > 0  # autoresets ran


def test_batch_equals_single_boats(plant):
    """Boat i of a batch reset with seed s runs what one boat reset with seed s + i runs."""
    batch = _rollout(OpenWaterVectorEnv(3, observation="positional", plant=plant), 11, 30)
    for i in range(3):
        single = _rollout(OpenWaterVectorEnv(1, observation="positional", plant=plant), 11 + i, 30)
        np.testing.assert_array_equal(batch[0][i], single[0][0])
        for k in range(30):
            obs_b, rew_b, term_b = batch[1 + 5 * k : 4 + 5 * k]
            obs_s, rew_s, term_s = single[1 + 5 * k : 4 + 5 * k]
            np.testing.assert_array_equal(obs_b[i], obs_s[0])
            assert rew_b[i] == rew_s[0] and term_b[i] == term_s[0]


def test_autoreset_same_step_returns_final_obs_and_the_next_episode(plant):
    """A boat that ends an episode reports its final observation in final_obs (the batch's own
    observation at that step) and returns the first observation of its next episode, drawn from
    its own generator."""
    episodes = list(from_pole_episodes(validation_episodes()[:1])) * 2  # ends at the same step
    env = OpenWaterVectorEnv(2, observation="scene", plant=plant)
    ref = OpenWaterBatch(2, observation="scene", plant=plant)
    env.reset(seed=5, options={"episodes": episodes})
    ref.reset(None, episodes)
    straight = np.zeros((2, 1), dtype=np.float32)  # at the pole: both collide
    for _ in range(60):
        obs, _, terminated, truncated, info = env.step(straight)
        expected = ref.step(straight)
        if terminated.any() or truncated.any():
            break
        np.testing.assert_array_equal(obs, expected.observation)
    done = terminated | truncated
    assert done.all() and info["collision"].all() and not info["is_success"].any()
    assert np.array_equal(info["_final_obs"], done)
    for i in range(2):
        np.testing.assert_array_equal(info["final_obs"][i], expected.observation[i])
        final = info["final_info"]
        assert final["collision"][i] and final["_collision"][i] and info["_final_info"][i]
        nxt = draw_family_episode(OPEN_WATER_FAMILY, seeding.np_random(5 + i)[0])
        fresh = OpenWaterBatch(1, observation="scene", plant=plant).reset(None, [nxt])
        np.testing.assert_array_equal(obs[i], fresh[0])
        assert not np.array_equal(obs[i], info["final_obs"][i])


@pytest.mark.parametrize("horizon", ["episode", "fixed"])
def test_study_episodes_equal_the_pole_task_env(horizon, plant):
    """On the study's own episodes the open-water env gives the pole task env's observations,
    rewards and flags, step for step, until each boat's first episode ends."""
    specs = validation_episodes()
    n = len(specs)
    kw = {"observation": "positional", "reward_horizon": horizon, "plant": plant}
    pole = PoleAvoidanceVectorEnv(n, **kw)
    water = OpenWaterVectorEnv(n, **kw)
    a, _ = pole.reset(seed=0, options={"episodes": list(specs)})
    b, _ = water.reset(seed=0, options={"episodes": list(from_pole_episodes(specs))})
    np.testing.assert_array_equal(a, b)
    helm = AvoidHelmsman()
    helm.reset(n)
    straight = np.arange(n) % 3 == 0  # a third run at the pole: collisions too
    running = np.ones(n, dtype=bool)
    ends = set()
    while running.any():
        act = np.where(straight[:, None], 0.0, helm.act(a)).astype(np.float32)
        a, ra, ta, ua, ia = pole.step(act)
        b, rb, tb, ub, ib = water.step(act)
        r = running
        np.testing.assert_array_equal(ra[r], rb[r])
        np.testing.assert_array_equal(ta[r], tb[r])
        np.testing.assert_array_equal(ua[r], ub[r])
        for key in ("reward_pole", "reward_goal", "is_success", "collision", "reached_goal"):
            np.testing.assert_array_equal(ia[key][r], ib[key][r])
        np.testing.assert_array_equal(ia["distance_to_pole_m"][r], ib["distance_to_obstacle_m"][r])
        ended = r & (ta | ua)
        for i in np.flatnonzero(ended):
            np.testing.assert_array_equal(ia["final_obs"][i], ib["final_obs"][i])
            ends.add("goal" if ia["reached_goal"][i] else "collision" if ta[i] else "cut")
        np.testing.assert_array_equal(a[r & ~ended], b[r & ~ended])
        running = r & ~ended
    assert {"goal", "collision"} <= ends


def test_fixed_horizon_counts_each_episodes_own_decisions(plant):
    """An episode with a 300 s limit (150 decisions) that collides at decision t gets
    r · (1 + γ (1 − γ^m) / (1 − γ)) with m = 150 − t; its 150 s neighbour m = 75 − t."""
    gamma = 0.99
    base = list(from_pole_episodes(validation_episodes()[:2]))
    episodes = [replace(base[0], time_limit_s=300.0), base[1]]
    env = OpenWaterVectorEnv(2, reward_horizon="fixed", gamma=gamma, plant=plant)
    env.reset(seed=0, options={"episodes": episodes})
    hits = {}
    for t in range(1, 60):
        _, reward, terminated, _, info = env.step(np.zeros((2, 1), dtype=np.float32))
        plain = info["reward_pole"] + info["reward_goal"]
        for i in np.flatnonzero(terminated):
            if i not in hits:
                hits[i] = (t, reward[i], plain[i])
        if len(hits) == 2:
            break
    for i, limit in ((0, 150), (1, 75)):
        t, r, plain = hits[i]
        m = limit - t
        assert r == pytest.approx(plain * (1 + gamma * (1 - gamma**m) / (1 - gamma)), rel=1e-12)


def test_reward_sees_the_nearest_obstacle_by_pole_equivalent_distance(plant):
    """Islet and vessel: d = min(|p − c| − R + 1 m) over both, at the period's end, from the true
    position; the pole term is the study's Gaussian of it."""
    start = from_pole_episodes(validation_episodes()[:1])[0]
    vessel = Vessel(40.0, -60.0, math.pi / 2, 2.0, 0.01, 5.0)
    ep = replace(start, obstacles=((start.anchor_ne[0], start.anchor_ne[1], 12.0),),
                 vessels=(vessel,))  # fmt: skip
    env = OpenWaterVectorEnv(1, observation="scene", plant=plant)
    env.reset(seed=0, options={"episodes": [ep]})
    seen = []
    for k in range(1, 12):
        _, _, terminated, truncated, info = env.step(np.full((1, 1), 0.3, dtype=np.float32))
        if terminated[0] or truncated[0]:
            break
        p = env.sim.inner.state.x[0, :2]
        chi = vessel.course_rad + vessel.turn_rate_radps * 2.0 * k
        w = vessel.speed_mps / vessel.turn_rate_radps
        v = np.array([vessel.x0_n + w * (math.sin(chi) - math.sin(vessel.course_rad)),
                      vessel.y0_e + w * (math.cos(vessel.course_rad) - math.cos(chi))])  # fmt: skip
        d = min(np.hypot(*(p - start.anchor_ne)) - 12.0 + 1.0, np.hypot(*(p - v)) - 5.0 + 1.0)
        assert info["distance_to_obstacle_m"][0] == pytest.approx(d, abs=1e-9)
        pole = GaussianReward()(np.array([d]), np.array([1.0])).pole[0]
        assert info["reward_pole"][0] == pytest.approx(pole, abs=1e-12)
        seen.append(d)
    assert len(seen) > 5 and min(seen) < 30.0  # the pole term was not negligible


def test_safety_reward_pays_each_period_that_comes_inside_the_safety_distance(plant):
    """Straight at the study's pole: the safety term is the margin ramp of the period's nearest
    distance over all its plant steps (at most the end step's), the reward grows by exactly it,
    and it is 0 far out and -w inside the safety distance."""
    ep = from_pole_episodes(validation_episodes()[:1])[0]
    safety = SafetyMarginReward(weight=2.0, margin_m=5.0)
    plain = OpenWaterVectorEnv(1, observation="scene", plant=plant)
    paid = OpenWaterVectorEnv(1, observation="scene", plant=plant, safety_reward=safety)
    d_safe = paid.sim.base.safety_distance_m
    for env in (plain, paid):
        env.reset(seed=0, options={"episodes": [ep]})
    terms, last_min = [], math.inf
    for _ in range(60):
        action = np.zeros((1, 1), dtype=np.float32)
        _, r0, *_ = plain.step(action)
        _, r1, terminated, truncated, info = paid.step(action)
        s = info["reward_safety"][0]
        assert r1[0] == pytest.approx(r0[0] + s, abs=1e-12)
        at_end = safety(info["distance_to_obstacle_m"], d_safe)[0]
        assert s <= at_end + 1e-12  # the period's nearest is no farther than its end
        if info["min_distance_m"][0] < last_min:  # this period set the episode's minimum
            assert s == pytest.approx(safety(info["min_distance_m"], d_safe)[0], abs=1e-12)
        last_min = float(info["min_distance_m"][0])
        terms.append(s)
        if terminated[0] or truncated[0]:
            break
    assert terms[0] == 0.0 and min(terms) == -2.0


def test_success_reward_is_paid_once_at_the_successful_end_after_the_horizon_scaling(plant):
    """The study's episode without its pole, sailed straight: the boat reaches the goal. Under
    the fixed horizon the paid env's reward equals the plain env's at every decision but the
    last, where it is the plain (horizon-scaled) reward plus exactly w."""
    ep = replace(from_pole_episodes(validation_episodes()[:1])[0], obstacles=())
    w = 2.0
    kwargs = {"observation": "scene", "plant": plant, "reward_horizon": "fixed"}
    plain = OpenWaterVectorEnv(1, **kwargs)
    paid = OpenWaterVectorEnv(1, success_reward=SuccessReward(w), **kwargs)
    for env in (plain, paid):
        env.reset(seed=0, options={"episodes": [ep]})
    action = np.zeros((1, 1), dtype=np.float32)
    for _ in range(200):
        _, r0, done0, cut0, _ = plain.step(action)
        _, r1, done1, cut1, info = paid.step(action)
        assert (done1[0], cut1[0]) == (done0[0], cut0[0])
        if done1[0] or cut1[0]:
            break
        assert r1[0] == r0[0] and info["reward_success"][0] == 0.0
    assert done1[0] and info["is_success"][0]
    assert info["reward_success"][0] == w and r1[0] == pytest.approx(r0[0] + w, abs=1e-12)
    assert r0[0] < 0.0  # the plain terminal reward, scaled by the decisions left, stays < 0


def test_aim_reward_charges_the_goal_off_the_bow_not_ahead(plant):
    """Two boats start alike (the study's start without its pole, heading at the anchor), one
    with the goal 60 m dead ahead, one with it 60 m abeam to starboard. After a straight
    decision the first is charged nearly nothing, the second about w (abeam, 1 - cos 90° = 1);
    the paid env's reward is the plain env's plus exactly ``info["reward_aim"]``."""
    base = replace(from_pole_episodes(validation_episodes()[:1])[0], obstacles=())
    base = replace(base, start=replace(base.start, heading_offset_rad=0.0))
    psi0 = base.start.start_bearing_rad + math.pi  # the start heading: at the anchor
    start = base.start_ne

    def goal(off_rad: float) -> tuple[float, float]:
        g = start + 60.0 * np.array([math.cos(psi0 + off_rad), math.sin(psi0 + off_rad)])
        return float(g[0]), float(g[1])

    episodes = [replace(base, goal_ne=goal(0.0)), replace(base, goal_ne=goal(math.pi / 2))]
    kwargs = {"observation": "scene", "plant": plant, "reward_horizon": "fixed"}
    plain = OpenWaterVectorEnv(2, **kwargs)
    paid = OpenWaterVectorEnv(2, aim_reward=GoalAimReward(weight=1.0, range_m=100.0), **kwargs)
    for env in (plain, paid):
        env.reset(seed=0, options={"episodes": episodes})
    action = np.zeros((2, 1), dtype=np.float32)
    _, r0, *_ = plain.step(action)
    _, r1, *_, info = paid.step(action)
    aim = info["reward_aim"]
    assert -0.01 < aim[0] <= 0.0  # ahead: a few degrees of drift at most
    assert -1.25 < aim[1] < -0.95  # abeam, 6 m on: the goal a little abaft the beam
    np.testing.assert_allclose(r1, r0 + aim, rtol=0, atol=1e-12)


def test_aim_reward_is_zero_beyond_its_range(plant):
    """The study's episode without its pole starts 100+ m from its goal: no charge there."""
    ep = replace(from_pole_episodes(validation_episodes()[:1])[0], obstacles=())
    env = OpenWaterVectorEnv(1, observation="scene", plant=plant,
                             aim_reward=GoalAimReward(range_m=50.0))  # fmt: skip
    env.reset(seed=0, options={"episodes": [ep]})
    _, _, _, _, info = env.step(np.zeros((1, 1), dtype=np.float32))
    assert info["distance_to_goal_m"][0] > 50.0 and info["reward_aim"][0] == 0.0


def test_normalized_positional_observation(plant):
    raw = OpenWaterVectorEnv(2, plant=plant)
    norm = OpenWaterVectorEnv(2, normalize_observation=True, plant=plant)
    a, _ = raw.reset(seed=3)
    b, _ = norm.reset(seed=3)
    np.testing.assert_array_equal(POSITIONAL_STANDARDIZATION.apply(a), b)
    assert norm.single_observation_space.contains(b[0])


def test_family_draws_are_seeded_and_mix_the_members():
    assert draw_family(OPEN_WATER_FAMILY, 3, 20) == draw_family(OPEN_WATER_FAMILY, 3, 20)
    episodes = draw_family(OPEN_WATER_FAMILY, 0, 600)
    traffic = np.mean([not e.obstacles and len(e.vessels) >= 1 for e in episodes])
    islets = np.mean([bool(e.obstacles) and e.obstacles[0][2] >= 8.0 for e in episodes])
    study = np.mean([e.disturbance is not None and e.disturbance.speed_mps == 3.0
                     and e.disturbance.current_speed_mps == 0.0 for e in episodes])  # fmt: skip
    p = dict(zip(OPEN_WATER_FAMILY.names, OPEN_WATER_FAMILY.probabilities, strict=True))
    assert abs(traffic - p["traffic"]) < 0.05
    assert abs(islets - p["islets"]) < 0.05
    assert abs(study - p["study"]) < 0.05  # only the study member runs calm at 3 m/s exactly
    speeds = [e.disturbance.speed_mps for e in episodes if e.disturbance is not None]
    assert 1.5 <= min(speeds) < 1.8 and 4.7 < max(speeds) <= 5.0


def test_perf_figure_is_a_rate():
    from usvsim.evaluation.perf import open_water_env_throughput

    rate = open_water_env_throughput("scene", 4, seconds=0.05)
    assert math.isfinite(rate) and rate > 0


def _start_geometry(episodes, plant):
    """The boats' true start poses η (N, 3), their goals' distances (m) and bearings off the
    heading (rad, absolute) once the episodes are started."""
    env = OpenWaterVectorEnv(len(episodes), observation="scene", plant=plant)
    env.reset(seed=0, options={"episodes": list(episodes)})
    eta, goal = env.sim.inner.state.eta, env.sim.goal_ne
    distance = np.hypot(goal[:, 0] - eta[:, 0], goal[:, 1] - eta[:, 1])
    off = np.abs(ssa(np.arctan2(goal[:, 1] - eta[:, 1], goal[:, 0] - eta[:, 0]) - eta[:, 2]))
    return eta, distance, off


def test_goal_approach_episodes_start_near_the_goal_pointed_past_it(plant):
    """The goal-approach member: no obstacle or vessel, the goal 14-40 m from the boat at its
    start and up to 115° off its heading, from ahead to behind the beam."""
    episodes = draw_family(goal_approach_family(), 5, 200)
    assert all(not e.obstacles and not e.vessels for e in episodes)
    _, distance, off = _start_geometry(episodes, plant)
    assert distance.min() >= 14.0 - 1e-9 and distance.max() <= 40.0 + 1e-9
    assert off.max() <= math.radians(115.0) + 1e-9
    assert np.mean(off > math.radians(60.0)) > 0.3 and np.mean(off < math.radians(30.0)) > 0.1


def test_goal_islet_episodes_end_at_a_goal_beside_islets(plant):
    """The goal-islet member: no vessel, the goal 40-100 m from the boat at its start and up to
    60° off its heading, one or two islets (8-25 m) with edges at least 25 m from start and
    goal, most of them near the goal's end of the route (within 40 m of the goal's circle)."""
    episodes = draw_family(goal_islet_family(), 5, 200)
    assert all(not e.vessels and 1 <= len(e.obstacles) <= 2 for e in episodes)
    eta, distance, off = _start_geometry(episodes, plant)
    assert distance.min() >= 40.0 - 1e-9 and distance.max() <= 100.0 + 1e-9
    assert off.max() <= math.radians(60.0) + 1e-9 and np.mean(off > math.radians(30.0)) > 0.3
    edges = []
    for e, s in zip(episodes, eta[:, :2], strict=True):
        for x, y, r in e.obstacles:
            assert 8.0 <= r <= 25.0
            assert math.hypot(x - e.goal_ne[0], y - e.goal_ne[1]) - r >= 25.0
            assert math.hypot(x - s[0], y - s[1]) - r >= 25.0 - 1e-6
            edges.append(math.hypot(x - e.goal_ne[0], y - e.goal_ne[1]) - r)
    assert np.mean(np.array(edges) < 50.0) > 0.5


def test_unsafe_ends_terminates_the_first_period_inside_the_safety_distance(plant):
    """Straight at the study's pole under the fixed horizon: with ``unsafe_ends`` the episode is
    the plain env's, reward for reward, until the first decision period whose nearest distance
    is inside the safety distance; that one terminates (``unsafe_end``), its reward the plain
    step's reward scaled by the decisions left, while the plain env sails on."""
    ep = from_pole_episodes(validation_episodes()[:1])[0]
    kwargs = {"observation": "scene", "plant": plant, "reward_horizon": "fixed"}
    plain = OpenWaterVectorEnv(1, **kwargs)
    strict = OpenWaterVectorEnv(1, unsafe_ends=True, **kwargs)
    d_safe = strict.sim.base.safety_distance_m
    for env in (plain, strict):
        env.reset(seed=0, options={"episodes": [ep]})
    action = np.zeros((1, 1), dtype=np.float32)
    taken = 0
    while taken < 60:
        _, r0, done0, cut0, _ = plain.step(action)
        _, r1, done1, cut1, info1 = strict.step(action)
        taken += 1
        inside = bool(info1["min_distance_m"][0] < d_safe)
        assert info1["unsafe_end"][0] == (inside and not done0[0])
        if inside:
            break
        assert (r1[0], done1[0], cut1[0]) == (r0[0], done0[0], cut0[0])
    assert taken > 3 and inside and not done0[0] and done1[0] and not cut1[0]
    left = plain.sim.base.max_decisions - taken
    assert r1[0] == pytest.approx(r0[0] * (1 + 0.99 * (1 - 0.99**left) / 0.01), rel=1e-12)
    assert r1[0] < 20 * r0[0] < 0.0  # the decisions left weigh on the end
    assert info1["final_info"]["unsafe_end"][0] and not info1["final_info"]["is_success"][0]
