"""Angle helpers shared by the whole package (radians internally): one smallest signed angle.

:func:`ssa` works on numbers and NumPy arrays, :func:`ssa_casadi` builds the same map as a
CasADi expression for the compiled plant and filter steps. Both follow Fossen (2021),
*Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed. (MSS ``ssa``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ssa", "ssa_casadi", "ssa_float"]


def ssa(angle_rad: ArrayLike) -> NDArray[np.float64]:
    """Smallest signed angle: map any angle (rad) to [-π, π).

    Fossen (2021), *Handbook of Marine Craft Hydrodynamics and Motion Control*; MSS ``ssa``.
    Works element-wise on arrays of any shape.

    >>> float(ssa(3 * np.pi / 2))
    -1.5707963267948966
    """
    a = np.asarray(angle_rad, dtype=float)
    return np.mod(a + np.pi, 2.0 * np.pi) - np.pi


def ssa_float(angle_rad: float) -> float:
    """:func:`ssa` of one Python float, as a float: the same bits, about 10× cheaper.

    Python's float ``%`` and NumPy's ``mod`` are the same operation (C's ``fmod``, then the
    divisor added where the signs differ, ``copysign(0, divisor)`` for a zero remainder), and
    ``np.pi`` is ``math.pi``, so ``(a + π) % 2π − π`` rounds as :func:`ssa` does (tested on
    random and edge values). For scalar code in hot paths (an episode's draw).

    >>> ssa_float(3 * math.pi / 2)
    -1.5707963267948966
    """
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def ssa_casadi(angle_rad: Any) -> Any:
    """:func:`ssa` as a CasADi expression (``SX``/``MX``/``DM``): map an angle (rad) to [-π, π).

    C's ``fmod`` keeps the sign of the dividend, so the first remainder lies in (-2π, 2π); adding
    2π and taking ``fmod`` again gives NumPy's ``mod`` (a result in [0, 2π)) before the shift by π.
    The compiled fast path is generated from this exact expression: changing its form changes
    the simulation's bits (``usvsim bench`` rows).

    >>> import casadi as ca
    >>> float(ssa_casadi(ca.DM(3 * np.pi / 2)))
    -1.5707963267948966
    """
    import casadi as ca  # lazily: the rest of usvsim.common needs no CasADi

    return ca.fmod(ca.fmod(angle_rad + ca.pi, 2 * ca.pi) + 2 * ca.pi, 2 * ca.pi) - ca.pi
