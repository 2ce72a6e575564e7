"""Small statistics for judging helmsmen: success proportions with Wilson score intervals.

Wilson score interval (Wilson 1927, "Probable inference, the law of succession, and statistical
inference", JASA 22(158); Newcombe 1998, "Two-sided confidence intervals for the single
proportion: comparison of seven methods", Stat. Med. 17(8), method 3). For k successes in n
trials, p̂ = k / n and z the standard-normal quantile of (1 + confidence) / 2::

    centre = (p̂ + z²/(2n)) / (1 + z²/n)
    half   = z / (1 + z²/n) · √(p̂ (1 − p̂) / n + z²/(4n²))
    [centre − half, centre + half]

Unlike the Wald interval p̂ ± z √(p̂(1 − p̂)/n) it stays inside [0, 1] and does not collapse to a
point at k = 0 or k = n — which matters here: a helmsman that succeeds in 15/15 validation
episodes has a 95 % interval of [79.6 %, 100 %], not [100 %, 100 %].
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from statistics import NormalDist

__all__ = [
    "Proportion",
    "difference_interval",
    "finite_mean",
    "finite_median",
    "proportion",
    "wilson_interval",
]


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval (lower, upper) of a binomial proportion (module docstring).

    >>> [round(x, 4) for x in wilson_interval(81, 263)]  # Newcombe (1998), Table I
    [0.2553, 0.3662]
    >>> [round(x, 4) for x in wilson_interval(15, 15)]
    [0.7961, 1.0]
    """
    if isinstance(successes, bool) or isinstance(n, bool):
        raise TypeError("successes and n must be integers, not bools")
    if n < 1 or not 0 <= successes <= n:
        raise ValueError(f"need n ≥ 1 and 0 ≤ successes ≤ n, got {successes}/{n}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must lie in (0, 1), got {confidence}")
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2.0 * n)) / denom
    half = z / denom * math.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n))
    # clamp rounding at k = 0 or n (the exact bounds are 0 and 1 there)
    lower = 0.0 if successes == 0 else max(0.0, centre - half)
    upper = 1.0 if successes == n else min(1.0, centre + half)
    return lower, upper


def difference_interval(
    k1: int, n1: int, k2: int, n2: int, confidence: float = 0.95
) -> tuple[float, float]:
    """Interval of the difference p̂₁ − p̂₂ of two independent proportions, built from their
    Wilson intervals (Newcombe 1998, "Interval estimation for the difference between independent
    proportions: comparison of eleven methods", Stat. Med. 17(8), method 10). Two success rates
    differ at ``confidence`` when the interval excludes 0.

    >>> [round(x, 4) for x in difference_interval(56, 70, 48, 80)]  # Newcombe's example (a)
    [0.0524, 0.3339]
    """
    p1, p2 = k1 / n1, k2 / n2
    l1, u1 = wilson_interval(k1, n1, confidence)
    l2, u2 = wilson_interval(k2, n2, confidence)
    d = p1 - p2
    return d - math.hypot(p1 - l1, u2 - p2), d + math.hypot(u1 - p1, p2 - l2)


@dataclass(frozen=True)
class Proportion:
    """k successes in n trials with a Wilson interval at ``confidence``."""

    successes: int
    n: int
    rate: float  # k / n
    lower: float  # Wilson lower bound
    upper: float  # Wilson upper bound
    confidence: float

    def format_percent(self) -> str:
        """``"93.3 % [70.2, 98.8]"``: the rate and its interval in percent."""
        return f"{100 * self.rate:.1f} % [{100 * self.lower:.1f}, {100 * self.upper:.1f}]"


def proportion(successes: int, n: int, confidence: float = 0.95) -> Proportion:
    """:class:`Proportion` of ``successes`` out of ``n`` with its Wilson interval."""
    lower, upper = wilson_interval(successes, n, confidence)
    return Proportion(successes, n, successes / n, lower, upper, confidence)


def _finite(values: Iterable[float]) -> list[float]:
    return sorted(v for v in (float(x) for x in values) if math.isfinite(v))


def finite_mean(values: Iterable[float]) -> float:
    """Mean of the finite values; NaN if there are none (no warning, unlike ``np.nanmean``)."""
    v = _finite(values)
    return math.fsum(v) / len(v) if v else math.nan


def finite_median(values: Iterable[float]) -> float:
    """Median of the finite values; NaN if there are none."""
    v = _finite(values)
    if not v:
        return math.nan
    mid = len(v) // 2
    return v[mid] if len(v) % 2 else 0.5 * (v[mid - 1] + v[mid])
