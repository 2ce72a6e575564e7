"""Scene radar degradation: each effect has the law the module docstring states, drawn per boat."""

from __future__ import annotations

import numpy as np
import pytest

from usvsim.task.scene_radar import (
    FRAME_DRAWS,
    RadarDegradation,
    RadarStreams,
    frame_draws,
    render_scene,
)
from usvsim.task.scene_radar_kernel import load_kernel

_KERNEL = load_kernel()

PIXELS = 50 * 119


def _quality(n: int, clutter=0.0, speckle=0.0, missed=0.0, noise=0.0) -> RadarDegradation:
    return RadarDegradation(*(np.full(n, float(x)) for x in (clutter, speckle, missed, noise)))


def _streams(n: int, seed: int = 0) -> np.ndarray:
    streams = RadarStreams(n)
    streams.seed(list(range(n)), [seed + i for i in range(n)])
    return streams.frame_keys(np.arange(n))


def _random_scenes(rng: np.random.Generator, n: int, j: int):
    rho = rng.uniform(0.0, 220.0, (n, j))
    phi = rng.uniform(-4.0, 4.0, (n, j))  # beyond ±π: wrapped
    r = np.where(rng.random((n, j)) < 0.3, 1.0, rng.uniform(0.5, 40.0, (n, j)))  # poles, islets
    ok = rng.random((n, j)) < 0.8
    q = RadarDegradation(
        *(np.where(rng.random(n) < 0.5, rng.uniform(0.0, x, n), 0.0) for x in (0.02, 0.5, 0.3, 60))
    )
    return rho, phi, r, ok, q


@pytest.mark.skipif(_KERNEL is None, reason="no C compiler: the radar kernel did not build")
def test_compiled_kernel_equals_the_numpy_path_bit_for_bit() -> None:
    rng = np.random.default_rng(1)
    for _ in range(4):
        rho, phi, r, ok, q = _random_scenes(rng, 128, 12)
        keys = _streams(128, int(rng.integers(2**62)))
        for quality, k in ((q, keys), (None, None)):
            fast = render_scene(rho, phi, r, ok, None, quality, k, backend="compiled")
            slow = render_scene(rho, phi, r, ok, None, quality, k, backend="numpy")
            np.testing.assert_array_equal(fast, slow)


def test_frames_of_a_stream_differ_and_restart_with_the_seed() -> None:
    streams = RadarStreams(3)
    streams.seed([0, 1, 2], [7, 7, 8])
    first = streams.frame_keys(np.arange(3))
    second = streams.frame_keys(np.arange(3))
    assert first[0] == first[1] != first[2]  # the key is the seed's, not the boat's
    assert np.all(first != second)
    # consecutive frames tile one SplitMix64 sequence: frame 1 starts 2**22 draws after frame 0
    np.testing.assert_array_equal(
        frame_draws(first[:1], FRAME_DRAWS, 5), frame_draws(second[:1], 0, 5)
    )
    streams.seed([0], [7])
    assert streams.frame_keys(np.arange(1))[0] == first[0]


def test_pixel_draws_are_uniform_and_uncorrelated_between_fields() -> None:
    keys = _streams(8, 123)
    h = frame_draws(keys, 0, PIXELS).ravel()
    fields = [((h >> np.uint64(s)) & np.uint64((1 << w) - 1)) / 2.0**w
              for s, w in ((0, 20), (20, 16), (36, 14), (50, 14))]  # fmt: skip
    for u in fields:
        assert u.mean() == pytest.approx(0.5, abs=0.005)  # 47,600 draws: σ 0.0013
        assert u.var() == pytest.approx(1 / 12, rel=0.02)
    corr = np.corrcoef(np.stack(fields))
    assert np.abs(corr - np.eye(4)).max() < 0.02


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
        _streams(n)[3:4],
    )  # fmt: skip
    np.testing.assert_array_equal(batch[3], alone[0])
    assert not np.array_equal(batch[0], batch[1])  # different streams, different images


def test_without_a_compiler_the_numpy_path_draws_the_same_images(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    rho, phi, r, ok, q = _random_scenes(np.random.default_rng(5), 16, 6)
    keys = _streams(16, 9)
    want = render_scene(rho, phi, r, ok, None, q, keys, backend="numpy")
    load_kernel.cache_clear()
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", "/nonexistent")
    monkeypatch.setenv("USVSIM_CACHE_DIR", "/nonexistent-cache")  # nothing cached to load
    try:
        assert load_kernel() is None
        np.testing.assert_array_equal(render_scene(rho, phi, r, ok, None, q, keys), want)
        with pytest.raises(ValueError, match="did not build"):
            render_scene(rho, phi, r, ok, None, q, keys, backend="compiled")
    finally:
        load_kernel.cache_clear()
