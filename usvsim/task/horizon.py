"""Reward horizon of the pole-avoidance task: per episode, or the study's fixed horizon.

``reward_horizon="episode"`` (default) returns the task's reward as it is: an episode ends at
the goal, at a collision or on leaving the area, and adds nothing after its end. This is what
evaluation uses.

``reward_horizon="fixed"`` gives a trainer the study's fixed-length episodes (Vedeler 2019 ran
every episode for the whole time limit). Every reward of the study is negative, so with early
termination a collision *ends the penalties*: trained on the plain reward, TRPO learns to ram
the pole (0/15 validation after 90 iterations, episodes of ~12 decisions; SB3 PPO through
``gymnasium.make``: 0, 0, 12, 0, 0, 0 of 15 over 63k steps). With the fixed horizon a
terminating step's reward also carries the discounted return of the decisions left until the
time limit, the boat staying where the episode ended (at the pole about −2.5 per decision, at
the goal about −0.005)::

    r'_t = r_t + r_t · Σ_{k=1}^{m} γ^k = r_t · (1 + γ (1 − γ^m) / (1 − γ)),   m = K − (t + 1)

(K decisions in the time limit, t + 1 decisions taken). Leaving the area is treated the same
way, as an absorbing state, and reported as ``terminated`` instead of ``truncated``: otherwise
a trainer would bootstrap from the value of states beyond the area's edge, which no rollout
ever continues from. Only the time limit stays a truncation. ``gamma`` must be the trainer's
discount factor (0.99: usvsim's setups and Stable-Baselines3's default).
"""

from __future__ import annotations

from typing import Literal, cast, get_args

import numpy as np
from numpy.typing import NDArray

from usvsim.task.scenario import Scenario

__all__ = ["REWARD_HORIZONS", "RewardHorizon", "apply_reward_horizon", "parse_reward_horizon"]

RewardHorizon = Literal["episode", "fixed"]
REWARD_HORIZONS: tuple[str, ...] = get_args(RewardHorizon)


def parse_reward_horizon(horizon: object, gamma: float) -> RewardHorizon:
    """``horizon`` as a :data:`RewardHorizon`, checked together with its discount ``gamma``.

    Raises
    ------
    ValueError
        If ``horizon`` is not one of :data:`REWARD_HORIZONS` or ``gamma`` is outside [0, 1).
    """
    if horizon not in REWARD_HORIZONS:
        raise ValueError(f"reward_horizon must be one of {REWARD_HORIZONS}, got {horizon!r}")
    if not 0.0 <= gamma < 1.0:
        raise ValueError(f"gamma must lie in [0, 1), got {gamma}")
    return cast(RewardHorizon, horizon)


def apply_reward_horizon(
    horizon: RewardHorizon,
    gamma: float,
    scenario: Scenario,
    reward: NDArray[np.float64],
    terminated: NDArray[np.bool_],
    truncated: NDArray[np.bool_],
    out_of_area: NDArray[np.bool_],
    time_s: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
    """Reward and flags of one batched step (each (N,)) under ``horizon`` (module docstring).

    ``time_s`` is each episode's time at the step's end (s); the inputs are not modified.

    >>> sc = Scenario()
    >>> r, te, tr = apply_reward_horizon("fixed", 0.5, sc, np.array([-1.0, -1.0]),
    ...     np.array([True, False]), np.array([False, False]), np.array([False, False]),
    ...     np.array([148.0, 10.0]))
    >>> r.tolist(), te.tolist()  # one decision left: -1 · (1 + 0.5)
    ([-1.5, -1.0], [True, False])
    """
    if horizon == "episode":
        return reward, terminated, truncated
    left = out_of_area & truncated
    if np.any(left):
        terminated, truncated = terminated | left, truncated & ~left
    if np.any(terminated):
        reward = np.array(reward, dtype=np.float64)
        decisions = np.rint(time_s / scenario.decision_period_s)
        m = np.maximum(scenario.max_decisions - decisions, 0.0)[terminated]
        reward[terminated] *= 1.0 + gamma * (1.0 - gamma**m) / (1.0 - gamma)
    return reward, terminated, truncated
