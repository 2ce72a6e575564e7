"""Noisy sensors of a small surface vessel: GNSS position, compass heading and rate gyro.

All functions are batched over ``N`` boats and draw every random number from a
``numpy.random.Generator`` passed in by the caller, so a seed fixes the whole sensor record.

Sensor models (white Gaussian noise; P. D. Groves, *Principles of GNSS, Inertial, and Multisensor
Integrated Navigation Systems*, 2nd ed., 2013, Ch. 4 and 9):

========  =====================================  ===========  =========================
sensor    measurement                            shape        noise
========  =====================================  ===========  =========================
GNSS      ``z = p_NE + w``                       ``(N, 2)``   ``w ~ N(0, σ_gps² I₂)``
compass   ``z = ssa(ψ + w)``                     ``(N,)``     ``w ~ N(0, σ_c²)``
gyro      ``z = r + b + w``                      ``(N,)``     ``w ~ N(0, σ_g²)``, ``b`` const
========  =====================================  ===========  =========================

Sensors are sampled on the plant's fixed step ``dt_s``: a sensor of rate ``f`` fires every
``round(1 / (f dt_s))`` plant steps, counted from step 0 (see :func:`sensor_fires`). The gyro is
read on every plant step.

Caveat: real GNSS errors are time-correlated (multipath, atmosphere; Groves 2013, Ch. 9),
so white noise makes any filter look better than it would be at sea.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa

__all__ = [
    "SensorConfig",
    "as_checked",
    "check_positive",
    "check_step_index",
    "draw_compass",
    "draw_gps",
    "draw_gps_velocity",
    "draw_gyro",
    "period_steps",
    "sample_compass",
    "sample_gps",
    "sample_gps_velocity",
    "sample_gyro",
    "sample_gyro_bias",
    "sensor_fires",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SensorConfig:
    """Noise levels and rates of the vessel's sensors (all standard deviations are 1σ).

    Raises
    ------
    ValueError
        If any field is not a finite, strictly positive number.
    """

    gps_sigma_m: float = 1.5
    # m, per horizontal axis; u-blox NEO-M8 datasheet: 2.5 m CEP (GPS), 2.0 m CEP (SBAS);
    # CEP ≈ 1.18 σ for a circular Gaussian, so σ ≈ 1.7-2.1 m; 1.5 m is a good consumer fix.
    gps_rate_hz: float = 5.0
    # Hz, consumer receivers (u-blox NEO-M8 class) update at up to 10 Hz; 5 Hz is common.
    gps_velocity_sigma_mps: float = 0.1
    # m/s, per horizontal axis, GNSS Doppler velocity reported with each fix (NMEA RMC/VTG,
    # UBX NAV-PVT, MAVLink GLOBAL_POSITION_INT vx/vy); u-blox NEO-M8 datasheet: 0.05 m/s.
    compass_sigma_rad: float = float(np.deg2rad(1.0))
    # rad, marine electronic (fluxgate / MEMS) compasses are specified around 1° RMS static.
    compass_rate_hz: float = 10.0
    # Hz, typical NMEA 2000 heading rate (PGN 127250 at 10 Hz).
    gyro_sigma_radps: float = float(np.deg2rad(0.1))
    # rad/s per sample at the plant rate; Groves (2013), Ch. 4 (inertial sensor errors): consumer
    # MEMS gyro angle
    # random walk ~1 °/√h ≈ 0.017 °/s/√Hz, i.e. ~0.05 °/s at 10 Hz; 0.1 °/s is conservative.
    gyro_bias_sigma_radps: float = float(np.deg2rad(0.05))
    # rad/s, residual turn-on bias after an at-rest calibration (≈180 °/h); Groves (2013),
    # Ch. 4: consumer MEMS gyro biases are of the order of 10-1000 °/h.

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            check_positive(f"SensorConfig.{f.name}", value)


def check_positive(name: str, value: object) -> None:
    """Raise ``ValueError`` unless ``value`` is a finite real number > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    if not math.isfinite(float(value)) or float(value) <= 0.0:
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")


def as_checked(name: str, array: object, shape_tail: tuple[int, ...]) -> FloatArray:
    """Return ``array`` as float64 after checking shape ``(N, *shape_tail)`` and finiteness."""
    a = np.asarray(array, dtype=np.float64)
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail:
        want = "(N, " + ", ".join(map(str, shape_tail)) + ")" if shape_tail else "(N,)"
        raise ValueError(f"{name} must have shape {want}, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or inf")
    return a


def period_steps(rate_hz: float, dt_s: float) -> int:
    """Number of plant steps between two samples of a sensor of rate ``rate_hz``.

    Parameters
    ----------
    rate_hz : float
        Sensor rate (Hz).
    dt_s : float
        Fixed plant step (s).

    Returns
    -------
    int
        ``round(1 / (rate_hz * dt_s))``, at least 1.

    Raises
    ------
    ValueError
        If either argument is not finite and positive, if the sensor is faster than the plant,
        or if the plant rate is not an integer multiple of the sensor rate.

    Examples
    --------
    >>> period_steps(5.0, 0.1), period_steps(10.0, 0.1)
    (2, 1)
    """
    check_positive("rate_hz", rate_hz)
    check_positive("dt_s", dt_s)
    exact = 1.0 / (float(rate_hz) * float(dt_s))
    period = round(exact)
    if period < 1:
        raise ValueError(
            f"sensor rate {rate_hz} Hz is faster than the plant rate {1.0 / dt_s:g} Hz "
            f"(dt_s={dt_s}); a sensor can fire at most once per plant step"
        )
    if abs(exact - period) > 1e-6 * exact:
        raise ValueError(
            f"sensor rate {rate_hz} Hz with dt_s={dt_s} s gives a period of {exact:.4g} plant "
            "steps; the plant rate must be an integer multiple of the sensor rate"
        )
    return int(period)


def sensor_fires(step_index: int, rate_hz: float, dt_s: float) -> bool:
    """Whether a sensor of rate ``rate_hz`` delivers a sample at plant step ``step_index``.

    Samples are taken at steps ``0, p, 2p, ...`` with ``p = period_steps(rate_hz, dt_s)``.

    Parameters
    ----------
    step_index : int
        Plant step counter ``k`` (time ``k * dt_s``), ``k >= 0``.
    rate_hz, dt_s : float
        Sensor rate (Hz) and plant step (s).

    Returns
    -------
    bool

    Examples
    --------
    >>> [sensor_fires(k, 5.0, 0.1) for k in range(4)]
    [True, False, True, False]
    """
    k = check_step_index(step_index)
    return k % period_steps(rate_hz, dt_s) == 0


def check_step_index(step_index: object) -> int:
    """Return ``step_index`` as ``int`` after checking it is a non-negative integer."""
    if isinstance(step_index, bool) or not isinstance(step_index, (int, np.integer)):
        raise ValueError(f"step_index must be an integer, got {step_index!r}")
    if step_index < 0:
        raise ValueError(f"step_index must be >= 0, got {step_index}")
    return int(step_index)


def sample_gps(pos_ne: FloatArray, rng: np.random.Generator, cfg: SensorConfig) -> FloatArray:
    """GNSS position fix: true position plus white noise of ``cfg.gps_sigma_m`` per axis.

    Parameters
    ----------
    pos_ne : ndarray, shape (N, 2)
        True position [x_N, y_E] (m).
    rng : numpy.random.Generator
        Source of the noise; draws ``2 N`` normals.
    cfg : SensorConfig

    Returns
    -------
    ndarray, shape (N, 2)
        Measured position (m).
    """
    return draw_gps(as_checked("pos_ne", pos_ne, (2,)), rng, cfg)


def draw_gps(pos_ne: FloatArray, rng: np.random.Generator, cfg: SensorConfig) -> FloatArray:
    """:func:`sample_gps` without input checks (for callers that validated already)."""
    return pos_ne + rng.normal(0.0, cfg.gps_sigma_m, size=pos_ne.shape)


def sample_gps_velocity(
    vel_ne: FloatArray, rng: np.random.Generator, cfg: SensorConfig
) -> FloatArray:
    """GNSS Doppler velocity: true velocity over ground (N, 2) m/s plus white noise per axis."""
    return draw_gps_velocity(as_checked("vel_ne", vel_ne, (2,)), rng, cfg)


def draw_gps_velocity(
    vel_ne: FloatArray, rng: np.random.Generator, cfg: SensorConfig
) -> FloatArray:
    """:func:`sample_gps_velocity` without input checks (for callers that validated already)."""
    return vel_ne + rng.normal(0.0, cfg.gps_velocity_sigma_mps, size=vel_ne.shape)


def sample_compass(psi: FloatArray, rng: np.random.Generator, cfg: SensorConfig) -> FloatArray:
    """Compass heading: ``ssa(ψ + w)`` with ``w ~ N(0, cfg.compass_sigma_rad²)``.

    Parameters
    ----------
    psi : ndarray, shape (N,)
        True heading ψ (rad, clockwise from north), any range.
    rng : numpy.random.Generator
        Source of the noise; draws ``N`` normals.
    cfg : SensorConfig

    Returns
    -------
    ndarray, shape (N,)
        Measured heading (rad) in [-π, π).
    """
    return draw_compass(as_checked("psi", psi, ()), rng, cfg)


def draw_compass(
    psi: FloatArray, rng: np.random.Generator, cfg: SensorConfig, wrap: bool = True
) -> FloatArray:
    """:func:`sample_compass` without input checks (for callers that validated already).

    ``wrap=False`` skips the final ``ssa`` for a caller that wraps the innovation anyway.
    """
    z = psi + rng.normal(0.0, cfg.compass_sigma_rad, size=psi.shape)
    return ssa(z) if wrap else z


def sample_gyro(
    r: FloatArray, bias: FloatArray, rng: np.random.Generator, cfg: SensorConfig
) -> FloatArray:
    """Rate-gyro reading: ``r + b + w`` with ``w ~ N(0, cfg.gyro_sigma_radps²)``.

    Parameters
    ----------
    r : ndarray, shape (N,)
        True yaw rate (rad/s).
    bias : ndarray, shape (N,)
        Gyro bias of each boat (rad/s), e.g. from :func:`sample_gyro_bias`.
    rng : numpy.random.Generator
        Source of the noise; draws ``N`` normals.
    cfg : SensorConfig

    Returns
    -------
    ndarray, shape (N,)
        Measured yaw rate (rad/s).
    """
    rate = as_checked("r", r, ())
    b = as_checked("bias", bias, ())
    if b.shape != rate.shape:
        raise ValueError(f"bias must have the shape of r {rate.shape}, got {b.shape}")
    return draw_gyro(rate, b, rng, cfg)


def draw_gyro(
    r: FloatArray, bias: FloatArray, rng: np.random.Generator, cfg: SensorConfig
) -> FloatArray:
    """:func:`sample_gyro` without input checks (for callers that validated already)."""
    return r + bias + rng.normal(0.0, cfg.gyro_sigma_radps, size=r.shape)


def sample_gyro_bias(n_boats: int, rng: np.random.Generator, cfg: SensorConfig) -> FloatArray:
    """Draw a constant gyro bias per boat, ``b ~ N(0, cfg.gyro_bias_sigma_radps²)``.

    Parameters
    ----------
    n_boats : int
        Number of biases to draw (>= 0).
    rng : numpy.random.Generator
    cfg : SensorConfig

    Returns
    -------
    ndarray, shape (n_boats,)
        Bias (rad/s).
    """
    if isinstance(n_boats, bool) or not isinstance(n_boats, (int, np.integer)) or n_boats < 0:
        raise ValueError(f"n_boats must be a non-negative integer, got {n_boats!r}")
    return rng.normal(0.0, cfg.gyro_bias_sigma_radps, size=int(n_boats))
