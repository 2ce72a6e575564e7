"""Scene radar degradation: each effect has the law the module docstring states, drawn per boat."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.task.scene_radar import (
    RadarDegradation,
    RadarStreams,
    bernoulli_positions,
    render_scene,
)

PIXELS = 50 * 119


def _quality(n: int, clutter=0.0, speckle=0.0, missed=0.0, noise=0.0) -> RadarDegradation:
    return RadarDegradation(*(np.full(n, float(x)) for x in (clutter, speckle, missed, noise)))


def _streams(n: int, seed: int = 0) -> list[np.random.Generator | None]:
    streams = RadarStreams(n)
    streams.seed(list(range(n)), [seed + i for i in range(n)])
    return streams.rows(np.arange(n))


@pytest.mark.parametrize("p", [0.001, 0.02, 0.5, 1.0])
def test_bernoulli_positions_have_the_law_of_independent_trials(p: float) -> None:
    g = np.random.default_rng(3)
    counts = np.zeros(PIXELS)
    sizes = []
    for _ in range(400):
        at = bernoulli_positions(g, PIXELS, p)
        assert np.all(np.diff(at) > 0) and (at.size == 0 or (at[0] >= 0 and at[-1] < PIXELS))
        counts[at] += 1
        sizes.append(at.size)
    mean, var = PIXELS * p, PIXELS * p * (1 - p)
    assert abs(np.mean(sizes) - mean) <= 4 * math.sqrt(var / 400) + 1e-9  # Binomial(P, p) count
    if 0 < p < 1:
        assert np.var(sizes) == pytest.approx(var, rel=0.25)
        # no position is favoured: first and second half of the image equally often
        half = PIXELS // 2
        assert counts[:half].sum() / counts.sum() == pytest.approx(half / PIXELS, abs=0.02)


def test_clutter_lights_the_stated_fraction_at_uniform_intensity() -> None:
    n, p = 64, 0.01
    empty = np.zeros((n, 0))
    img = render_scene(
        empty, empty, empty, empty.astype(bool), None, _quality(n, clutter=p), _streams(n)
    )
    lit = img[:, 0] > 0
    assert lit.mean() == pytest.approx(p, rel=0.1)  # 3808 expected clutter pixels
    assert img[:, 0][lit].mean() == pytest.approx(127.0, abs=6.0)  # 255 U, truncated


def test_speckle_scales_lit_pixels_only_and_noise_adds_everywhere() -> None:
    n = 16
    rho, phi, r = np.full((n, 1), 60.0), np.zeros((n, 1)), np.full((n, 1), 20.0)
    ok = np.ones((n, 1), bool)
    clean = render_scene(rho, phi, r, ok)[:, 0]
    speckled = render_scene(rho, phi, r, ok, None, _quality(n, speckle=0.5), _streams(n))[:, 0]
    lit = clean > 0
    assert np.all(speckled[~lit] == 0)
    # 255 (1 - 0.5 U): mean 191.25, truncated to an integer: about 190.75; within [127, 255]
    assert speckled[lit].mean() == pytest.approx(190.75, abs=2.0)
    assert speckled[lit].min() >= 127
    noisy = render_scene(rho, phi, r, ok, None, _quality(n, noise=40.0), _streams(n))[:, 0]
    assert np.all(noisy[lit] == 255)  # saturated returns stay saturated
    assert noisy[~lit].mean() == pytest.approx(19.5, abs=0.5)  # 40 U truncated


def test_missed_returns_drop_whole_discs_at_the_stated_rate() -> None:
    n = 400
    rho, phi, r = np.full((n, 1), 60.0), np.zeros((n, 1)), np.full((n, 1), 5.0)
    img = render_scene(
        rho, phi, r, np.ones((n, 1), bool), None, _quality(n, missed=0.3), _streams(n)
    )
    shown = img[:, 0].reshape(n, -1).any(axis=1)
    assert 1 - shown.mean() == pytest.approx(0.3, abs=0.08)


def test_a_boats_image_depends_on_its_own_stream_only() -> None:
    n = 5
    q = _quality(n, clutter=0.01, speckle=0.3, missed=0.2, noise=10.0)
    rho, phi = np.full((n, 2), 50.0), np.tile([0.0, 0.4], (n, 1))
    r, ok = np.full((n, 2), 8.0), np.ones((n, 2), bool)
    batch = render_scene(rho, phi, r, ok, None, q, _streams(n))
    alone = render_scene(
        rho[3:4], phi[3:4], r[3:4], ok[3:4], None, _quality(1, 0.01, 0.3, 0.2, 10.0),
        [np.random.default_rng(3)],
    )  # fmt: skip
    np.testing.assert_array_equal(batch[3], alone[0])
    assert not np.array_equal(batch[0], batch[1])  # different streams, different images
