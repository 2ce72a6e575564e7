"""Generalised advantage estimation, GAE(γ, λ) (Schulman et al. 2016, Eq. 16), for N envs.

Arrays are (T, N): T steps of N environments. Step t of env n is the transition
(s_t, a_t, r_t, s'_t), where s'_t is the *true* next state:

- the episode goes on: s'_t = s_{t+1};
- the episode ends at t (``episode_end``): s'_t is its final observation, and s_{t+1} (if any)
  already belongs to the next episode.

``next_values[t]`` = V(s'_t) is given by the caller
(:func:`learning.algorithms.rollout.attach_values`), so the two ways an episode ends stay apart:

    δ_t = r_t + γ (1 − terminated_t) V(s'_t) − V(s_t)          TD error
    A_t = δ_t + γ λ (1 − episode_end_t) A_{t+1}                 A_T = 0

On *termination* the next state is absorbing (no bootstrap); on *truncation* (a time limit)
the episode could have gone on, so V(s'_t) bootstraps it (Pardo et al. 2018). Either way the
recursion stops at the episode's end. The λ-return target of the critic is A_t + V(s_t).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["gae"]

F32 = NDArray[np.float32]


def gae(
    rewards: NDArray[np.floating],
    values: NDArray[np.floating],
    next_values: NDArray[np.floating],
    terminated: NDArray[np.bool_],
    episode_end: NDArray[np.bool_],
    gamma: float,
    lam: float,
) -> tuple[F32, F32]:
    """Advantages A_t and λ-returns A_t + V(s_t), both (T, N) float32 (module docstring).

    ``episode_end`` = terminated | truncated. Float64 inside.

    >>> r = np.array([[1.0], [1.0]]); v = np.zeros((2, 1)); nv = np.array([[0.0], [10.0]])
    >>> end = np.array([[False], [True]])  # truncated at t = 1: bootstrap V(s') = 10
    >>> adv, ret = gae(r, v, nv, np.zeros((2, 1), bool), end, gamma=0.5, lam=1.0)
    >>> adv[:, 0].tolist()
    [4.0, 6.0]
    """
    shape = rewards.shape
    for name, a in (
        ("values", values),
        ("next_values", next_values),
        ("terminated", terminated),
        ("episode_end", episode_end),
    ):
        if a.shape != shape:
            raise ValueError(f"{name} has shape {a.shape}, rewards {shape}")
    not_terminal = 1.0 - terminated.astype(np.float64)
    carry = 1.0 - episode_end.astype(np.float64)
    delta = rewards + gamma * not_terminal * next_values - values
    adv = np.zeros(shape, dtype=np.float64)
    running = np.zeros(shape[1:], dtype=np.float64)
    for t in range(shape[0] - 1, -1, -1):
        running = delta[t] + gamma * lam * carry[t] * running
        adv[t] = running
    return adv.astype(np.float32), (adv + values).astype(np.float32)
