"""usvsim.evaluation.stats: the Wilson score interval against published values and a second
implementation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.evaluation.stats import finite_mean, finite_median, proportion, wilson_interval


@pytest.mark.parametrize(
    ("k", "n", "lower", "upper"),
    [  # Newcombe (1998), Stat. Med. 17(8), Table I, method 3 (Wilson score, no correction)
        (81, 263, 0.2553, 0.3662),
        (15, 148, 0.0624, 0.1605),
        (0, 20, 0.0000, 0.1611),
        (1, 29, 0.0061, 0.1718),
    ],
)
def test_wilson_matches_newcombe_table(k: int, n: int, lower: float, upper: float) -> None:
    lo, hi = wilson_interval(k, n)
    assert (round(lo, 4), round(hi, 4)) == (lower, upper)


def _wilson_by_quadratic(k: int, n: int, z: float) -> tuple[float, float]:
    """Second implementation: the roots p of (p̂ − p)² = z² p (1 − p) / n."""
    p_hat = k / n
    a, b, c = 1 + z * z / n, -(2 * p_hat + z * z / n), p_hat * p_hat
    roots = np.roots([a, b, c]).real
    return float(roots.min()), float(roots.max())


@pytest.mark.parametrize(("k", "n"), [(0, 15), (7, 15), (15, 15), (199, 200), (3, 10)])
def test_wilson_equals_the_roots_of_the_score_equation(k: int, n: int) -> None:
    lo, hi = wilson_interval(k, n, confidence=0.95)
    ref = _wilson_by_quadratic(k, n, 1.959963984540054)
    assert lo == pytest.approx(max(ref[0], 0.0), abs=1e-12)
    assert hi == pytest.approx(min(ref[1], 1.0), abs=1e-12)


def test_wilson_all_successes_of_the_validation_set() -> None:
    # 15/15 validation episodes: the interval is [79.6 %, 100 %], not a point
    lo, hi = wilson_interval(15, 15)
    assert (round(lo, 4), hi) == (0.7961, 1.0)


def test_wilson_is_symmetric_under_swapping_successes_and_failures() -> None:
    lo, hi = wilson_interval(4, 17)
    lo2, hi2 = wilson_interval(13, 17)
    assert (lo, hi) == pytest.approx((1 - hi2, 1 - lo2), abs=1e-15)


def test_wilson_widens_with_confidence() -> None:
    lo90, hi90 = wilson_interval(6, 10, 0.90)
    lo99, hi99 = wilson_interval(6, 10, 0.99)
    assert lo99 < lo90 < 0.6 < hi90 < hi99


@pytest.mark.parametrize(
    ("k", "n", "conf"), [(3, 0, 0.95), (-1, 5, 0.95), (6, 5, 0.95), (1, 5, 1.0)]
)
def test_wilson_rejects_bad_input(k: int, n: int, conf: float) -> None:
    with pytest.raises(ValueError):
        wilson_interval(k, n, conf)


def test_proportion_formats_percent() -> None:
    p = proportion(14, 15)
    assert (p.successes, p.n, p.rate) == (14, 15, 14 / 15)
    assert p.format_percent() == "93.3 % [70.2, 98.8]"


def test_finite_mean_and_median_skip_nan_and_return_nan_when_empty() -> None:
    assert finite_mean([1.0, math.nan, 3.0]) == 2.0
    assert finite_median([5.0, math.nan, 1.0, 3.0, 10.0]) == 4.0
    assert math.isnan(finite_mean([math.nan])) and math.isnan(finite_median([]))


def test_difference_interval_matches_newcombe_and_is_antisymmetric() -> None:
    from usvsim.evaluation.stats import difference_interval

    lo, hi = difference_interval(56, 70, 48, 80)  # Newcombe 1998 (Stat. Med. 17), example (a)
    assert (round(lo, 4), round(hi, 4)) == (0.0524, 0.3339)
    back = difference_interval(48, 80, 56, 70)
    assert back == pytest.approx((-hi, -lo))
    assert difference_interval(52, 100, 64, 100)[1] > 0.0  # 52 vs 64 of 100: not different
    assert difference_interval(40, 100, 64, 100)[1] < 0.0  # 40 vs 64 of 100: different
