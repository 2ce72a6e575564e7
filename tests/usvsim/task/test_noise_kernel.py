"""The compiled per-boat noise streams equal NumPy's ``default_rng(seed).standard_normal``."""

import numpy as np
import pytest

from usvsim.task.noise_kernel import load_kernel, pcg64_states
from usvsim.task.scenario import BoatNoise

kernel = load_kernel()
needs_kernel = pytest.mark.skipif(kernel is None, reason="no C compiler or no libnpyrandom")


@needs_kernel
def test_seeding_equals_numpy_at_the_word_edges_and_at_random():
    rng = np.random.default_rng(5)
    seeds = [0, 1, 2**32 - 1, 2**32, 2**63 - 1, 2**64 - 1]
    seeds += [int(x) for x in rng.integers(0, 2**63, 100)]
    states = np.zeros((len(seeds), 4), dtype=np.uint64)
    assert kernel is not None
    kernel.seed(np.arange(len(seeds)), seeds, states)
    np.testing.assert_array_equal(states, pcg64_states(seeds))


@needs_kernel
def test_a_million_numbers_equal_numpy_wedges_and_tail_included():
    assert kernel is not None
    seeds = [3, 2**40 + 9]
    states = pcg64_states(seeds)
    got = np.concatenate([kernel.draw(np.arange(2), states, m) for m in (1, 499_999, 500_000)], 1)
    ref = np.stack([np.random.default_rng(s).standard_normal(1_000_000) for s in seeds])
    np.testing.assert_array_equal(got, ref)
    # the slow paths ran: numbers beyond the ziggurat's base (r = 3.654) come from its tail
    assert (np.abs(got) > 3.66).sum() > 100


@needs_kernel
def test_boats_in_any_order_and_subset_draw_their_own_streams():
    assert kernel is not None
    seeds = [11, 12, 13, 14, 15, 16]
    states = pcg64_states(seeds)
    first = kernel.draw(np.array([4, 0, 5, 2, 1]), states, 9)  # lanes of four and a rest
    second = kernel.draw(np.arange(6), states, 3)
    for row, boat in enumerate([4, 0, 5, 2, 1]):
        ref = np.random.default_rng(seeds[boat]).standard_normal(12)
        np.testing.assert_array_equal(np.concatenate([first[row], second[boat]]), ref)
    np.testing.assert_array_equal(second[3], np.random.default_rng(14).standard_normal(3))


@needs_kernel
def test_seeds_beyond_64_bits_use_numpys_seeding_and_bad_seeds_are_numpys_errors():
    noise = BoatNoise(2, backend="compiled")
    noise.seed(np.arange(2), [2**70 + 5, 8])
    ref = np.stack([np.random.default_rng(s).standard_normal(5) for s in (2**70 + 5, 8)])
    np.testing.assert_array_equal(noise.standard_normal((2, 5)), ref)
    with pytest.raises(ValueError):
        noise.seed(np.arange(1), [-1])
    for backend in ("compiled", "numpy"):
        with pytest.raises(TypeError):  # NumPy's seeding takes integers only
            BoatNoise(1, backend=backend).seed(np.arange(1), [1.5])  # type: ignore[list-item]


def test_unseeded_boats_and_a_bad_backend_are_reported():
    with pytest.raises(ValueError, match="backend must be 'auto', 'compiled' or 'numpy'"):
        BoatNoise(2, backend="fast")  # type: ignore[arg-type]
    for backend in ("numpy", "auto"):
        noise = BoatNoise(2, backend=backend)  # type: ignore[arg-type]
        noise.seed(np.array([0]), [1])
        with pytest.raises(RuntimeError, match="boat 1 has no seeded stream"):
            noise.standard_normal((2, 3))


def test_draws_below_and_above_the_threads_threshold_are_each_boats_numpy_stream():
    # the kernel runs its boats in one thread below 65,536 numbers (waking a second thread costs
    # more than it saves there) and in OpenMP threads above: both give every boat its own stream
    for n, m in ((256, 80), (820, 80)):  # 20,480 and 65,600 numbers
        noise = BoatNoise(n, backend="compiled")
        noise.seed(np.arange(n), list(range(n)))
        got = noise.standard_normal((n, m))
        for i in (0, 1, n // 2, n - 1):
            np.testing.assert_array_equal(got[i], np.random.default_rng(i).standard_normal(m))


def test_a_boat_left_unseeded_is_reported_after_others_are_reseeded():
    noise = BoatNoise(3, backend="compiled")
    noise.seed(np.array([0, 2]), [1, 2])
    noise.seed(np.array([0]), [5])
    with pytest.raises(RuntimeError, match="boat 1 has no seeded stream"):
        noise.standard_normal((3, 2))
    noise.seed(np.array([1]), [3])  # now every boat has a stream
    np.testing.assert_array_equal(
        noise.standard_normal((3, 2))[1], np.random.default_rng(3).standard_normal(2)
    )


def test_without_the_kernel_auto_falls_back_and_compiled_says_why(monkeypatch):
    import usvsim.task.scenario as scenario

    monkeypatch.setattr(scenario, "load_noise_kernel", lambda: None)
    noise = BoatNoise(1)
    noise.seed(np.arange(1), [4])
    ref = np.random.default_rng(4).standard_normal(6)
    np.testing.assert_array_equal(noise.standard_normal((1, 6))[0], ref)
    with pytest.raises(RuntimeError, match="compiled noise kernel is unavailable"):
        BoatNoise(1, backend="compiled")
