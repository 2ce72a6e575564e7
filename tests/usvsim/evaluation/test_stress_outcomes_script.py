"""benchmarks/stress_outcomes.py: the geometry behind its goal-orbit and traffic counts."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from usvsim.task.openwater import Vessel

_SPEC = importlib.util.spec_from_file_location(
    "stress_outcomes", Path(__file__).resolve().parents[3] / "benchmarks" / "stress_outcomes.py"
)
assert _SPEC is not None and _SPEC.loader is not None
outcomes = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(outcomes)


def _vessel(x0_n: float, y0_e: float, course_deg: float, speed_mps: float) -> Vessel:
    return Vessel(x0_n, y0_e, math.radians(course_deg), speed_mps, 0.0, 5.0, "overtaking")


def test_closest_goal_approach_is_the_least_distance_of_the_track_to_the_goal() -> None:
    """A straight track north along y_E = 12 m passes a goal at (100, 0) 12 m off."""
    north = np.linspace(0.0, 200.0, 401)
    track = np.stack([north, np.full_like(north, 12.0), np.zeros_like(north)], axis=1)
    record = SimpleNamespace(trajectory=track, episode=SimpleNamespace(goal_ne=(100.0, 0.0)))
    assert outcomes.closest_goal_approach_m(record) == pytest.approx(12.0, abs=1e-12)


def test_a_vessel_on_a_course_through_the_goal_passes_it_within_the_time_limit() -> None:
    """2 m/s due north from 150 m south of the goal: at the goal after 75 s; a parallel course
    30 m to the east passes 30 m off; a 60 s time limit ends before the vessel arrives."""
    goal = (150.0, 0.0)
    through = SimpleNamespace(
        goal_ne=goal, time_limit_s=150.0, vessels=(_vessel(0.0, 0.0, 0.0, 2.0),)
    )
    beside = SimpleNamespace(
        goal_ne=goal, time_limit_s=150.0, vessels=(_vessel(0.0, 30.0, 0.0, 2.0),)
    )
    early = SimpleNamespace(goal_ne=goal, time_limit_s=60.0, vessels=through.vessels)
    alone = SimpleNamespace(goal_ne=goal, time_limit_s=150.0, vessels=())
    assert outcomes.nearest_vessel_to_goal_m(through) == pytest.approx(0.0, abs=1e-9)
    assert outcomes.nearest_vessel_to_goal_m(beside) == pytest.approx(30.0, abs=1e-9)
    assert outcomes.nearest_vessel_to_goal_m(early) == pytest.approx(30.0, abs=1e-9)
    assert outcomes.nearest_vessel_to_goal_m(alone) == math.inf
