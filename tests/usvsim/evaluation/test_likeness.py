"""Expert-likeness: pass side, heading changes, path distance, and a ranking that makes sense."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from usvsim.evaluation.episodes import validation_episodes
from usvsim.evaluation.likeness import (
    ExpertReference,
    expert_reference,
    heading_changes,
    helmsman_likeness,
    likeness,
    pass_side,
)
from usvsim.helm.protocol import StraightAheadHelmsman


def _north_path(east_m: float, n: int = 1001) -> np.ndarray:
    """Heading north (ψ = 0) from x = -50 m to +50 m at y = ``east_m``."""
    return np.column_stack([np.linspace(-50.0, 50.0, n), np.full(n, east_m), np.zeros(n)])


def test_pass_side() -> None:
    pole = np.zeros(2)
    assert pass_side(_north_path(-10.0), pole) == -1.0  # pole to starboard: went round to port
    assert pass_side(_north_path(+10.0), pole) == 1.0  # pole to port: went round to starboard


def test_heading_changes_are_wrapped_2_s_differences() -> None:
    t = np.arange(0.0, 10.05, 0.1)
    path = np.column_stack([t, t, np.asarray(np.angle(np.exp(1j * (3.0 + 0.1 * t))))])
    np.testing.assert_allclose(heading_changes(path), np.full(5, 0.2), atol=1e-9)


@dataclass
class _Record:
    trajectory: np.ndarray
    pole_ne: np.ndarray


def test_identical_paths_are_perfectly_alike_and_offsets_measure_in_metres() -> None:
    path = _north_path(-20.0)
    ref = ExpertReference(
        specs=(validation_episodes()[0],),
        paths=((path,),),
        sides=(np.array([-1.0]),),
        heading_changes_rad=heading_changes(path),
    )
    same = likeness([_Record(path, np.zeros(2))], ref)  # type: ignore[list-item]
    assert (same.path_distance_m, same.side_agreement, same.action_distance_deg) == (0, 1, 0)
    shifted = likeness([_Record(_north_path(-17.0), np.zeros(2))], ref)  # type: ignore[list-item]
    assert shifted.path_distance_m == pytest.approx(3.0, abs=1e-9)
    other_side = likeness([_Record(_north_path(20.0), np.zeros(2))], ref)  # type: ignore[list-item]
    assert other_side.side_agreement == 0.0


def test_expert_reference_is_deterministic() -> None:
    specs = validation_episodes()[:2]
    a = expert_reference(specs, n_samples=2)
    b = expert_reference(specs, n_samples=2)
    assert all(np.array_equal(x, y) for x, y in zip(a.paths[1], b.paths[1], strict=True))
    np.testing.assert_array_equal(a.heading_changes_rad, b.heading_changes_rad)


def test_avoiding_helmsman_is_more_expert_like_than_straight_ahead() -> None:
    from baselines.avoid import AvoidHelmsman

    ref = expert_reference(validation_episodes()[:5], n_samples=2)
    straight = helmsman_likeness(StraightAheadHelmsman(), reference=ref)
    avoid = helmsman_likeness(AvoidHelmsman(), reference=ref)
    assert avoid.path_distance_m < 0.5 * straight.path_distance_m
    assert math.isfinite(avoid.action_distance_deg) and avoid.n_episodes == 5
