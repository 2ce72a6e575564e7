"""Radar image: pixel geometry (rows = range, columns = bearing), box size, batching."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.task.radar import RadarConfig, pixel_index, render_radar
from usvsim.task.scenario import BoatNoise

TINY = 1e-6  # m: a point-like pole lights exactly one pixel


def lit(img):
    rows, cols = np.nonzero(img[0])
    return sorted(set(rows.tolist())), sorted(set(cols.tolist()))


@pytest.mark.parametrize(
    ("range_m", "bearing_deg", "row", "col"),
    [
        (10.0, 0.0, 2, 59),  # dead ahead: the middle column
        (0.5, 0.0, 0, 59),  # row 0 is nearest
        (4.01, 0.0, 1, 59),
        (199.9, 0.0, 49, 59),
        (50.0, -120.0, 12, 0),  # port edge
        (50.0, 120.0, 12, 118),  # starboard edge, included
        (50.0, -119.0, 12, 0),
        (50.0, 119.0, 12, 118),
        (50.0, -90.0, 12, 14),  # floor((120 - 90) / (240 / 119)) = 14
        (50.0, 45.0, 12, 81),  # floor(165 / (240 / 119)) = 81
    ],
)
def test_pixel_of_a_point_pole(range_m, bearing_deg, row, col):
    r, c = pixel_index(range_m, math.radians(bearing_deg))
    assert (int(r), int(c)) == (row, col)
    img = render_radar(np.array([range_m]), np.array([math.radians(bearing_deg)]), TINY)
    assert img.shape == (1, 1, 50, 119) and img.dtype == np.uint8
    assert lit(img[0]) == ([row], [col])
    assert int(img.sum()) == 255


def test_pixel_edges_belong_to_the_farther_pixel():
    assert pixel_index(4.0, 0.0) == (1, 59)
    assert pixel_index(8.0, math.radians(-120.0 + 240.0 / 119.0 + 1e-9)) == (2, 1)


@pytest.mark.parametrize(
    ("range_m", "bearing_deg"),
    [
        (200.01, 0.0),
        (250.0, 10.0),
        (50.0, 120.5),
        (50.0, -121.0),
        (50.0, 180.0),
    ],
)
def test_out_of_range_or_view_is_black(range_m, bearing_deg):
    assert pixel_index(range_m, math.radians(bearing_deg)) == (-1, -1)
    img = render_radar(np.array([range_m]), np.array([math.radians(bearing_deg)]), TINY)
    assert int(img.max()) == 0


def test_box_size_follows_pole_radius_and_pixel_footprint():
    # R = 1 m at 10 m: range [9, 11] m → row 2; bearing ±asin(0.1) = ±5.74° → columns 56..62
    img = render_radar(np.array([10.0]), np.array([0.0]), 1.0)
    assert lit(img[0]) == ([2], list(range(56, 63)))
    assert int(img.sum()) == 255 * 7
    # R = 1 m at 8 m straddles a row edge: rows 1 and 2
    img = render_radar(np.array([8.0]), np.array([0.0]), 1.0)
    assert lit(img[0])[0] == [1, 2]
    # far away the pole is smaller than a pixel but still one pixel
    img = render_radar(np.array([150.0]), np.array([0.0]), 1.0)
    assert int(img.sum()) == 255


def test_box_at_the_edge_is_clipped_not_wrapped():
    img = render_radar(np.array([50.0]), np.array([math.radians(120.0)]), 1.0)
    assert lit(img[0]) == ([12], [118])
    img = render_radar(np.array([5.0]), np.array([math.radians(-119.0)]), 1.0)
    rows, cols = lit(img[0])
    assert cols[0] == 0 and max(cols) < 10 and rows == [1]


def test_batched_render_equals_one_by_one():
    rng = np.random.default_rng(0)
    r = rng.uniform(0.0, 220.0, 64)
    b = rng.uniform(-math.pi, math.pi, 64)
    batch = render_radar(r, b, 1.0)
    for i in range(64):
        np.testing.assert_array_equal(batch[i], render_radar(r[i : i + 1], b[i : i + 1], 1.0)[0])
    assert set(np.unique(batch).tolist()) <= {0, 255}


def test_several_obstacles_per_boat():
    img = render_radar(np.array([[10.0, 102.0]]), np.radians([[0.0, -60.0]]), TINY)
    rows, cols = np.nonzero(img[0, 0])
    assert sorted(zip(rows.tolist(), cols.tolist(), strict=True)) == [(2, 59), (25, 29)]


def test_clutter_is_off_by_default_and_needs_a_noise_source():
    cfg = RadarConfig(clutter_probability=0.05)
    with pytest.raises(ValueError, match="noise source"):
        render_radar(np.array([300.0]), np.array([0.0]), 1.0, cfg)
    noise = BoatNoise(1)
    noise.seed(np.arange(1), [3])
    img = render_radar(np.array([300.0]), np.array([0.0]), 1.0, cfg, noise)
    frac = np.count_nonzero(img) / img.size
    assert 0.03 < frac < 0.07
