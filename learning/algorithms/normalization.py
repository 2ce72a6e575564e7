"""Observation normalisation: running mean/std for vectors, a fixed scale for images.

=====================================  ===================================================
observation part                       normalised as
=====================================  ===================================================
``Box`` float vector (positional, goal)  ``clip((x - μ) / sqrt(σ² + ε), -clip, clip)``, μ and σ²
                                       running statistics over every observation seen
``Box`` uint8 image (radar)            ``x / 255`` (a fixed scale: no statistics to drift)
``Dict``                               each key as above
``Box`` scene vector, ``scaling="scene"``  fixed constants, empty slots all 0
                                       (:func:`usvsim.task.observations.standardize_scene`):
                                       a slot that is rarely filled has a tiny running σ, and
                                       its first obstacle would read as ±clip
=====================================  ===================================================

The running statistics use the parallel update of Chan, Golub and LeVeque (1979), in float64,
so that a batch of any size merges exactly with the statistics so far. Their state is a plain
dict of arrays (:meth:`ObservationNormalizer.state_dict`) saved with the model: a policy's inputs
mean the same thing when it is loaded again.

When the statistics change is the trainer's choice; :mod:`learning.algorithms.trpo` updates them
between iterations, so that within one iteration the policy is one fixed function.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from usvsim.task.observations import standardize_scene

__all__ = ["SCALINGS", "ObservationNormalizer", "RunningMeanStd", "is_image_space"]

SCALINGS = ("running", "scene")  # ObservationNormalizer scaling of vector parts

Obs = NDArray[Any] | dict[str, NDArray[Any]]


def is_image_space(space: spaces.Space) -> bool:
    """True for a ``Box`` of uint8 with shape (C, H, W): an image fed to a CNN."""
    return isinstance(space, spaces.Box) and space.dtype == np.uint8 and len(space.shape) == 3


class RunningMeanStd:
    """Running mean and variance of vectors of shape ``shape`` (float64).

    >>> rms = RunningMeanStd((1,))
    >>> rms.update(np.array([[1.0], [2.0]])); rms.update(np.array([[3.0], [4.0], [5.0]]))
    >>> float(rms.mean[0]), float(rms.var[0]), rms.count
    (3.0, 2.0, 5.0)
    """

    def __init__(self, shape: tuple[int, ...]) -> None:
        self.shape = shape
        self.mean = np.zeros(shape, dtype=np.float64)
        self.var = np.ones(shape, dtype=np.float64)
        self.count = 0.0

    def update(self, x: NDArray[Any]) -> None:
        """Merge a batch ``x`` of shape (B, *shape) into the statistics (population variance)."""
        x = np.asarray(x, dtype=np.float64).reshape((-1, *self.shape))
        if not np.isfinite(x).all():
            raise ValueError("non-finite observation: refusing to update the running statistics")
        n = float(x.shape[0])
        if n == 0:
            return
        self.merge(x.mean(axis=0), x.var(axis=0), n)

    def merge(self, mean: NDArray[Any], var: NDArray[Any], n: float) -> None:
        """Merge a batch given by its mean, population variance and count (Chan, Golub and
        LeVeque 1979): what :meth:`update` does with the rows, for callers that hold only the
        moments (a batch on a torch device: only they leave it)."""
        mean, var = np.asarray(mean, dtype=np.float64), np.asarray(var, dtype=np.float64)
        if not (np.isfinite(mean).all() and np.isfinite(var).all()):
            raise ValueError("non-finite observation: refusing to update the running statistics")
        if n == 0:
            return
        if self.count == 0:
            self.mean, self.var, self.count = mean.copy(), var.copy(), float(n)
            return
        total = self.count + n
        delta = mean - self.mean
        m2 = self.var * self.count + var * n + delta**2 * self.count * n / total
        self.mean = self.mean + delta * n / total
        self.var = m2 / total
        self.count = total

    def state_dict(self) -> dict[str, Any]:
        return {"mean": self.mean.copy(), "var": self.var.copy(), "count": self.count}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        mean = np.asarray(state["mean"], dtype=np.float64)
        if mean.shape != self.shape:
            raise ValueError(
                f"normaliser shape mismatch: saved {mean.shape}, expected {self.shape}"
            )
        self.mean = mean.copy()
        self.var = np.asarray(state["var"], dtype=np.float64).copy()
        self.count = float(state["count"])


class ObservationNormalizer:
    """Normalises observations of ``space`` (Box vector, Box uint8 image, or a Dict of those).

    ``enabled=False`` keeps the vector parts unchanged (images are still scaled by 1/255).
    Arrays may carry any leading batch axes: (..., *shape).
    """

    def __init__(
        self,
        space: spaces.Space,
        clip: float = 10.0,
        eps: float = 1e-8,
        enabled: bool = True,
        scaling: str = "running",
    ) -> None:
        if scaling not in SCALINGS:
            raise ValueError(f"observation scaling must be one of {SCALINGS}, got {scaling!r}")
        self.space = space
        self.clip, self.eps, self.enabled = clip, eps, enabled
        self.fixed = scaling == "scene"
        parts = space.spaces if isinstance(space, spaces.Dict) else {"": space}
        self.stats: dict[str, RunningMeanStd] = {}
        for key, sub in parts.items():
            if not isinstance(sub, spaces.Box):
                raise TypeError(
                    f"observation part {key!r}: only Box spaces are supported, got {sub}"
                )
            if not is_image_space(sub) and not self.fixed:
                self.stats[key] = RunningMeanStd(tuple(sub.shape))

    def _parts(self, obs: Obs) -> dict[str, NDArray[Any]]:
        if isinstance(self.space, spaces.Dict):
            if not isinstance(obs, dict):
                raise TypeError("expected a dict observation")
            return obs
        if isinstance(obs, dict):
            raise TypeError("expected an array observation, got a dict")
        return {"": obs}

    def update(self, obs: Obs) -> None:
        """Merge a batch of raw observations into the running statistics."""
        if not self.enabled:
            return
        for key, x in self._parts(obs).items():
            if key in self.stats:
                self.stats[key].update(x)

    def __call__(self, obs: Obs) -> Obs:
        """Normalised float32 copy of a batch of raw observations (same structure)."""
        out: dict[str, NDArray[np.float32]] = {}
        for key, x in self._parts(obs).items():
            if self.fixed and x.dtype != np.uint8:
                out[key] = np.clip(standardize_scene(x), -self.clip, self.clip)
            elif key not in self.stats:
                # one pass (cast inside the ufunc): the same float32 products, ~7x faster
                out[key] = np.multiply(x, np.float32(1.0 / 255.0), dtype=np.float32)
            elif not self.enabled:
                out[key] = np.asarray(x, dtype=np.float32)
            else:
                s = self.stats[key]
                z = (np.asarray(x, dtype=np.float64) - s.mean) / np.sqrt(s.var + self.eps)
                out[key] = np.clip(z, -self.clip, self.clip).astype(np.float32)
        return out if isinstance(self.space, spaces.Dict) else out[""]

    def state_dict(self) -> dict[str, Any]:
        return {key: s.state_dict() for key, s in self.stats.items()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        if set(state) != set(self.stats):
            raise ValueError(
                f"normaliser keys mismatch: saved {sorted(state)}, expected {sorted(self.stats)}"
            )
        for key, s in self.stats.items():
            s.load_state_dict(state[key])
