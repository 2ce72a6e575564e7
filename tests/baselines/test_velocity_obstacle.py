"""The ``vo`` helmsman: velocity obstacles with COLREG on top of LOS to the goal (issue 16)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from baselines.avoid import AvoidHelmsman
from baselines.velocity_obstacle import VOConfig, VOHelmsman, vo_course
from usvsim.evaluation.episodes import evaluate, heldout_episodes
from usvsim.evaluation.stress import STRESS_SETS, evaluate_set, stress_episodes
from usvsim.task.observations import SCENE_FEATURES, SCENE_K

DEG = math.pi / 180


def _obs(goal_bearing=0.0, own=(3.0, 0.0), obstacles=()):
    """One scene observation: goal 200 m away; obstacles (r, φ, R, v_N-like rel vx, vy)."""
    o = np.zeros((1, 4 + SCENE_FEATURES * SCENE_K), dtype=np.float32)
    o[0, :4] = (200.0, goal_bearing, *own)
    for k, (r, phi, radius, vx, vy) in enumerate(obstacles):
        o[0, 4 + 6 * k : 10 + 6 * k] = (r, phi, radius, vx, vy, 1.0)
    return o


def _act(obs):
    h = VOHelmsman()
    h.reset(1)
    return float(h.act(obs)[0, 0]) * 30.0  # degrees


def test_open_water_steers_at_the_goal():
    assert _act(_obs(goal_bearing=10 * DEG)) == pytest.approx(10.0, abs=1.6)  # 3° candidates
    assert _act(_obs(goal_bearing=90 * DEG)) == pytest.approx(30.0)  # clipped to the bound


def test_crab_angle_is_compensated():
    # a current sets the boat 0.6 m/s to starboard: course over ground 11° right of the heading;
    # to make good the goal dead ahead the heading turns ~11° to port
    assert _act(_obs(own=(3.0, 0.6))) == pytest.approx(-math.degrees(math.atan2(0.6, 3.0)), abs=1.6)


def test_pole_dead_ahead_is_passed_to_starboard_at_the_cone_edge():
    course, avoiding = vo_course(
        VOConfig(), _obs(obstacles=[(60.0, 0.0, 1.0, -3.0, 0.0)]), np.full(1, np.nan)
    )
    assert avoiding[0]
    edge = math.degrees(math.asin(18.0 / 60.0))  # R_safe = 1 + 17 m
    assert edge < math.degrees(course[0]) < edge + 4.0


def test_extra_margin_widens_that_boats_pass_only():
    obs = np.repeat(_obs(obstacles=[(60.0, 0.0, 1.0, -3.0, 0.0)]), 2, axis=0)
    course, _ = vo_course(VOConfig(), obs, np.full(2, np.nan), np.array([0.0, 6.0]))
    assert math.degrees(course[0]) < math.degrees(math.asin(18.0 / 60.0)) + 4.0
    assert math.degrees(course[1]) > math.degrees(math.asin(24.0 / 60.0))  # R_safe = 1 + 23 m


def test_extra_margin_needs_one_value_per_boat():
    obs = np.repeat(_obs(), 2, axis=0)
    with pytest.raises(ValueError, match=r"extra_margin_m must have shape \(2,\)"):
        vo_course(VOConfig(), obs, np.full(2, np.nan), np.array([1.0, 2.0, 3.0]))


def test_graded_cone_turns_away_where_every_course_is_blocked():
    # a pole 15.5 m ahead, 2° to port: every course's predicted turn comes within its margin.
    # The yes/no cone, all candidates blocked alike, steers for the goal past the pole's edge;
    # graded by how far each falls short, it turns away hard to starboard
    obs = _obs(obstacles=[(15.5, -2 * DEG, 1.0, -3.0, 0.0)])
    yes_no, _ = vo_course(VOConfig(), obs, np.full(1, np.nan))
    graded, _ = vo_course(VOConfig(w_shortfall=5.0), obs, np.full(1, np.nan))
    assert abs(math.degrees(yes_no[0])) < 10.0
    assert math.degrees(graded[0]) > 40.0


@pytest.mark.parametrize("bearing_deg", [-3.0, -1.0, 1.0, 3.0])
def test_starboard_habit_passes_a_pole_near_dead_ahead_to_starboard(bearing_deg):
    obs = _obs(obstacles=[(60.0, bearing_deg * DEG, 1.0, -3.0, 0.0)])
    either, _ = vo_course(VOConfig(), obs, np.full(1, np.nan))
    habit, _ = vo_course(VOConfig(w_static_starboard=0.3), obs, np.full(1, np.nan))
    assert (either[0] > 0) == (bearing_deg < 0)  # yes/no cone: away from the pole's side
    assert habit[0] > 0  # the habit: always to starboard, the pole left to port


def test_graded_cone_leaves_an_open_course_alone():
    obs = _obs(obstacles=[(60.0, 0.0, 1.0, -3.0, 0.0)])
    a, _ = vo_course(VOConfig(), obs, np.full(1, np.nan))
    b, _ = vo_course(VOConfig(w_shortfall=5.0), obs, np.full(1, np.nan))
    assert a[0] == b[0]


def test_head_on_vessel_gives_a_starboard_turn():
    # a vessel 150 m ahead coming at us at 3 m/s, slightly to port of dead ahead
    vessel = (150.0, -2 * DEG, 5.0, -6.0, 0.0)  # relative velocity: closing at 6 m/s
    assert _act(_obs(obstacles=[vessel])) > 5.0


def test_crossing_from_starboard_is_passed_astern():
    # 100 m away at 60° to starboard, moving to port at 3 m/s: our course passes within R_safe
    vessel = (100.0, 60 * DEG, 5.0, -3.0, -3.0)  # relative velocity (body frame, m/s)
    nan = np.full(1, np.nan)
    course, _ = vo_course(VOConfig(), _obs(obstacles=[vessel]), nan)
    free, _ = vo_course(VOConfig(w_colreg=0.0), _obs(obstacles=[vessel]), nan)
    assert course[0] > 45 * DEG  # gives way: alters to starboard, passes astern
    assert free[0] < 0.0  # without COLREG the cheaper way is ahead of it, to port


def test_empty_slots_are_ignored():
    o = _obs()
    o[0, 4:10] = (5.0, 0.0, 30.0, 0.0, 0.0, 0.0)  # an "obstacle" with validity 0
    assert _act(o) == pytest.approx(0.0, abs=1.6)


def test_reset_size_is_checked():
    h = VOHelmsman()
    h.reset(2)
    with pytest.raises(ValueError, match="reset"):
        h.act(_obs())


def test_vo_succeeds_on_the_studys_held_out_set():
    records = evaluate(VOHelmsman(), heldout_episodes(), observation="scene")
    assert np.mean([r.success for r in records]) >= 0.99
    assert min(r.min_pole_distance_m for r in records) > 15.0


@pytest.mark.parametrize("name", ["several-obstacles", "moving-vessels"])
def test_vo_beats_los_avoid_where_there_is_more_than_one_pole(name):
    stress_set = next(s for s in STRESS_SETS if s.name == name)
    episodes = stress_episodes(stress_set, 40)
    vo = np.mean([r.success for r in evaluate_set(VOHelmsman(), stress_set, episodes)])
    cone = np.mean([r.success for r in evaluate_set(AvoidHelmsman(), stress_set, episodes)])
    assert vo >= 0.95 and vo > cone + 0.2
