"""benchmarks/goal_response.py: a helmsman's turn towards a goal in clear water."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from usvsim.helm.registry import helmsman_kinds, make_helmsman
from usvsim.task.observations import GOAL_STANDARDIZATION

_BENCH = Path(__file__).resolve().parents[3] / "benchmarks"
_SPEC = importlib.util.spec_from_file_location("goal_response", _BENCH / "goal_response.py")
assert _SPEC is not None and _SPEC.loader is not None
response = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(response)


def test_the_radar_observation_is_a_clean_image_and_the_goal_where_it_was_put() -> None:
    bearings = np.radians([-45.0, 0.0, 30.0])
    obs = response.clear_water_observations("radar+goal", 25.0, bearings)
    assert obs["radar"].shape[0] == 3 and not obs["radar"].any()
    want = GOAL_STANDARDIZATION.apply(np.stack([np.full(3, 25.0), bearings], axis=1))
    np.testing.assert_allclose(obs["goal"], want, rtol=0, atol=1e-5)


def test_asymmetry_is_the_largest_mirrored_sum() -> None:
    bearings = np.array([-10.0, -5.0, 0.0, 5.0, 10.0, 20.0])  # +20° has no mirror: ignored
    turns = np.array([-1.0, -4.0, 0.5, 5.0, 18.0, 27.0])
    assert response.asymmetry_deg(bearings, turns) == pytest.approx(17.0)


def test_a_helmsman_that_steers_at_the_goal_turns_by_its_bearing_up_to_the_limit() -> None:
    """``vo-radar`` in clear water is LOS to the goal: the turn has the bearing's sign, none
    when the goal is ahead, mirrored port and starboard, and the ±30° limit abeam."""
    helmsman = make_helmsman("vo-radar")
    kind, action = helmsman_kinds(helmsman)
    bearings = np.array(response.BEARINGS_DEG)
    turns = response.response_deg(helmsman, kind, action, 40.0, bearings)
    assert turns[bearings == 0.0][0] == 0.0
    assert np.all(np.sign(turns[bearings != 0.0]) == np.sign(bearings[bearings != 0.0]))
    assert response.asymmetry_deg(bearings, turns) < 1e-9
    assert abs(turns[bearings == 90.0][0]) == pytest.approx(30.0)
