"""Scenario: episode draws, start geometry, per-boat noise streams."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.common.angles import ssa
from usvsim.task.scenario import (
    BoatNoise,
    EpisodeSpec,
    Scenario,
    draw_episode,
    draw_episodes,
    episode_geometry,
)


def test_draws_cover_the_studys_ranges():
    specs = draw_episodes(np.random.default_rng(0), Scenario(), 2000)
    d = np.array([s.start_distance_m for s in specs])
    b = np.array([s.start_bearing_rad for s in specs])
    assert d.min() >= 50.0 and d.max() <= 100.0
    assert d.min() < 51.0 and d.max() > 99.0
    assert b.min() >= 0.0 and b.max() < 2 * math.pi
    assert np.histogram(b, bins=8, range=(0, 2 * math.pi))[0].min() > 200  # uniform-ish
    assert {s.pole_index for s in specs} == {0, 1}
    assert all(s.heading_offset_rad == 0.0 for s in specs)


def test_same_generator_seed_gives_same_episodes():
    a = draw_episodes(np.random.default_rng(5), Scenario(), 10)
    b = draw_episodes(np.random.default_rng(5), Scenario(), 10)
    assert a == b


def test_start_faces_the_pole_and_goal_lies_220_m_beyond_it():
    sc = Scenario()
    specs = draw_episodes(np.random.default_rng(1), sc, 500)
    geo = episode_geometry(sc, specs)
    start, pole, goal = geo.start_eta[:, :2], geo.pole_ne, geo.goal_ne
    d = np.array([s.start_distance_m for s in specs])
    np.testing.assert_allclose(np.linalg.norm(start - pole, axis=1), d, rtol=1e-12)
    to_pole = np.arctan2(pole[:, 1] - start[:, 1], pole[:, 0] - start[:, 0])
    np.testing.assert_allclose(ssa(geo.start_eta[:, 2] - to_pole), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(goal - start, axis=1), 220.0, rtol=1e-12)
    # on the far side of the pole, on the start→pole line
    np.testing.assert_allclose(np.linalg.norm(goal - pole, axis=1), 220.0 - d, rtol=1e-9)
    cross = (pole - start)[:, 0] * (goal - start)[:, 1] - (pole - start)[:, 1] * (goal - start)[
        :, 0
    ]
    np.testing.assert_allclose(cross, 0.0, atol=1e-9)


def test_known_geometry_of_one_episode():
    spec = EpisodeSpec(pole_index=1, start_distance_m=80.0, start_bearing_rad=math.pi / 2)
    geo = episode_geometry(Scenario(), [spec])
    np.testing.assert_allclose(geo.start_eta[0], [500.0, 580.0, -math.pi / 2], atol=1e-12)
    np.testing.assert_allclose(geo.goal_ne[0], [500.0, 360.0], atol=1e-12)


def test_heading_offset_widens_the_start_heading():
    sc = Scenario(heading_offset_range_rad=(-0.5, 0.5))
    specs = draw_episodes(np.random.default_rng(2), sc, 300)
    offsets = np.array([s.heading_offset_rad for s in specs])
    assert offsets.min() < -0.45 and offsets.max() > 0.45
    geo = episode_geometry(sc, specs)
    to_pole = np.arctan2(
        geo.pole_ne[:, 1] - geo.start_eta[:, 1], geo.pole_ne[:, 0] - geo.start_eta[:, 0]
    )
    np.testing.assert_allclose(ssa(geo.start_eta[:, 2] - to_pole), offsets, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"start_distance_range_m": (100.0, 50.0)},
        {"pole_radius_m": -1.0},
        {"goal_distance_m": 90.0},
        {"decision_period_s": 2.05},
        {"poles_ne": ()},
    ],
)
def test_invalid_scenarios_raise(kwargs):
    with pytest.raises(ValueError):
        Scenario(**kwargs)


def test_bad_pole_index_raises():
    with pytest.raises(ValueError, match="pole_index"):
        episode_geometry(Scenario(), [EpisodeSpec(2, 60.0, 0.0)])


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_boat_noise_serves_each_boat_its_own_generator_stream(backend):
    noise = BoatNoise(3, width=16, block=5, backend=backend)
    noise.seed(np.arange(3), [11, 12, 13])
    got: list[list[float]] = [[], [], []]
    pattern = np.random.default_rng(0)
    for _ in range(300):  # random subsets and sizes, incl. draws larger than the buffer
        boats = np.flatnonzero(pattern.random(3) < 0.6)
        if boats.size == 0:
            continue
        m = int(pattern.integers(1, 40))
        x = noise.for_boats(boats).normal(0.0, 1.0, size=(boats.size, m))
        for row, i in zip(x, boats, strict=True):
            got[i].extend(row)
    for i, seed in enumerate([11, 12, 13]):
        ref = np.random.default_rng(seed).standard_normal(len(got[i]))
        np.testing.assert_array_equal(np.array(got[i]), ref)


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_boat_noise_reseeding_restarts_only_those_streams(backend):
    noise = BoatNoise(3, width=16, block=5, backend=backend)
    noise.seed(np.arange(3), [1, 2, 3])
    first = noise.for_boats(None).standard_normal((3, 7))
    noise.seed(np.array([1]), [42])
    second = noise.for_boats(None).standard_normal((3, 20))
    ref = {s: np.random.default_rng(s).standard_normal(27) for s in (1, 3)}
    np.testing.assert_array_equal(np.concatenate([first[0], second[0]]), ref[1])
    np.testing.assert_array_equal(np.concatenate([first[2], second[2]]), ref[3])
    np.testing.assert_array_equal(second[1], np.random.default_rng(42).standard_normal(20))


def test_first_bad_spec_is_reported():
    specs = [EpisodeSpec(0, 60.0, 0.0), EpisodeSpec(0, -1.0, 0.0), EpisodeSpec(5, 60.0, 0.0)]
    with pytest.raises(ValueError, match=r"start_distance_m must be finite and > 0, got -1\.0"):
        episode_geometry(Scenario(), specs)
    with pytest.raises(ValueError, match="pole_index 5 out of range for 2 poles"):
        episode_geometry(Scenario(), specs[2:] + specs[:2])


@pytest.mark.parametrize("backend", ["numpy", "auto"])
def test_boat_noise_scales_and_checks_the_row_count(backend):
    noise = BoatNoise(2, backend=backend)
    noise.seed(np.arange(2), [1, 2])
    x = noise.normal(3.0, 2.0, size=(2, 4))
    ref = np.stack([np.random.default_rng(s).standard_normal(4) for s in (1, 2)])
    np.testing.assert_array_equal(x, 3.0 + 2.0 * ref)
    with pytest.raises(ValueError, match="serves 2 boats"):
        noise.normal(0.0, 1.0, size=(3,))


def test_draw_episode_order_is_fixed():
    rng = np.random.default_rng(9)
    spec = draw_episode(rng, Scenario())
    ref = np.random.default_rng(9)
    assert spec.pole_index == int(ref.integers(2))
    assert spec.start_distance_m == float(ref.uniform(50.0, 100.0))
