"""Heading wave filter: a notch at the wave frequency, so the autopilot does not chase the waves.

Fossen (2021), *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed., §13 (wave
filtering of the heading measurement) uses the notch

    h_n(s) = (s² + 2 ζ ω₀ s + ω₀²) / (s + ω₀)²,   |h_n(jω₀)| = ζ,

in cascade with a low-pass filter. ζ sets the attenuation at the wave (peak or encounter)
frequency ω₀: A = -20 log₁₀ ζ dB. The discrete filter is the bilinear (Tustin) transform
prewarped at ω₀, so its gain at ω₀ equals the continuous one exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.errors import UserError

__all__ = ["NotchFilter", "design_notch", "notch_coefficients"]

ATTENUATION_RANGE_DB = (1.0, 60.0)  # dB, accepted notch depths


@dataclass(frozen=True)
class NotchFilter:
    """Discrete filter y_k = Σ b_i u_{k-i} - Σ a_i y_{k-i} (a₀ = 1); (3,) or (4,) entries."""

    b: NDArray[np.float64]
    a: NDArray[np.float64]
    omega0: float  # rad/s, notch frequency
    zeta: float  # -, numerator damping = gain at ω₀
    dt_s: float  # s, sample time


def design_notch(
    omega0: float,
    attenuation_db: float = 20.0,
    dt_s: float = 0.1,
    lowpass_rad_s: float | None = None,
) -> NotchFilter:
    """Design the heading notch for wave frequency ``omega0`` (rad/s) and depth ``attenuation_db``.

    ``omega0`` must lie below the Nyquist frequency π/dt_s. With ``lowpass_rad_s`` = ω_f the notch
    is cascaded with the low-pass ω_f / (s + ω_f) (Fossen 2021 §13), Tustin prewarped at ω_f; the
    coefficients then have 4 entries.

    >>> f = design_notch(0.8, 20.0, 0.1)
    >>> round(f.zeta, 3)
    0.1
    """
    lo, hi = ATTENUATION_RANGE_DB
    if not lo <= attenuation_db <= hi:
        raise UserError(f"notch attenuation must lie in [{lo:g}, {hi:g}] dB, got {attenuation_db}")
    if not dt_s > 0 or not 0 < omega0 < math.pi / dt_s:
        raise UserError(
            f"notch frequency must lie in (0, π/dt) = (0, {math.pi / dt_s:.3g}) rad/s, got {omega0}"
        )
    zeta = 10.0 ** (-attenuation_db / 20.0)
    b, a = notch_coefficients(np.array([omega0]), attenuation_db, dt_s)
    num, den = b[0], a[0]
    if lowpass_rad_s is not None:
        if not 0 < lowpass_rad_s < math.pi / dt_s:
            raise UserError(
                f"low-pass corner must lie in (0, π/dt) = (0, {math.pi / dt_s:.3g}) rad/s, "
                f"got {lowpass_rad_s}"
            )
        cf = lowpass_rad_s / math.tan(0.5 * lowpass_rad_s * dt_s)
        num = np.asarray(np.polymul(num, [lowpass_rad_s, lowpass_rad_s]), float)  # ω_f (z + 1)
        # c (z - 1) + ω_f (z + 1)
        den = np.asarray(np.polymul(den, [cf + lowpass_rad_s, lowpass_rad_s - cf]), float)
    return NotchFilter(num / den[0], den / den[0], omega0, zeta, dt_s)


def notch_coefficients(
    omega0: NDArray[np.float64], attenuation_db: float, dt_s: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The notch of :func:`design_notch` (no low-pass) for N frequencies at once: numerator b and
    denominator a, each (N, 3), a[:, 0] = 1. Checks nothing (the caller clips ω₀ below π/dt)."""
    w = np.asarray(omega0, dtype=float)[:, None]
    zeta = 10.0 ** (-attenuation_db / 20.0)
    c = w / np.tan(0.5 * w * dt_s)  # prewarped Tustin: s = c (z - 1) / (z + 1)

    def quadratic(z: float) -> NDArray[np.float64]:
        # c²(z-1)² + 2 z ω₀ c (z²-1) + ω₀²(z+1)² in powers z², z¹, z⁰
        return np.concatenate(
            [c * c + 2 * z * w * c + w**2, 2 * w**2 - 2 * c * c, c * c - 2 * z * w * c + w**2], 1
        )

    num, den = quadratic(zeta), quadratic(1.0)
    return num / den[:, :1], den / den[:, :1]
