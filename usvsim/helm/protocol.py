"""The Helmsman protocol: anything that steers N boats from their observations.

A *helmsman* is a learned policy, a classical baseline, or a person behind the MAVLink bridge.
It is reset before a set of episodes and then asked for an action every decision period (2 s).
This module holds the protocol and the two sanity helmsmen; :mod:`usvsim.helm.registry` finds
every helmsman by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from usvsim.task.batch import N_CATEGORIES, ActionKind

__all__ = ["Helmsman", "RandomHelmsman", "StraightAheadHelmsman"]


@runtime_checkable
class Helmsman(Protocol):
    """Steers N boats: ``reset(n)`` before the episodes start, then ``act`` every 2 s.

    ``act`` receives the batched observation (leading axis N) and returns batched actions of the
    environment's action space: (N, 1) floats in [-1, 1] (gaussian) or (N,) ints (categorical).
    """

    def reset(self, n_boats: int) -> None: ...

    def act(self, observation: Any) -> NDArray[Any]: ...


@dataclass
class StraightAheadHelmsman:
    """Never changes the heading: the sanity baseline that must hit the pole."""

    action: ActionKind = "gaussian"

    def reset(self, n_boats: int) -> None:
        self._n = n_boats

    def act(self, observation: Any) -> NDArray[Any]:
        if self.action == "categorical":
            return np.full(self._n, (N_CATEGORIES - 1) // 2, dtype=np.int64)
        return np.zeros((self._n, 1), dtype=np.float32)


@dataclass
class RandomHelmsman:
    """Uniformly random actions from a seeded generator (re-seeded on every ``reset``)."""

    action: ActionKind = "gaussian"
    seed: int = 0

    def reset(self, n_boats: int) -> None:
        self._n = n_boats
        self._rng = np.random.default_rng(self.seed)

    def act(self, observation: Any) -> NDArray[Any]:
        if self.action == "categorical":
            return self._rng.integers(N_CATEGORIES, size=self._n)
        return self._rng.uniform(-1.0, 1.0, (self._n, 1)).astype(np.float32)
