"""Expert-likeness on the open-water family: an expert sample is more like the expert than a
boat that holds its course, and the metrics follow their definitions."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from baselines.family_expert import run_family_expert
from usvsim.evaluation.family_likeness import (
    FAMILY_HELD_OUT_SEED,
    disc_track,
    family_held_out_episodes,
    family_likeness,
    family_reference,
)
from usvsim.evaluation.openwater import OpenWaterRecord, evaluate_open_water
from usvsim.helm.protocol import StraightAheadHelmsman


@pytest.fixture(scope="module")
def episodes():  # type: ignore[no-untyped-def]
    return family_held_out_episodes(6)


@pytest.fixture(scope="module")
def reference(episodes):  # type: ignore[no-untyped-def]
    return family_reference(episodes, n_samples=3)


def _as_records(runs, like):  # type: ignore[no-untyped-def]
    return [
        OpenWaterRecord(**{**rec.__dict__, "trajectory": run.trajectory[:, 1:4]})
        for run, rec in zip(runs, like, strict=True)
    ]


def test_held_out_set_has_its_own_seed() -> None:
    assert FAMILY_HELD_OUT_SEED == zlib.crc32(b"family-held-out")
    assert FAMILY_HELD_OUT_SEED != zlib.crc32(b"family-validation")


def test_an_expert_sample_is_more_alike_than_a_straight_run(episodes, reference) -> None:  # type: ignore[no-untyped-def]
    straight = evaluate_open_water(StraightAheadHelmsman(), episodes)
    other = run_family_expert(list(episodes), seed=99)  # fresh traits, same episodes
    expert_like = family_likeness(_as_records(other, straight), reference)
    straight_like = family_likeness(straight, reference)
    assert expert_like.path_distance_m < straight_like.path_distance_m
    assert expert_like.action_distance_deg < straight_like.action_distance_deg
    assert expert_like.side_agreement >= 0.5
    assert 0.0 <= straight_like.side_agreement <= 1.0


def test_a_reference_sample_has_distance_zero_to_itself(episodes, reference) -> None:  # type: ignore[no-untyped-def]
    straight = evaluate_open_water(StraightAheadHelmsman(), episodes)
    records = [
        OpenWaterRecord(**{**rec.__dict__, "trajectory": paths[0]})
        for paths, rec in zip(reference.paths, straight, strict=True)
    ]
    lk = family_likeness(records, reference)
    assert lk.path_distance_m == 0.0


def test_disc_track_moves_vessels_and_keeps_statics(episodes) -> None:  # type: ignore[no-untyped-def]
    t = np.array([0.0, 10.0])
    for e in episodes:
        for j in range(len(e.obstacles)):
            track = disc_track(e, j, t)
            assert np.array_equal(track[0], track[1])
        for k, v in enumerate(e.vessels):
            track = disc_track(e, len(e.obstacles) + k, t)
            assert np.hypot(*(track[1] - track[0])) == pytest.approx(v.speed_mps * 10.0, rel=1e-3)


def test_records_must_match_the_reference(reference) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match="need 6 records"):
        family_likeness([], reference)
