"""The RL setups in traffic with the COLREG reward (issue 41, learning.experiments.setups)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from learning.experiments.setups import RLSetup, get_setup, setup_from_params, setup_params
from usvsim.task.colreg_reward import COLREG_TERMS, ColregRewardWeights
from usvsim.task.reward import GoalAimReward, SafetyMarginReward, SuccessReward

NAMES = (
    "rl-gaussian-radar-colreg",
    "rl-gaussian-radar-colreg-noreward",
    "rl-gaussian-radar-colreg-ft",
    "rl-gaussian-scene-colreg",
    "rl-gaussian-radar-colreg-reactive",
    "rl-gaussian-radar-colreg-ilft-safe",
    "rl-gaussian-radar-colreg-ilft-safe-ow",
    "rl-gaussian-radar-colreg-ilft-safe-ow-arrive",
    "rl-gaussian-radar-colreg-ilft-safe-ow-approach",
    "rl-gaussian-radar-colreg-ilft-safe-ow-goaltraffic",
    "rl-gaussian-radar-colreg-ilft-safe-ow-aim",
    "rl-gaussian-radar-colreg-ilft-safe-ow-aim2",
    "rl-gaussian-radar-colreg-ilft-safe-ow-aim4",
    "rl-gaussian-radar-colreg-ilft-safe-ow-aim2-safe6",
    "rl-gaussian-radar-colreg-ilft-safe-ow-aim-islet",
)


def test_the_colreg_setup_builds_its_env_with_the_colreg_reward_on() -> None:
    setup = get_setup("rl-gaussian-radar-colreg")
    env = setup.make_vector_env(4)
    assert env.colreg is not None and env.colreg.weights == ColregRewardWeights()
    assert {"colreg-imazu", "colreg-trafficgen"} <= set(env.family.names)
    colreg = [n.startswith(("colreg-", "harsh-colreg-")) for n in env.family.names]
    np.testing.assert_allclose(env.family.probabilities[colreg].sum(), 0.5)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros((4, 1)))
    assert {f"reward_colreg_{t}" for t in COLREG_TERMS} <= set(info)
    assert np.all(np.isfinite(reward))


def test_the_ablation_baseline_has_the_same_family_and_budget_without_the_reward() -> None:
    on, off = get_setup(NAMES[0]), get_setup(NAMES[1])
    assert off.colreg_weights is None and off.make_vector_env(2).colreg is None
    assert off.training_family == on.training_family
    assert off.algorithm_config == on.algorithm_config
    assert get_setup(NAMES[2]).init_policy == "rl-gaussian-radar-ow"
    assert get_setup(NAMES[3]).observation == "scene"
    assert on.make_vector_env(2).on_decision is None


def test_the_reactive_setup_trains_with_steered_targets() -> None:
    from learning.experiments.train_rl import env_maker
    from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets

    setup = get_setup("rl-gaussian-radar-colreg-reactive")
    env = env_maker(setup)(2)
    assert isinstance(env.on_decision, TrainingReactiveTargets) and env.colreg is not None
    assert env_maker(get_setup(NAMES[0]))(2).on_decision is None
    assert setup.replace(name=NAMES[0], reactive_targets=False) == get_setup(NAMES[0])


def test_colreg_reward_names_the_terms_on() -> None:
    setup = get_setup(NAMES[0]).replace(colreg_reward="cpa, starboard")
    w, full = setup.colreg_weights, ColregRewardWeights()
    assert w is not None
    assert (w.cpa, w.starboard) == (full.cpa, full.starboard)
    assert all(getattr(w, t) == 0.0 for t in COLREG_TERMS if t not in ("cpa", "starboard"))
    with pytest.raises(ValueError, match="unknown COLREG reward term 'speed'"):
        get_setup(NAMES[0]).replace(colreg_reward="speed")
    with pytest.raises(ValueError, match="task='open-water'"):
        RLSetup("x", "positional", "gaussian", colreg_reward="all")


@pytest.mark.parametrize("name", NAMES)
def test_colreg_setups_round_trip_through_a_checkpoint(name: str) -> None:
    setup = get_setup(name)
    back = setup_from_params(get_setup("rl-gaussian-radar-ow"), setup_params(setup))
    assert back == dataclasses.replace(setup)


def test_the_il_fine_tuning_keeps_the_input_statistics_and_needs_a_start_file() -> None:
    ilft, on = get_setup("rl-gaussian-radar-colreg-ilft"), get_setup(NAMES[0])
    assert ilft.init_policy_required and not ilft.init_policy
    assert ilft.algorithm_config.fixed_input_stats and not on.algorithm_config.fixed_input_stats
    assert ilft.training_family == on.training_family and ilft.colreg_reward == "all"
    assert dataclasses.replace(ilft.algorithm_config, fixed_input_stats=False) == (
        on.algorithm_config
    )


@pytest.mark.parametrize(
    ("name", "parent", "field", "attribute", "term", "says"),
    [
        (
            "rl-gaussian-radar-colreg-ilft-safe",
            "rl-gaussian-radar-colreg-ilft",
            "safety_reward",
            "safety",
            SafetyMarginReward(weight=2.0),
            "no safety-margin, success or aim reward",
        ),
        (
            "rl-gaussian-radar-colreg-ilft-safe-ow-arrive",
            "rl-gaussian-radar-colreg-ilft-safe-ow",
            "success_reward",
            "success",
            SuccessReward(weight=2.0),
            "no safety-margin, success or aim reward",
        ),
        (
            "rl-gaussian-radar-colreg-ilft-safe-ow-aim",
            "rl-gaussian-radar-colreg-ilft-safe-ow",
            "aim_reward",
            "aim",
            GoalAimReward(weight=1.0, range_m=100.0),
            "no safety-margin, success or aim reward",
        ),
        (
            "rl-gaussian-radar-colreg-ilft-safe-ow-aim2",
            "rl-gaussian-radar-colreg-ilft-safe-ow",
            "aim_reward",
            "aim",
            GoalAimReward(weight=2.0, range_m=100.0),
            "no safety-margin, success or aim reward",
        ),
        (
            "rl-gaussian-radar-colreg-ilft-safe-ow-aim4",
            "rl-gaussian-radar-colreg-ilft-safe-ow",
            "aim_reward",
            "aim",
            GoalAimReward(weight=4.0, range_m=100.0),
            "no safety-margin, success or aim reward",
        ),
    ],
)
def test_a_reward_setup_adds_its_term_and_nothing_else(
    name: str, parent: str, field: str, attribute: str, term: object, says: str
) -> None:
    from learning.experiments.train_rl import device_env_maker

    setup, base = get_setup(name), get_setup(parent)
    assert setup.replace(name=base.name, **{field: 0.0}) == base
    env = setup.make_vector_env(2)
    assert getattr(env, attribute) == term
    assert getattr(base.make_vector_env(2), attribute) is None
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros((2, 1)))
    assert f"reward_{attribute}" in info and np.all(np.isfinite(reward))
    for bad in (-1.0, math.nan):
        with pytest.raises(ValueError, match=f"{field} must be a finite weight >= 0"):
            base.replace(**{field: bad})
    with pytest.raises(ValueError, match="task='open-water'"):
        RLSetup("x", "positional", "gaussian", **{field: 1.0})
    with pytest.raises(ValueError, match=says):
        device_env_maker(setup, "torch-cpu")


def test_the_safe_ow_setup_draws_a_quarter_of_its_episodes_from_the_colreg_members() -> None:
    safe, ow = (
        get_setup("rl-gaussian-radar-colreg-ilft-safe"),
        get_setup("rl-gaussian-radar-colreg-ilft-safe-ow"),
    )
    assert ow.replace(name=safe.name, colreg_share=0.5) == safe
    family = ow.training_family
    colreg = [n.startswith(("colreg-", "harsh-colreg-")) for n in family.names]
    np.testing.assert_allclose(family.probabilities[colreg].sum(), 0.25)


def test_the_safe6_setup_is_aim2_with_three_times_the_safety_penalty() -> None:
    aim2 = get_setup("rl-gaussian-radar-colreg-ilft-safe-ow-aim2")
    safe6 = get_setup("rl-gaussian-radar-colreg-ilft-safe-ow-aim2-safe6")
    assert safe6.replace(name=aim2.name, safety_reward=2.0) == aim2
    env = safe6.make_vector_env(2)
    assert env.safety == SafetyMarginReward(weight=6.0, margin_m=5.0)
    assert env.aim == GoalAimReward(weight=2.0, range_m=100.0)
    # inside the safety distance a period costs 6, three times -aim2's
    assert env.safety(np.array([5.0]), 10.0).tolist() == [-6.0]


@pytest.mark.parametrize(
    ("base", "setup", "share", "member"),
    [
        ("-arrive", "-approach", "approach_share", "goal-approach"),
        ("", "-goaltraffic", "goal_traffic_share", "goal-overtaking"),
        ("-aim", "-aim-islet", "goal_islet_share", "goal-islet"),
    ],
)
def test_a_practice_setup_draws_15_percent_of_its_member_and_nothing_else_new(
    base: str, setup: str, share: str, member: str
) -> None:
    """``-approach`` is ``-arrive``, ``-goaltraffic`` is ``-safe-ow``, ``-aim-islet`` is ``-aim``,
    each with 15 % of its practice member's episodes (the COLREG share scaled by the rest); the
    share is checked."""
    name = "rl-gaussian-radar-colreg-ilft-safe-ow"
    before, after = get_setup(name + base), get_setup(name + setup)
    assert after.replace(name=before.name, **{share: 0.0}) == before
    family = after.training_family
    practice = [n.endswith(member) for n in family.names]
    np.testing.assert_allclose(family.probabilities[practice].sum(), 0.15)
    colreg = [n.startswith(("colreg-", "harsh-colreg-")) for n in family.names]
    np.testing.assert_allclose(family.probabilities[colreg].sum(), 0.25 * 0.85)
    for bad in (-0.1, 1.0):
        with pytest.raises(ValueError, match=f"{share} must be in"):
            before.replace(**{share: bad})
    with pytest.raises(ValueError, match="task='open-water'"):
        RLSetup("x", "positional", "gaussian", **{share: 0.1})
