"""baselines: the landmark pose, the collision-cone rule, both helmsmen on the validation set."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines import AvoidHelmsman, CollisionCone, LOSHelmsman, cone_heading_change, landmark_pose
from usvsim.evaluation.episodes import evaluate, validation_episodes
from usvsim.task.observations import build_observation


def test_landmark_pose_is_the_navigation_pose_up_to_a_rigid_motion() -> None:
    rng = np.random.default_rng(4)
    n = 50
    pole = np.tile(rng.uniform(-100, 100, 2), (n, 1))
    goal = np.tile(rng.uniform(-100, 100, 2), (n, 1))
    pos, psi = rng.uniform(-200, 200, (n, 2)), rng.uniform(-math.pi, math.pi, n)
    obs = build_observation("positional", pos, psi, pole, goal, 1.0)
    assert isinstance(obs, np.ndarray)
    pose = landmark_pose(obs)
    # distances between boats and heading differences are frame-independent
    d_true = np.hypot(*(pos[:, None] - pos[None]).transpose(2, 0, 1))
    d_est = np.hypot(*(pose.pos_m[:, None] - pose.pos_m[None]).transpose(2, 0, 1))
    np.testing.assert_allclose(d_est, d_true, atol=2e-3)
    dpsi_true = np.angle(np.exp(1j * (psi[:, None] - psi[None])))
    dpsi_est = np.angle(np.exp(1j * (pose.psi_rad[:, None] - pose.psi_rad[None])))
    np.testing.assert_allclose(dpsi_est, dpsi_true, atol=1e-5)
    np.testing.assert_allclose(pose.pair_distance_m, np.hypot(*(pole - goal)[0]), rtol=1e-5)
    goal_range = obs[:, 2].astype(np.float64)
    np.testing.assert_allclose(np.hypot(*pose.pos_m.T), goal_range, rtol=1e-6)  # goal at origin


def test_cone_deflects_a_course_at_a_pole_dead_ahead_to_starboard() -> None:
    cone = CollisionCone(safety_radius_m=20.0, margin_rad=math.radians(4.0))
    dpsi, side, blocked = cone_heading_change(
        cone, np.zeros(1), np.array([50.0]), np.zeros(1), np.zeros(1, dtype=np.int64)
    )
    assert bool(blocked[0]) and int(side[0]) == 1
    assert dpsi[0] == pytest.approx(math.asin(20.0 / 50.0) + math.radians(4.0))


def test_cone_passes_a_pole_to_starboard_on_the_port_side() -> None:
    cone = CollisionCone(safety_radius_m=20.0, margin_rad=0.0)
    phi = math.radians(10.0)
    dpsi, side, _ = cone_heading_change(
        cone, np.zeros(1), np.array([40.0]), np.array([phi]), np.zeros(1, dtype=np.int64)
    )
    assert int(side[0]) == -1 and dpsi[0] == pytest.approx(phi - math.radians(30.0))


def test_cone_leaves_a_clear_course_alone_and_releases_the_side() -> None:
    cone = CollisionCone(safety_radius_m=20.0, margin_rad=0.0)
    desired = np.array([math.radians(40.0)])  # outside the 30° cone of a pole 40 m ahead
    dpsi, side, blocked = cone_heading_change(
        cone, desired, np.array([40.0]), np.zeros(1), np.array([-1])
    )
    assert not blocked[0] and int(side[0]) == 0 and dpsi[0] == pytest.approx(desired[0])


def test_cone_keeps_its_side_while_the_pole_blocks() -> None:
    cone = CollisionCone(safety_radius_m=20.0, margin_rad=0.0)
    # the pole drifted 5° to starboard, but the boat already chose to pass it to port-side (+1)
    phi = math.radians(5.0)
    dpsi, side, _ = cone_heading_change(
        cone, np.zeros(1), np.array([40.0]), np.array([phi]), np.array([1])
    )
    assert int(side[0]) == 1 and dpsi[0] == pytest.approx(phi + math.radians(30.0))


def test_cone_ignores_a_pole_abaft_the_beam() -> None:
    cone = CollisionCone()
    _, _, blocked = cone_heading_change(
        cone, np.array([math.pi]), np.array([15.0]), np.array([math.pi]), np.zeros(1, np.int64)
    )
    assert not blocked[0]


def test_los_actions_are_clipped_gaussian_actions() -> None:
    h = LOSHelmsman()
    h.reset(3)
    # goal 90° to starboard, 120° to port and dead ahead; pole somewhere else
    obs = np.array(
        [[60, 0.3, 200, math.pi / 2], [60, 0.3, 200, -2.1], [60, 0.3, 200, 0.0]], np.float32
    )
    a = h.act(obs)
    assert a.shape == (3, 1) and a.dtype == np.float32
    np.testing.assert_allclose(a[:, 0], [1.0, -1.0, 0.0], atol=1e-6)


def test_los_lays_a_new_path_when_the_goal_changes() -> None:
    h = LOSHelmsman()
    h.reset(1)
    h.act(np.array([[60, 0.0, 200, 0.0]], np.float32))
    h.act(np.array([[54, 0.0, 194, 0.0]], np.float32))
    assert h.last_output is not None and h.last_output.along_track_m[0] == pytest.approx(6.0)
    h.act(np.array([[50, 0.0, 150, 1.0]], np.float32))  # new goal: a new path from here
    assert h.last_output.along_track_m[0] == pytest.approx(0.0, abs=1e-3)
    assert h.last_output.cross_track_m[0] == pytest.approx(0.0, abs=1e-3)


def test_los_hits_the_pole_in_most_validation_episodes() -> None:
    records = evaluate(LOSHelmsman(), validation_episodes())
    assert sum(r.success for r in records) == 0
    assert sum(r.collision for r in records) >= 13
    assert max(r.min_pole_distance_m for r in records) < 3.0


def test_los_avoid_succeeds_on_every_validation_episode() -> None:
    records = evaluate(AvoidHelmsman(), validation_episodes())
    assert all(r.success for r in records)
    assert min(r.min_pole_distance_m for r in records) >= 15.0  # measured 17.5 m
