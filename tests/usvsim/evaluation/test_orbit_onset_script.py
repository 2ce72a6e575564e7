"""benchmarks/orbit_onset.py: the arrival figures of a track beside a vessel near the goal."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from usvsim.task.openwater import Vessel

_BENCH = Path(__file__).resolve().parents[3] / "benchmarks"
sys.path.insert(0, str(_BENCH))  # the script imports stress_outcomes beside it
_SPEC = importlib.util.spec_from_file_location("orbit_onset", _BENCH / "orbit_onset.py")
assert _SPEC is not None and _SPEC.loader is not None
onset = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(onset)


def _record(vessel: Vessel) -> SimpleNamespace:
    """Due north at 2 m/s along y_E = 12 m, a state every 2 s for 100 s; goal at (100, 0)."""
    north = np.arange(0.0, 201.0, 4.0)
    track = np.stack([north, np.full_like(north, 12.0), np.zeros_like(north)], axis=1)
    episode = SimpleNamespace(goal_ne=(100.0, 0.0), time_limit_s=150.0, vessels=(vessel,))
    return SimpleNamespace(trajectory=track, duration_s=100.0, episode=episode)


def test_arrival_with_a_vessel_parked_on_the_goal_is_blocked_until_the_limit() -> None:
    """First within 25 m of the goal at x_N = 80 m (|(-20, 12)| = 23.3 m): 40 s; the parked
    vessel 5 m from the goal blocks it to the end; the goal 31° off the heading, the vessel
    abeam-forward."""
    figures = onset.onset(_record(Vessel(100.0, 5.0, 0.0, 0.0, 0.0, 5.0, "x")), 25.0)
    assert figures["arrival_s"] == pytest.approx(40.0)
    assert figures["vessel_to_goal_m"] == pytest.approx(5.0)
    assert figures["blocked"] == 1.0 and math.isinf(figures["clear_after_s"])
    assert figures["circled_clear_s"] == 0.0
    assert figures["goal_off_deg"] == pytest.approx(math.degrees(math.atan2(12.0, 20.0)))
    assert figures["goal_signed_deg"] == -figures["goal_off_deg"]  # heading north, goal to port
    assert figures["vessel_range_m"] == pytest.approx(math.hypot(20.0, 7.0))


def test_a_vessel_leaving_the_goal_clears_it_when_it_is_24_m_away() -> None:
    """A vessel steaming east at 1 m/s, at the goal at the arrival (40 s): 24 m off 24 s later,
    so the goal clears then (within the 0.5 s sampling) and 86 s of the limit are left."""
    figures = onset.onset(_record(Vessel(100.0, -40.0, math.pi / 2, 1.0, 0.0, 5.0, "x")), 25.0)
    assert figures["blocked"] == 1.0
    assert figures["clear_after_s"] == pytest.approx(24.0, abs=0.5)
    assert figures["circled_clear_s"] == pytest.approx(150.0 - 40.0 - 24.0, abs=0.5)


def test_a_track_that_never_comes_near_has_no_arrival() -> None:
    record = _record(Vessel(100.0, 5.0, 0.0, 0.0, 0.0, 5.0, "x"))
    record.trajectory[:, 1] = 60.0
    assert onset.onset(record, 25.0) is None
