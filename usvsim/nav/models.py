"""The navigation filters' configuration and their linear-Gaussian models (the matrices).

:class:`usvsim.nav.filter.Navigator` runs these models batched over N boats;
:mod:`usvsim.nav.compiled` is its CasADi twin; :mod:`usvsim.nav.telemetry` feeds the same
Navigator from MAVLink telemetry.

Choice of filter
----------------
Two *linear* filters that share no state (so no EKF linearisation and no vessel parameters: the
sensors measure position and heading directly and the gyro measures the heading rate):

1. **Position** — state ``x = [x_N, y_E, v_N, v_E]`` (m, m, m/s, m/s), discrete white-noise
   acceleration process noise (Bar-Shalom, Li & Kirubarajan 2001, *Estimation with Applications
   to Tracking and Navigation*, Sect. 6.3.2; ``Q`` from filterpy's ``Q_discrete_white_noise``),
   GNSS measurements ``z = [x_N, y_E]``, ``R = σ_gps² I``, and (``NavConfig.gnss_velocity``,
   default on) the receiver's Doppler velocity ``z_v = [v_N, v_E]``, ``R_v = σ_v² I``, fused
   sequentially with each fix. The transition is the coordinated-turn
   model with *known* rate (ibid., Ch. 11), the rate being the bias-corrected gyro
   ``ω = g − b̂`` from the heading filter (:func:`position_transition`); with
   ``NavConfig(turn_rate_aided=False)`` it is the plain constant-velocity (CV) model.

   Why turn-rate aiding: a plain CV filter lags in a turn by about ``a σ_gps / σ_a``
   (centripetal ``a = U r ≈ 0.52 m/s²`` for 3 m/s at 10 °/s), so σ_a must be large and the
   smoothing is lost. On the test manoeuvre (3 m/s, 30 s straight, 20 s at 10 °/s, straight) the
   best plain CV filter (σ_a ≈ 1-1.5 m/s²) reaches position RMSE / raw GNSS RMSE ≈ 0.45; the aided
   one reaches ≈ 0.26 at σ_a = 0.2 m/s². The model stays linear: ω is a known input, only F
   becomes time-varying and different per boat.

2. **Heading** — state ``x = [ψ, b]`` (rad, rad/s), the gyro ``g = r + b + n_g`` as process input
   and the compass as measurement: the classic compass / rate-gyro filter with a bias state (Farrell
   2008, *Aided Navigation: GPS with High Rate Sensors*; Fossen 2021, *Handbook of Marine Craft
   Hydrodynamics and Motion Control*, 2nd ed., ch. 13)::

       ψ_k = ψ_{k-1} + dt (g_k − b_{k-1}),  b_k = b_{k-1} + n_b
       F = [[1, −dt], [0, 1]],  B = [dt, 0]ᵀ,  Q = diag((dt σ_g)², σ_bw² dt)
       z_k = ψ_k + v,  H = [1 0],  R = σ_c²,  innovation wrapped: y = ssa(z − ψ⁻)
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
from filterpy.common import Q_discrete_white_noise
from numpy.typing import NDArray

from usvsim.nav.sensors import SensorConfig, check_positive, period_steps

__all__ = [
    "LinearModel",
    "NavConfig",
    "heading_filter_model",
    "position_filter_model",
    "position_transition",
    "turn_factors",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass(frozen=True)
class NavConfig:
    """Configuration of the navigation filters (sensor noise, process noise, plant step).

    Raises
    ------
    ValueError
        If a number is not finite and > 0, or a sensor rate does not divide the plant rate.
    """

    sensors: SensorConfig = field(default_factory=SensorConfig)
    # sensor noise and rates, see usvsim.nav.sensors.SensorConfig
    dt_s: float = 0.1
    # s, fixed plant step (the simulator's integration step)
    turn_rate_aided: bool = True
    # rotate the velocity by the gyro yaw rate (coordinated turn with known rate, Bar-Shalom
    # et al. 2001, Ch. 11); False gives the plain constant-velocity filter.
    accel_sigma_mps2: float = 0.5
    # m/s², σ_a of the discrete white-noise acceleration (Bar-Shalom et al. 2001, Sect. 6.3.3).
    # With turn-rate aiding it covers speed changes and sideslip transients (the default hull
    # sideslips strongly in turns). Measured on the plant's zig-zag with GNSS velocity: RMSE ratio
    # to raw GNSS 0.18 (σ_a = 0.2), 0.14 (0.5), 0.14 (1.0). Position fixes only, on a kinematic
    # turn: 0.26 at σ_a = 0.2, and a plain CV filter needs σ_a ≈ 1-1.5 (ratio 0.45).
    gyro_bias_walk_sigma: float = float(np.deg2rad(0.001))
    # rad/s/√s, bias random walk σ_bw that keeps the bias estimate alive; Groves (2013), Ch. 4:
    # consumer MEMS in-run bias drift is of the order of 1-10 °/h over minutes.
    gnss_velocity: bool = True
    # fuse the GNSS Doppler velocity with each fix. Measured on the plant (zig-zag ±30°, box and
    # avoidance manoeuvres of the default vessel, whose sideslip changes quickly in turns): the
    # position RMSE / raw GNSS RMSE falls from 0.45-0.50 (position only, σ_a = 1.5) to ~0.3.
    init_vel_sigma_mps: float = 0.1
    # m/s, 1σ velocity of the first fix (GNSS Doppler velocity; u-blox NEO-M8 datasheet 0.05 m/s).

    def __post_init__(self) -> None:
        if not isinstance(self.sensors, SensorConfig):
            raise ValueError(f"NavConfig.sensors must be a SensorConfig, got {self.sensors!r}")
        if not isinstance(self.gnss_velocity, bool):
            raise ValueError(f"NavConfig.gnss_velocity must be a bool, got {self.gnss_velocity!r}")
        if not isinstance(self.turn_rate_aided, bool):
            raise ValueError(
                f"NavConfig.turn_rate_aided must be a bool, got {self.turn_rate_aided!r}"
            )
        for f in fields(self):
            if f.name not in ("sensors", "turn_rate_aided", "gnss_velocity"):
                check_positive(f"NavConfig.{f.name}", getattr(self, f.name))
        # Both raise ValueError with the offending numbers if the rate does not fit dt_s.
        period_steps(self.sensors.gps_rate_hz, self.dt_s)
        period_steps(self.sensors.compass_rate_hz, self.dt_s)


@dataclass(frozen=True)
class LinearModel:
    """Matrices of a discrete linear-Gaussian model ``x⁺ = F x + B u + w``, ``z = H x + v``.

    Attributes
    ----------
    F : ndarray, shape (n, n)
        State transition over one plant step (for the position filter: the ω = 0 member).
    B : ndarray, shape (n, 1)
        Input matrix (zeros when there is no input).
    Q : ndarray, shape (n, n)
        Process noise covariance ``E[w wᵀ]`` per plant step.
    H : ndarray, shape (m, n)
        Measurement matrix; here always ``[I_m 0]`` (the leading m states are measured).
    R : ndarray, shape (m, m)
        Measurement noise covariance ``E[v vᵀ]``.
    """

    F: FloatArray
    B: FloatArray
    Q: FloatArray
    H: FloatArray
    R: FloatArray


def turn_factors(omega_radps: FloatArray, dt_s: float) -> tuple[ComplexArray, ComplexArray]:
    """Complex turn factors ``G = ∫₀^dt e^{iωt} dt`` and ``E = e^{iω dt}`` over ``dt_s``.

    ``G = dt e^{iθ/2} sin(θ/2) / (θ/2)`` with ``θ = ω dt``, i.e. ``sin(θ)/ω + i (1 − cos θ)/ω``;
    ω = 0 gives ``G = dt``, ``E = 1`` exactly. Shapes follow ``omega_radps``.
    """
    half = (0.5 * dt_s) * omega_radps
    sin_h = np.sin(half)
    sinc_h = np.divide(sin_h, half, out=np.ones_like(half), where=half != 0.0)
    E_half = np.empty(half.shape, dtype=np.complex128)
    E_half.real, E_half.imag = np.cos(half), sin_h
    return (dt_s * sinc_h) * E_half, E_half * E_half


def position_transition(omega_radps: FloatArray, dt_s: float) -> FloatArray:
    """Transition of ``[x_N, y_E, v_N, v_E]`` over ``dt_s`` for a turn at known rate ω.

    Coordinated-turn model with known turn rate (Bar-Shalom et al. 2001, Ch. 11): the
    velocity rotates by ``θ = ω dt`` (clockwise-positive, like ψ) and the position integrates it::

        F = [[1, 0, S,     -C   ],        S = sin(θ)/ω,  C = (1 − cos θ)/ω
             [0, 1, C,      S   ],
             [0, 0, cos θ, -sin θ],
             [0, 0, sin θ,  cos θ]]

    ω = 0 gives the constant-velocity matrix exactly.

    Parameters
    ----------
    omega_radps : ndarray, shape (N,)
        Turn rate of the velocity vector (rad/s).
    dt_s : float
        Step (s).

    Returns
    -------
    ndarray, shape (N, 4, 4)
    """
    G, E = turn_factors(np.asarray(omega_radps, dtype=np.float64), dt_s)
    F = np.zeros((*G.shape, 4, 4))
    F[..., 0, 0] = F[..., 1, 1] = 1.0
    F[..., 0, 2], F[..., 0, 3], F[..., 1, 2], F[..., 1, 3] = G.real, -G.imag, G.imag, G.real
    F[..., 2, 2], F[..., 2, 3], F[..., 3, 2], F[..., 3, 3] = E.real, -E.imag, E.imag, E.real
    return F


def position_filter_model(cfg: NavConfig) -> LinearModel:
    """CV model of ``[x_N, y_E, v_N, v_E]`` measured by GNSS (Bar-Shalom et al. 2001, 6.3.2).

    Parameters
    ----------
    cfg : NavConfig

    Returns
    -------
    LinearModel
        n = 4, m = 2, no input; ``F`` is :func:`position_transition` at ω = 0.
    """
    dt = cfg.dt_s
    eye2 = np.eye(2)
    F = position_transition(np.zeros(()), dt)
    # order_by_dim=False orders the blocks as [x, y, vx, vy], matching F.
    Q = Q_discrete_white_noise(
        dim=2, dt=dt, var=cfg.accel_sigma_mps2**2, block_size=2, order_by_dim=False
    )
    H = np.hstack([eye2, np.zeros((2, 2))])
    R = cfg.sensors.gps_sigma_m**2 * eye2
    return _frozen_model(F, np.zeros((4, 1)), Q, H, R)


def heading_filter_model(cfg: NavConfig) -> LinearModel:
    """Gyro-driven heading ``[ψ, b]`` with input ``g`` (gyro) and compass measurement.

    Parameters
    ----------
    cfg : NavConfig

    Returns
    -------
    LinearModel
        n = 2, m = 1, one input (the gyro reading, rad/s).
    """
    dt = cfg.dt_s
    F = np.array([[1.0, -dt], [0.0, 1.0]])
    B = np.array([[dt], [0.0]])
    # The gyro's white noise is held over dt (angle error dt·σ_g); the bias walks as σ_bw √dt.
    Q = np.diag([(dt * cfg.sensors.gyro_sigma_radps) ** 2, cfg.gyro_bias_walk_sigma**2 * dt])
    H = np.array([[1.0, 0.0]])
    R = np.array([[cfg.sensors.compass_sigma_rad**2]])
    return _frozen_model(F, B, Q, H, R)


def _frozen_model(*mats: FloatArray) -> LinearModel:
    """Build a :class:`LinearModel` whose arrays are read-only float64 copies."""
    frozen = []
    for m in mats:
        a = np.array(m, dtype=np.float64)
        a.flags.writeable = False
        frozen.append(a)
    return LinearModel(*frozen)
