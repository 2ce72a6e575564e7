"""Rewards of the pole-avoidance task (for RL), computed from the TRUE distances.

The study's handcrafted reward (Vedeler 2019) in the corrected form of
``shared/reference/table-4-1.md``::

    r      = r_pole + r_goal
    r_pole = -w_pole · exp(-½ (d_pole / σ_pole)²),   w_pole = 2, σ_pole = 5 m     ∈ (-2, 0)
    r_goal = -w_goal + w_goal · exp(-½ (d_goal / σ_goal)²),  w_goal = 1, σ_goal = 100 m  ∈ (-1, 0)

(the study's 1/(σ√(2π)) factor contradicts its stated ranges, and its goal term used the pole's
position: a typo; usvsim uses the forms above).

Pluggable: anything matching :class:`RewardFunction` — a callable from the true distances to a
:class:`RewardTerms` — can be passed to the environments; each term is reported in ``info``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "GaussianReward",
    "GoalAimReward",
    "RewardFunction",
    "RewardTerms",
    "SafetyMarginReward",
    "SuccessReward",
]

FloatArray = NDArray[np.float64]


def _require_positive(term: object, *names: str) -> None:
    """Raise ``ValueError`` naming the first of ``term``'s fields ``names`` that is not finite
    and > 0."""
    for name in names:
        value = getattr(term, name)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{type(term).__name__}.{name} must be finite and > 0, got {value!r}")


@dataclass(frozen=True)
class RewardTerms:
    """The two terms of the reward for N boats, each (N,); the reward is their sum."""

    pole: FloatArray
    goal: FloatArray

    @property
    def total(self) -> FloatArray:
        """``pole + goal`` (N,)."""
        return self.pole + self.goal


class RewardFunction(Protocol):
    """A reward from the true distances (m, each (N,)) at the end of a decision period."""

    def __call__(self, d_pole_m: FloatArray, d_goal_m: FloatArray) -> RewardTerms: ...


@dataclass(frozen=True)
class GaussianReward:
    """The study's Gaussian reward, corrected (module docstring).

    >>> terms = GaussianReward()(np.array([0.0, 5.0]), np.array([0.0, 100.0]))
    >>> terms.pole.round(4).tolist(), terms.goal.round(4).tolist()
    ([-2.0, -1.2131], [0.0, -0.3935])
    """

    pole_weight: float = 2.0  # study: r_pole ∈ (-2, 0)
    pole_sigma_m: float = 5.0  # m; study
    goal_weight: float = 1.0  # study: r_goal ∈ (-1, 0)
    goal_sigma_m: float = 100.0  # m; study

    def __post_init__(self) -> None:
        _require_positive(self, "pole_weight", "pole_sigma_m", "goal_weight", "goal_sigma_m")

    def __call__(self, d_pole_m: FloatArray, d_goal_m: FloatArray) -> RewardTerms:
        pole = -self.pole_weight * np.exp(-0.5 * (np.asarray(d_pole_m) / self.pole_sigma_m) ** 2)
        goal = self.goal_weight * (
            np.exp(-0.5 * (np.asarray(d_goal_m) / self.goal_sigma_m) ** 2) - 1.0
        )
        return RewardTerms(pole=pole, goal=goal)


@dataclass(frozen=True)
class SafetyMarginReward:
    """A per-decision penalty for coming within the success rule's safety distance (usvsim's
    own term, not the study's; off unless an env is given one).

    The study's pole term sees the nearest obstacle only at the end of each 2 s decision period
    and is weak at the safety distance (-0.33 at 10 m with σ_pole = 5 m), so a policy can pass
    an obstacle at 4-9 m, mid-period, almost unpaid, and still reach the goal: an episode the
    success rule (never closer than the safety distance) counts as failed. This term sees the
    period's nearest pole-equivalent distance over every plant step, ``d_min`` (m), and pays::

        r_safe = -w · clip((d_safe + m - d_min) / m, 0, 1)

    0 beyond ``d_safe + m``, a linear ramp over the margin ``m``, and -w at and inside the
    safety distance ``d_safe`` (the scenario's ``safety_distance_m``).

    >>> SafetyMarginReward()(np.array([20.0, 12.5, 10.0, 3.0]), 10.0).round(2).tolist()
    [-0.0, -1.0, -2.0, -2.0]
    """

    weight: float = 2.0  # the study's pole weight: the scale of one unsafe period
    margin_m: float = 5.0  # m; the study's σ_pole

    def __post_init__(self) -> None:
        _require_positive(self, "weight", "margin_m")

    def __call__(self, period_nearest_m: FloatArray, safety_distance_m: float) -> FloatArray:
        """The penalty (N,) of N boats whose period came within ``period_nearest_m`` (N,) m of
        an obstacle (``inf``: none), for a safety distance ``safety_distance_m`` (m)."""
        d = np.asarray(period_nearest_m, dtype=np.float64)
        ramp = np.clip((safety_distance_m + self.margin_m - d) / self.margin_m, 0.0, 1.0)
        return -self.weight * ramp


@dataclass(frozen=True)
class SuccessReward:
    """A one-off payment at the decision an episode ends in success (usvsim's own term, not the
    study's; off unless an env is given one).

    The study's goal term is flat near the goal (``r_goal`` = -0.006 a decision at 11 m, 0 at the
    goal), and the time limit is a truncation, so a policy that passes the goal 11-15 m off and
    then circles it outside the 10 m goal circle is paid almost as well as one that enters it:
    a *goal orbit*, the most common failure of the learned traffic helmsmen on the stress suite's
    obstacle sets (``docs/notes/2026-12-traffic.md``). This term pays::

        r_success = w · 1[success]

    once, on the terminating decision of an episode that reached the goal without a collision
    and never came within the safety distance (the success rule itself). Under the fixed reward
    horizon it is added after the horizon's scaling (not multiplied by the decisions left), so
    arriving k decisions later costs ``w (1 - γ^k)`` of it through discounting alone.

    >>> SuccessReward()(np.array([True, False])).tolist()
    [2.0, 0.0]
    """

    weight: float = 2.0  # the study's pole weight: one decision at the pole costs as much

    def __post_init__(self) -> None:
        _require_positive(self, "weight")

    def __call__(self, is_success: NDArray[np.bool_]) -> FloatArray:
        """The payment (N,) of N boats, ``is_success`` (N,) True where the decision ended an
        episode in success."""
        return self.weight * np.asarray(is_success, dtype=np.float64)


@dataclass(frozen=True)
class GoalAimReward:
    """A per-decision penalty for pointing off the goal near it (usvsim's own term, not the
    study's; off unless an env is given one).

    The study's goal term depends on the range alone and is nearly flat near the goal (-0.006 a
    decision at 11 m), so it hardly pays for where the bow points in the last 100 m. Fine-tuned
    with the COLREG terms, the traffic policies learned a blanket starboard habit that shows as a
    dead zone there: with a clean radar image and the goal 5-10° to port at 15-40 m they hold
    course or turn to starboard, while a goal as far to starboard gets a full turn
    (``benchmarks/goal_response.py``), and they come to the goal with it to port, the goal orbits'
    onset (``docs/notes/2026-12-traffic.md``). This term pays, with β the goal's bearing off the
    heading (rad) and ``d`` its range (m) at the end of the decision period::

        r_aim = -w · (1 - cos β) · 1[d < R]

    0 when pointed at the goal, -w/2 at 60° off, -w abeam; only within ``R`` of the goal, where
    the approach is flown (beyond it avoidance may need any heading).

    >>> b, d = np.radians([0.0, 60.0, -90.0, 60.0]), np.array([50.0, 50.0, 50.0, 150.0])
    >>> GoalAimReward()(b, d).round(3).tolist()
    [-0.0, -0.5, -1.0, 0.0]
    """

    weight: float = 1.0  # the study's goal weight: abeam near the goal costs a far decision's
    range_m: float = 100.0  # m; the study's σ_goal

    def __post_init__(self) -> None:
        _require_positive(self, "weight", "range_m")

    def __call__(self, goal_bearing_rad: FloatArray, d_goal_m: FloatArray) -> FloatArray:
        """The penalty (N,) of N boats whose goal lies ``goal_bearing_rad`` (N,) rad off their
        heading at ``d_goal_m`` (N,) m."""
        near = np.asarray(d_goal_m, dtype=np.float64) < self.range_m
        off = 1.0 - np.cos(np.asarray(goal_bearing_rad, dtype=np.float64))
        return np.where(near, -self.weight * off, 0.0)
