"""How a navigation filter starts: the first fix of k boats and the filter's starting variances.

:meth:`usvsim.nav.filter.Navigator.reset` starts its filters from :func:`first_fix` with
:func:`start_variances`; :func:`usvsim.nav.compiled.started_nav_rows` packs the same numbers
for the batched environments.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.nav.kalman import as_complex
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import draw_compass, draw_gps, draw_gyro, sample_gyro_bias

__all__ = ["FirstFix", "first_fix", "start_variances"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass(frozen=True)
class FirstFix:
    """The readings a filter starts from, k boats: GNSS position (k, 2) m, velocity over
    ground (k,) complex ``v_N + i v_E`` m/s, compass heading (k,) rad, the boat's new true gyro
    bias (k,) rad/s and its first gyro reading (k,) rad/s."""

    pos_ne: FloatArray
    vel_ne: ComplexArray
    heading_rad: FloatArray
    gyro_bias_radps: FloatArray
    gyro_radps: FloatArray


def first_fix(
    cfg: NavConfig, eta: FloatArray, nu: FloatArray, rng: np.random.Generator
) -> FirstFix:
    """Draw the first fix of k boats at true ``eta``, ``nu`` (k, 3): GNSS position, compass,
    Doppler velocity ``R(ψ) [u, v] + N(0, init_vel_sigma² I)``, a new gyro bias and a gyro
    reading, in that order from ``rng`` (GNSS (k, 2), compass (k,), velocity (k, 2), bias (k,),
    gyro (k,)). :meth:`Navigator.reset` starts its filters from it."""
    s, k = cfg.sensors, eta.shape[0]
    psi_true = eta[:, 2]
    gps = draw_gps(eta[:, :2], rng, s)
    compass = draw_compass(psi_true, rng, s)
    # Body velocity to NED: w = (u + i v) e^{iψ}, i.e. R(ψ) [u, v].
    w = (nu[:, 0] + 1j * nu[:, 1]) * np.exp(1j * psi_true)
    w = w + as_complex(rng.normal(0.0, cfg.init_vel_sigma_mps, size=(k, 2)))
    bias = sample_gyro_bias(k, rng, s)
    gyro = draw_gyro(nu[:, 2], bias, rng, s)
    return FirstFix(gps, w, compass, bias, gyro)


def start_variances(cfg: NavConfig) -> tuple[float, float, float, float]:
    """A started filter's variances (cross terms 0): position ``σ_gps²`` m², velocity
    ``σ_v0²`` (m/s)², heading ``σ_c²`` rad², gyro bias ``σ_b0²`` (rad/s)²."""
    s = cfg.sensors
    return (
        s.gps_sigma_m**2,
        cfg.init_vel_sigma_mps**2,
        s.compass_sigma_rad**2,
        s.gyro_bias_sigma_radps**2,
    )
