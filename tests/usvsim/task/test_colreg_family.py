"""The COLREG members of the open-water family (usvsim.task.colreg_family, issue 41)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from usvsim.common.splits import selection_mode
from usvsim.evaluation.colreg import EncounterTracks, EncounterType, evaluate_colreg
from usvsim.evaluation.colreg_suite import COLREG_SETS, colreg_episodes
from usvsim.task.colreg_family import (
    COLREG_FAMILY,
    COLREG_FAMILY_SUITE_GOALS,
    COLREG_KINDS,
    ColregTraffic,
    colreg_training_family,
    goal_overtaking_family,
)
from usvsim.task.openwater import OpenWaterEpisode, draw_open_water, vessel_motion
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, draw_family

ROLE = {  # the own ship's role each type is drawn for, as the scorer names it
    "head-on": EncounterType.HEAD_ON,
    "crossing-give-way": EncounterType.CROSSING_GIVE_WAY,
    "crossing-stand-on": EncounterType.CROSSING_STAND_ON,
    "overtaking-give-way": EncounterType.OVERTAKING_GIVE_WAY,
    "overtaking-stand-on": EncounterType.OVERTAKEN_STAND_ON,
}


def _straight_run_roles(e: OpenWaterEpisode) -> list[int]:
    """The scorer's encounter type of each target when the own ship runs start → goal at its
    cruise speed (1 s samples)."""
    s, g = e.start_ne, np.asarray(e.goal_ne)
    speed = e.disturbance.speed_mps if e.disturbance and e.disturbance.speed_mps else 3.0
    chi = math.atan2(g[1] - s[1], g[0] - s[0])
    t = np.arange(int(e.time_limit_s), dtype=float)
    own = s + speed * t[:, None] * np.array([math.cos(chi), math.sin(chi)])
    k = len(e.vessels)
    p0 = np.array([[v.x0_n, v.y0_e] for v in e.vessels])[:, None]
    course = np.array([v.course_rad for v in e.vessels])[:, None]
    v_speed = np.array([v.speed_mps for v in e.vessels])[:, None]
    pos, vel = vessel_motion(p0, course, v_speed, np.zeros((k, 1)), np.broadcast_to(t, (k, t.size)))
    tracks = EncounterTracks(
        1.0, own[None], np.full((1, t.size), chi), np.full((1, t.size), speed), pos[None],
        np.arctan2(vel[..., 1], vel[..., 0])[None], np.hypot(vel[..., 0], vel[..., 1])[None],
        np.ones((1, t.size), bool),
    )  # fmt: skip
    return [int(x) for x in evaluate_colreg(tracks).encounter[0]]


def test_each_type_is_the_role_the_scorer_gives_on_the_nominal_run() -> None:
    episodes = draw_family(COLREG_FAMILY, 3, 120)
    kinds = [v.encounter for e in episodes for v in e.vessels]
    roles = [r for e in episodes for r in _straight_run_roles(e)]
    assert set(kinds) == set(COLREG_KINDS)  # crossings from port and starboard both occur
    assert [int(ROLE[k]) for k in kinds] == roles


def test_imazu_member_targets_meet_the_own_run_at_one_time() -> None:
    member = COLREG_FAMILY.members[0]
    for e in draw_open_water(member, 11, 20):
        s, g = e.start_ne, np.asarray(e.goal_ne)
        speed = e.disturbance.speed_mps
        u = (g - s) / np.linalg.norm(g - s)
        n = np.array([-u[1], u[0]])  # starboard normal
        # when each target is abeam of the own nominal position: one time, within the miss range
        times = []
        for v in e.vessels:
            vv = v.speed_mps * np.array([math.cos(v.course_rad), math.sin(v.course_rad)])
            d0, dv = np.array([v.x0_n, v.y0_e]) - s, vv - speed * u
            t_c = -float(d0 @ u) / float(dv @ u)
            assert abs(float((d0 + dv * t_c) @ n)) <= 10.0 + 1e-9
            times.append(t_c)
        assert max(times) - min(times) < 1e-6
        assert 1 <= len(e.vessels) <= 4


def test_traffic_adds_vessels_and_moves_no_other_draw() -> None:
    base = replace(COLREG_FAMILY.members[1], traffic=None)
    plain = draw_open_water(base, 5, 30)
    traffic = draw_open_water(COLREG_FAMILY.members[1], 5, 30)
    assert all(e.vessels == () for e in plain)
    assert [replace(e, vessels=()) for e in traffic] == list(plain)
    assert all(1 <= len(e.vessels) <= 3 for e in traffic)


def test_the_open_water_family_is_unchanged() -> None:
    """The default family draws no traffic: its members have ``traffic=None``."""
    assert all(m.traffic is None for m in OPEN_WATER_FAMILY.members)
    mixed = colreg_training_family(0.4)
    assert mixed.members[:5] == OPEN_WATER_FAMILY.members
    assert mixed.names[5:] == ("colreg-imazu", "colreg-trafficgen")
    np.testing.assert_allclose(mixed.probabilities[5:].sum(), 0.4)


def _signatures(episodes: tuple[OpenWaterEpisode, ...]) -> np.ndarray:
    """Per target: its start relative to the own start in the own course's frame (m), its course
    relative to the own course (rad) and its speed (m/s)."""
    rows = []
    for e in episodes:
        s, g = e.start_ne, np.asarray(e.goal_ne)
        chi = math.atan2(g[1] - s[1], g[0] - s[0])
        c, si = math.cos(chi), math.sin(chi)
        for v in e.vessels:
            dn, de = v.x0_n - s[0], v.y0_e - s[1]
            rows.append((c * dn + si * de, -si * dn + c * de,
                         math.remainder(v.course_rad - chi, 2 * math.pi), v.speed_mps))  # fmt: skip
    return np.array(rows)


def test_training_never_draws_a_colreg_test_episode() -> None:
    with selection_mode("colreg-family training draw"):  # no test-split drawer is reached
        train = _signatures(draw_family(colreg_training_family(), 0, 400))
    test = _signatures(tuple(e for s in COLREG_SETS for e in colreg_episodes(s, 5, "test")))
    near = (
        (np.abs(train[:, None, 0] - test[None, :, 0]) < 1.0)
        & (np.abs(train[:, None, 1] - test[None, :, 1]) < 1.0)
        & (np.abs(train[:, None, 2] - test[None, :, 2]) < math.radians(1.0))
        & (np.abs(train[:, None, 3] - test[None, :, 3]) < 0.01)
    )
    assert len(train) > 300 and len(test) > 100
    assert not near.any()


def test_bad_traffic_parameters_are_refused() -> None:
    with pytest.raises(ValueError, match="n_targets_range"):
        ColregTraffic(n_targets_range=(0, 2))
    with pytest.raises(ValueError, match="kinds"):
        ColregTraffic(kinds=("crossing",))


def test_suite_goal_members_reach_as_far_as_the_colreg_suite() -> None:
    def goal_m(family: object, n: int) -> np.ndarray:
        eps = draw_family(family, 5, n)
        return np.array([np.hypot(*(np.asarray(e.goal_ne) - e.start_ne)) for e in eps])

    near, far = goal_m(COLREG_FAMILY, 200), goal_m(COLREG_FAMILY_SUITE_GOALS, 200)
    suite = [
        np.hypot(*(np.asarray(e.goal_ne) - e.start_ne))
        for name in ("imazu-01", "trafficgen-1ts")
        for e in colreg_episodes(next(s for s in COLREG_SETS if s.name == name), 2, "validation")
    ]
    assert near.min() >= 250.0 and near.max() <= 500.0
    assert far.min() >= 250.0 and far.max() <= 850.0
    assert max(suite) > near.max()  # the suite's goals (600, 797 m) lie beyond the default
    assert (far > max(suite)).any() and (far < 500.0).any()  # and inside the far range


def test_goal_overtaking_puts_a_slow_vessel_about_at_the_goal_when_the_boat_arrives() -> None:
    """The practice member for goal orbits: one vessel at 0.25-0.75 of the own speed on the
    route, near the goal (median within its 10 m circle) at the own boat's nominal arrival
    L / U, starting at least 40 m from the own start; no static obstacle."""
    episodes = draw_family(goal_overtaking_family(), 5, 300)
    to_goal, from_start = [], []
    for e in episodes:
        assert len(e.vessels) == 1 and not e.obstacles
        s, g = e.start_ne, np.asarray(e.goal_ne)
        length, own = float(np.hypot(*(g - s))), e.disturbance.speed_mps
        assert 120.0 <= length <= 300.0
        v = e.vessels[0]
        assert 0.25 * own <= v.speed_mps <= 0.75 * own
        p, _ = vessel_motion(
            np.array([v.x0_n, v.y0_e]), np.array(v.course_rad), np.array(v.speed_mps),
            np.array(0.0), np.array(length / own),
        )  # fmt: skip
        to_goal.append(float(np.hypot(*(p - g))))
        from_start.append(math.hypot(v.x0_n - s[0], v.y0_e - s[1]))
    assert np.median(to_goal) < 10.0 and np.percentile(to_goal, 90) < 25.0
    assert np.mean(np.asarray(from_start) >= 40.0) >= 0.99
