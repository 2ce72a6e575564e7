"""The per-decision COLREG reward terms (usvsim.task.colreg_reward, issue 41) on hand-made
geometries: each term fires in its situation with its documented sign and size, and is 0 in
the others. Own ship at the origin heading north (course 0) at 3 m/s unless stated."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.colreg_geometry import EncounterType
from usvsim.task.colreg_reward import (
    COLREG_TERMS,
    ColregReward,
    ColregRewardWeights,
    ColregTerms,
    own_motion,
)
from usvsim.task.openwater_env import OpenWaterVectorEnv

W = ColregRewardWeights()
DT = 2.0  # s, a decision period
DEG = math.pi / 180.0


def _call(
    rew: ColregReward, own: tuple[float, float], course_deg: float,
    vessels: list[tuple[float, float, float, float]], speed: float = 3.0,
) -> ColregTerms:  # fmt: skip
    """One decision of one boat: vessels as (north m, east m, v_north m/s, v_east m/s)."""
    v = np.array(vessels, dtype=float).reshape(1, -1, 4)
    return rew(
        np.array([own], float), np.array([course_deg * DEG]), np.array([speed]),
        v[..., 0:2], v[..., 2:4], np.ones(v.shape[:2], bool), DT,
    )  # fmt: skip


def _values(t: ColregTerms) -> dict[str, float]:
    return {name: float(getattr(t, name)[0]) for name in COLREG_TERMS}


def _zero_but(t: ColregTerms, *names: str) -> None:
    v = _values(t)
    assert {k: x for k, x in v.items() if k not in names} == dict.fromkeys(
        [k for k in COLREG_TERMS if k not in names], 0.0
    )


HEAD_ON = (300.0, 5.0, -3.0, 0.0)  # 5 m to starboard of dead ahead, reciprocal course
GIVE_WAY = (150.0, 150.0, 0.0, -3.0)  # from starboard, heading west: meets at (150, 0)
STAND_ON = (150.0, -150.0, 0.0, 3.0)  # from port, heading east


def test_head_on_passing_starboard_to_starboard_is_charged_in_proportion() -> None:
    rew = ColregReward(W, 1)
    t = _call(rew, (0.0, 0.0), 0.0, [HEAD_ON])
    assert rew.role[0, 0] == EncounterType.HEAD_ON
    y_cpa = 5.0  # the target's predicted offset at the CPA, to starboard
    assert _values(t)["head_on_side"] == pytest.approx(
        -W.head_on_side * y_cpa / W.params.preferred_cpa_m
    )
    _zero_but(t, "head_on_side", "cpa")
    # passing it on the port side (target to port of the own track): nothing
    rew = ColregReward(W, 1)
    assert _values(_call(rew, (0.0, 0.0), 0.0, [(300.0, -5.0, -3.0, 0.0)]))["head_on_side"] == 0.0


def test_head_on_turn_to_port_is_charged_and_to_starboard_is_paid() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [HEAD_ON])
    port = _values(_call(rew, (6.0, 0.0), -5.0, [(294.0, 5.0, -3.0, 0.0)]))
    assert port["head_on_port"] == pytest.approx(-W.head_on_port * 0.5)  # 5° of 10°
    assert port["starboard"] == 0.0 and port["stand_on"] == 0.0
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [(300.0, -5.0, -3.0, 0.0)])
    stbd = _values(_call(rew, (6.0, 0.0), 15.0, [(294.0, -5.0, -3.0, 0.0)]))
    assert stbd["starboard"] == pytest.approx(W.starboard * 0.5)  # 15° of a 30° alteration
    assert stbd["head_on_port"] == 0.0 and stbd["head_on_side"] == 0.0


def test_head_on_resuming_the_course_after_a_starboard_alteration_is_not_charged() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [(300.0, -5.0, -3.0, 0.0)])
    _call(rew, (6.0, 0.0), 12.0, [(294.0, -5.0, -3.0, 0.0)])  # 12° to starboard first
    back = _values(_call(rew, (12.0, 0.5), -5.0, [(288.0, -5.0, -3.0, 0.0)]))
    assert back["head_on_port"] == 0.0
    assert back["starboard"] == pytest.approx(-W.starboard * 12 / 30)  # the alteration given back


def test_starboard_alteration_is_paid_once_up_to_a_readily_apparent_one() -> None:
    rew = ColregReward(W, 1)
    paid = [_values(_call(rew, (0.0, 0.0), c, [GIVE_WAY]))["starboard"] for c in (0, 20, 40, 50)]
    assert rew.role[0, 0] == EncounterType.CROSSING_GIVE_WAY
    assert paid == pytest.approx([0.0, W.starboard * 20 / 30, W.starboard * 10 / 30, 0.0])
    assert sum(paid) == pytest.approx(W.starboard)


def test_give_way_crossing_ahead_of_the_bow_is_charged_once() -> None:
    rew = ColregReward(W, 1)
    t0 = _call(rew, (0.0, 0.0), 0.0, [GIVE_WAY])
    assert rew.role[0, 0] == EncounterType.CROSSING_GIVE_WAY
    _zero_but(t0, "cpa")
    # the own ship is across the target's course line (north 150 m) while the target is still
    # 100 m east of it, heading west: ahead of its bow
    t1 = _call(rew, (160.0, 0.0), 0.0, [(150.0, 100.0, 0.0, -3.0)])
    assert _values(t1)["crossing_ahead"] == -W.crossing_ahead
    _zero_but(t1, "crossing_ahead", "cpa")
    t2 = _call(rew, (166.0, 0.0), 0.0, [(150.0, 94.0, 0.0, -3.0)])
    assert _values(t2)["crossing_ahead"] == 0.0


def test_give_way_passing_astern_is_not_charged() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [GIVE_WAY])
    # across its course line after it passed: the target already 20 m west of the own ship
    t = _call(rew, (160.0, 30.0), 60.0, [(150.0, 10.0, 0.0, -3.0)])
    assert _values(t)["crossing_ahead"] == 0.0


def test_stand_on_course_change_is_charged_before_the_give_way_vessel_could_act() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [STAND_ON])
    assert rew.role[0, 0] == EncounterType.CROSSING_STAND_ON
    t = _call(rew, (6.0, 0.0), 6.0, [(150.0, -144.0, 0.0, 3.0)])
    assert _values(t)["stand_on"] == pytest.approx(-W.stand_on * 0.5)  # (6° − 2°) / (10° − 2°)
    _zero_but(t, "stand_on", "cpa")
    t = _call(rew, (12.0, 0.0), 25.0, [(150.0, -138.0, 0.0, 3.0)])
    assert _values(t)["stand_on"] == -W.stand_on
    assert _values(t)["starboard"] == 0.0  # a stand-on alteration earns nothing


def test_stand_on_may_act_after_the_grace_time_inside_the_free_range() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [STAND_ON])  # range 212 m < 330 m: free once the grace is over
    rew.age_s[:] = W.stand_on_grace_s
    t = _call(rew, (6.0, 0.0), 25.0, [(150.0, -144.0, 0.0, 3.0)])
    assert _values(t)["stand_on"] == 0.0


def test_stand_on_is_not_charged_while_giving_way_to_another_vessel() -> None:
    rew = ColregReward(W, 1)
    _call(rew, (0.0, 0.0), 0.0, [STAND_ON, GIVE_WAY])
    assert rew.role[0].tolist() == [
        EncounterType.CROSSING_STAND_ON,
        EncounterType.CROSSING_GIVE_WAY,
    ]
    t = _call(rew, (6.0, 0.0), 25.0, [(150.0, -144.0, 0.0, 3.0), (150.0, 144.0, 0.0, -3.0)])
    assert _values(t)["stand_on"] == 0.0
    assert _values(t)["starboard"] == pytest.approx(W.starboard * 25 / 30)


@pytest.mark.parametrize(
    ("miss_m", "share"), [(0.0, 1.0), (20.0, 1.0), (43.5, 0.5), (57.0, 0.0), (80.0, 0.0)]
)
def test_cpa_term_ramps_from_the_preferred_to_the_minimum_passing_distance(
    miss_m: float, share: float
) -> None:
    # the own ship stopped; a vessel 200 m ahead heading south, passing miss_m to starboard
    rew = ColregReward(W, 1)
    t = _call(rew, (0.0, 0.0), 0.0, [(200.0, miss_m, -4.0, 0.0)], speed=0.0)
    assert _values(t)["cpa"] == pytest.approx(-W.cpa * share)


def test_no_vessel_no_risk_no_reward() -> None:
    rew = ColregReward(W, 1)
    far = _call(rew, (0.0, 0.0), 0.0, [(900.0, 0.0, -3.0, 0.0)])  # beyond the entry range
    away = _call(rew, (0.0, 0.0), 0.0, [(-100.0, 0.0, -3.0, 0.0)])  # astern, opening
    assert _values(far) == dict.fromkeys(COLREG_TERMS, 0.0)
    assert _values(away) == dict.fromkeys(COLREG_TERMS, 0.0)


def test_without_zeroes_the_named_terms_only() -> None:
    w = W.without("starboard", "cpa")
    assert (w.starboard, w.cpa, w.crossing_ahead) == (0.0, 0.0, W.crossing_ahead)
    with pytest.raises(ValueError, match="unknown COLREG term"):
        W.without("speed")


def test_own_motion_reads_course_and_speed_over_ground() -> None:
    t = np.arange(1, 21) * 0.1
    traj = np.zeros((2, 20, 13))
    traj[0, :, 0], traj[0, :, 1] = 2.0 * t, 2.0 * t  # north-east at 2√2 m/s
    traj[1, :, 1] = -3.0 * t  # west at 3 m/s
    pos, course, speed, t_end = own_motion(traj, np.array([20, 5]), 0.1)
    np.testing.assert_allclose(course, [45 * DEG, -90 * DEG])
    np.testing.assert_allclose(speed, [2 * math.sqrt(2), 3.0])
    np.testing.assert_allclose(t_end, [2.0, 0.5])
    np.testing.assert_allclose(pos[1], [0.0, -1.5])


def _rollout(env: OpenWaterVectorEnv, steps: int) -> list[tuple[np.ndarray, dict]]:
    env.reset(seed=3)
    rng = np.random.default_rng(0)
    out = []
    for _ in range(steps):
        _, r, _, _, info = env.step(rng.uniform(-0.5, 0.5, (env.num_envs, 1)))
        out.append((r, info))
    return out


def test_env_reward_is_the_studys_without_the_option_and_adds_the_terms_with_it() -> None:
    off = _rollout(OpenWaterVectorEnv(8, observation="scene", family=COLREG_FAMILY), 40)
    on_env = OpenWaterVectorEnv(8, observation="scene", family=COLREG_FAMILY, colreg_reward=W)
    on = _rollout(on_env, 40)
    fired = np.zeros(len(COLREG_TERMS), int)
    for (r0, i0), (r1, i1) in zip(off, on, strict=True):
        assert not any(k.startswith("reward_colreg") for k in i0)
        np.testing.assert_array_equal(r0, i0["reward_pole"] + i0["reward_goal"])
        np.testing.assert_array_equal(i0["reward_pole"], i1["reward_pole"])  # same episodes
        np.testing.assert_array_equal(
            r1, i1["reward_pole"] + i1["reward_goal"] + i1["reward_colreg"]
        )
        fired += [int(np.any(i1[f"reward_colreg_{t}"] != 0)) for t in COLREG_TERMS]
    assert fired[COLREG_TERMS.index("cpa")] > 0 and fired[COLREG_TERMS.index("starboard")] > 0
