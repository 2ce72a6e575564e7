"""Angle helpers shared by the whole package (radians internally)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ssa"]


def ssa(angle_rad: ArrayLike) -> NDArray[np.float64]:
    """Smallest signed angle: map any angle (rad) to [-π, π).

    Fossen (2021), *Handbook of Marine Craft Hydrodynamics and Motion Control*, (MSS ``ssa``).
    Works element-wise on arrays of any shape.

    >>> float(ssa(3 * np.pi / 2))
    -1.5707963267948966
    """
    a = np.asarray(angle_rad, dtype=float)
    return np.mod(a + np.pi, 2.0 * np.pi) - np.pi
