"""Reward: the corrected Gaussian form of table-4-1.md at known distances."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.task.reward import (
    GaussianReward,
    GoalAimReward,
    RewardTerms,
    SafetyMarginReward,
    SuccessReward,
)


def test_values_at_known_distances():
    d_pole = np.array([0.0, 5.0, 10.0, 1e3])
    d_goal = np.array([0.0, 100.0, 200.0, 1e5])
    t = GaussianReward()(d_pole, d_goal)
    np.testing.assert_allclose(
        t.pole, [-2.0, -2 * math.exp(-0.5), -2 * math.exp(-2.0), 0.0], rtol=1e-15, atol=1e-300
    )
    np.testing.assert_allclose(
        t.goal, [0.0, math.exp(-0.5) - 1.0, math.exp(-2.0) - 1.0, -1.0], rtol=1e-15
    )
    np.testing.assert_allclose(t.total, t.pole + t.goal)
    assert t.pole[1] == pytest.approx(-1.2130613194252668, rel=1e-15)
    assert t.goal[1] == pytest.approx(-0.3934693402873666, rel=1e-15)


def test_ranges_match_the_study():
    d = np.linspace(0.0, 500.0, 1001)
    t = GaussianReward()(d, d)
    assert t.pole.min() == -2.0 and t.pole.max() <= 0.0
    assert t.goal.min() >= -1.0 and t.goal.max() == 0.0


def test_invalid_parameters_raise():
    with pytest.raises(ValueError, match="pole_sigma_m"):
        GaussianReward(pole_sigma_m=0.0)


def test_terms_dataclass_sum():
    terms = RewardTerms(pole=np.array([-1.0]), goal=np.array([-0.25]))
    assert terms.total.tolist() == [-1.25]


def test_safety_margin_is_zero_beyond_the_margin_and_full_inside_the_safety_distance():
    r = SafetyMarginReward(weight=2.0, margin_m=5.0)
    d = np.array([np.inf, 16.0, 15.0, 13.75, 12.5, 10.0, 9.99, 0.0])
    np.testing.assert_allclose(r(d, 10.0), [0.0, 0.0, 0.0, -0.5, -1.0, -2.0, -2.0, -2.0])
    assert r(np.array([12.5]), 8.0)[0] == pytest.approx(-0.2)  # the scenario's distance


@pytest.mark.parametrize("name", ["weight", "margin_m"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan])
def test_safety_margin_invalid_parameters_raise(name, value):
    with pytest.raises(ValueError, match=f"SafetyMarginReward.{name}"):
        SafetyMarginReward(**{name: value})


def test_success_reward_pays_the_weight_where_an_episode_succeeds_and_nothing_elsewhere():
    paid = SuccessReward(weight=3.0)(np.array([True, False, True, False]))
    assert paid.dtype == np.float64 and paid.tolist() == [3.0, 0.0, 3.0, 0.0]
    assert SuccessReward()(np.zeros(5, dtype=bool)).sum() == 0.0


@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan])
def test_success_reward_invalid_weight_raises(value):
    with pytest.raises(ValueError, match=r"SuccessReward\.weight"):
        SuccessReward(weight=value)


def test_goal_aim_reward_is_one_minus_cosine_inside_its_range():
    b = np.radians([0.0, 30.0, -30.0, 90.0, 180.0, 90.0])
    d = np.array([10.0, 10.0, 10.0, 99.9, 50.0, 100.0])  # the last at the range: outside
    got = GoalAimReward(weight=2.0, range_m=100.0)(b, d)
    want = [0.0, -2 * (1 - math.cos(math.pi / 6)), -2 * (1 - math.cos(math.pi / 6)), -2.0, -4.0,
            0.0]  # fmt: skip
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert got[1] == got[2]  # port and starboard alike


@pytest.mark.parametrize("field", ["weight", "range_m"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.inf, math.nan])
def test_goal_aim_reward_invalid_parameters_raise(field, value):
    with pytest.raises(ValueError, match=rf"GoalAimReward\.{field}"):
        GoalAimReward(**{field: value})
