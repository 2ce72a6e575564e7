"""usvsim.task.waypoints: course geometry, goal switching in order, and the baselines on courses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines import AvoidHelmsman
from usvsim.evaluation.waypoints import WaypointRecord, evaluate_waypoints
from usvsim.helm.protocol import StraightAheadHelmsman
from usvsim.task.waypoints import WaypointScenario, draw_course, heldout_courses, validation_courses


@pytest.fixture(scope="module")
def avoid_records() -> list[WaypointRecord]:
    return evaluate_waypoints(AvoidHelmsman(), validation_courses())


def test_courses_put_one_pole_on_each_leg_with_clearance() -> None:
    ws = WaypointScenario()
    for c in heldout_courses(ws, n=50):
        w, p = c.waypoints_ne, c.poles_ne
        assert w.shape == (ws.n_legs + 1, 2) and p.shape == (ws.n_legs, 2)
        for k in range(ws.n_legs):
            u = (w[k + 1] - w[k]) / np.hypot(*(w[k + 1] - w[k]))
            rel = p[k] - w[k]
            along, across = rel @ u, rel @ np.array([-u[1], u[0]])
            length = np.hypot(*(w[k + 1] - w[k]))
            assert ws.pole_fraction_range[0] * length - 1e-9 <= along
            assert along <= ws.pole_fraction_range[1] * length + 1e-9
            assert abs(across) <= max(abs(x) for x in ws.pole_offset_range_m) + 1e-9
        d_pp = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1))
        assert np.min(d_pp[~np.eye(len(p), dtype=bool)]) >= ws.clearance_m


def test_course_draws_are_deterministic() -> None:
    a = draw_course(np.random.default_rng(7), WaypointScenario())
    b = draw_course(np.random.default_rng(7), WaypointScenario())
    np.testing.assert_array_equal(a.waypoints_ne, b.waypoints_ne)
    assert a.noise_seed == b.noise_seed


def test_goals_switch_in_order_when_each_waypoint_is_reached(
    avoid_records: list[WaypointRecord],
) -> None:
    period, dt = 2.0, 0.1
    for r in avoid_records:
        k = len(r.course.poles_ne)
        g = r.goal_index
        assert g[0] == 1 and g[-1] == k
        assert set(np.diff(g).tolist()) <= {0, 1}  # never skips, never goes back
        assert np.all(np.diff(r.reach_time_s) > 0)
        for wp in range(1, k):
            first = int(np.argmax(g == wp + 1))  # first decision with the next goal
            t = r.reach_time_s[wp - 1]
            assert (first - 1) * period < t <= first * period + 1e-9
            step = round(t / dt)
            assert np.hypot(*(r.trajectory[step, :2] - r.course.waypoints_ne[wp])) <= 10.0
            assert np.hypot(*(r.trajectory[step - 1, :2] - r.course.waypoints_ne[wp])) > 10.0


def test_los_avoid_completes_every_validation_course(avoid_records: list[WaypointRecord]) -> None:
    assert all(r.success and r.waypoints_reached == 3 for r in avoid_records)
    assert min(r.min_pole_distance_m for r in avoid_records) >= 10.0


def test_min_pole_distance_covers_every_pole(avoid_records: list[WaypointRecord]) -> None:
    for r in avoid_records[:5]:
        rel = r.trajectory[:, None, :2] - r.course.poles_ne[None]
        assert r.min_pole_distance_m == pytest.approx(np.hypot(*rel.transpose(2, 0, 1)).min())


def test_a_boat_that_never_turns_hits_the_first_pole_and_never_switches() -> None:
    records = evaluate_waypoints(StraightAheadHelmsman(), validation_courses(n=4))
    for r in records:
        assert r.collision and not r.success and r.outcome == "collision"
        assert set(r.goal_index.tolist()) == {1} and r.waypoints_reached == 0
        assert math.isnan(r.time_to_goal_s)
