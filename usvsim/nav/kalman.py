"""The two navigation filters' equations, element-wise over N boats (means and covariances).

Pure functions on explicit, typed filter states (:class:`PositionState`, :class:`HeadingState`):
:class:`usvsim.nav.filter.Navigator` holds the states of N boats and feeds these functions the
simulated or given sensor readings; the models they implement are in :mod:`usvsim.nav.models`.

------------------------------------
F differs per boat (it depends on ω) and a vector environment resets boats one at a time, so
every boat has its own covariance (a single shared P, exact for the plain CV filter without
resets, is not an option). Stored as ``(N, 4, 4)`` and updated with batched ``matmul``, a step
cost ~270 µs at N = 256 on the 2-vCPU development VM, so we use an exact reduction instead
(~100 µs there, most of it the ~70 NumPy calls' fixed overhead and the random draws). With
isotropic ``Q`` and ``R`` and an isotropic start, the position covariance stays *circularly
symmetric*: write the position and velocity as complex numbers ``p = x_N + i y_E``,
``w = v_N + i v_E``; the rotation ``[[c, −s], [s, c]]`` is multiplication by ``e^{iθ}`` and the
filter is a 2-state complex Kalman filter (Picinbono 1996, *IEEE TSP* 44(10), second-order
circularity) whose Hermitian covariance ``Λ`` holds 4 real numbers per boat. The real
covariance is recovered exactly as (see :meth:`PositionState.covariance`)::

    P = [[Λ_pp, 0,     Re Λ_pw, −Im Λ_pw],
         [0,    Λ_pp,  Im Λ_pw,  Re Λ_pw],
         [Re,   Im,    Λ_ww,     0      ],
         [−Im,  Re,    0,        Λ_ww   ]]

The 2×2 heading covariance is kept as its three entries per boat. All updates are then
element-wise on ``(N,)`` arrays; the tests check both filters against filterpy's ``KalmanFilter``
run per boat on the full 4×4 / 2×2 model, to 1e-9.

"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.nav.models import NavConfig, heading_filter_model, position_filter_model, turn_factors

__all__ = [
    "FilterNoise",
    "HeadingState",
    "PositionState",
    "as_complex",
    "as_ne",
    "predict_heading",
    "predict_position",
    "update_heading",
    "update_position",
    "update_velocity",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def as_ne(z: ComplexArray) -> FloatArray:
    """View complex ``x_N + i y_E`` of shape (N,) as real ``[x_N, y_E]`` of shape (N, 2)."""
    return z[:, None].view(np.float64)


def as_complex(ne: FloatArray) -> ComplexArray:
    """Complex ``x_N + i y_E`` (N,) from real ``[x_N, y_E]`` (N, 2) (a view when contiguous)."""
    return np.ascontiguousarray(ne, dtype=np.float64).view(np.complex128)[:, 0]


@dataclass(frozen=True)
class FilterNoise:
    """Per-axis entries of the (isotropic) process and measurement noise, and the step.

    Attributes
    ----------
    q_pp, q_pw, q_ww : float
        Position-filter ``Q`` per axis: position (m²), position-velocity (m²/s), velocity (m²/s²)
        (:func:`usvsim.nav.models.position_filter_model`).
    r_gps : float
        GNSS position variance per axis (m²).
    r_gps_vel : float
        GNSS velocity variance per axis (m²/s²).
    q_psi, q_bias : float
        Heading-filter ``Q`` diagonal (rad², rad²/s²)
        (:func:`usvsim.nav.models.heading_filter_model`).
    r_compass : float
        Compass variance (rad²).
    dt_s : float
        Plant step (s).
    turn_rate_aided : bool
        Coordinated-turn transition at the gyro rate; False: constant velocity.
    """

    q_pp: float
    q_pw: float
    q_ww: float
    r_gps: float
    r_gps_vel: float
    q_psi: float
    q_bias: float
    r_compass: float
    dt_s: float
    turn_rate_aided: bool

    @classmethod
    def from_config(cls, cfg: NavConfig) -> FilterNoise:
        """The entries of the models of ``cfg`` (see :mod:`usvsim.nav.models`)."""
        pm, hm = position_filter_model(cfg), heading_filter_model(cfg)
        return cls(
            q_pp=pm.Q[0, 0],
            q_pw=pm.Q[0, 2],
            q_ww=pm.Q[2, 2],
            r_gps=pm.R[0, 0],
            r_gps_vel=cfg.sensors.gps_velocity_sigma_mps**2,
            q_psi=hm.Q[0, 0],
            q_bias=hm.Q[1, 1],
            r_compass=hm.R[0, 0],
            dt_s=cfg.dt_s,
            turn_rate_aided=cfg.turn_rate_aided,
        )


@dataclass(frozen=True)
class PositionState:
    """Position filter of N boats in circular complex form (arrays of shape (N,)).

    Attributes
    ----------
    p : complex ndarray
        Position ``x_N + i y_E`` (m).
    w : complex ndarray
        Velocity over ground ``v_N + i v_E`` (m/s).
    L_pp : ndarray
        Position variance per axis Λ_pp (m²).
    L_pw : complex ndarray
        Position-velocity covariance Λ_pw (m²/s).
    L_ww : ndarray
        Velocity variance per axis Λ_ww (m²/s²).
    """

    p: ComplexArray
    w: ComplexArray
    L_pp: FloatArray
    L_pw: ComplexArray
    L_ww: FloatArray

    @property
    def covariance(self) -> FloatArray:
        """Covariance of ``[x_N, y_E, v_N, v_E]``, shape (N, 4, 4) (m², m²/s, m²/s²)."""
        pp, ww, re, im = self.L_pp, self.L_ww, self.L_pw.real, self.L_pw.imag
        zero = np.zeros_like(pp)
        rows = [[pp, zero, re, -im], [zero, pp, im, re], [re, im, ww, zero], [-im, re, zero, ww]]
        return np.stack([np.stack(row, -1) for row in rows], -2)


@dataclass(frozen=True)
class HeadingState:
    """Heading filter ``[ψ, b]`` of N boats (arrays of shape (N,)).

    Attributes
    ----------
    psi : ndarray
        Heading ψ (rad); unwrapped between a prediction and the end of a filter cycle.
    b : ndarray
        Gyro bias estimate b̂ (rad/s).
    P_psi, P_pb, P_b : ndarray
        Covariance entries ``[[P_psi, P_pb], [P_pb, P_b]]`` (rad², rad²/s, rad²/s²).
    """

    psi: FloatArray
    b: FloatArray
    P_psi: FloatArray
    P_pb: FloatArray
    P_b: FloatArray

    @property
    def covariance(self) -> FloatArray:
        """Covariance of ``[ψ, b]``, shape (N, 2, 2) (rad², rad²/s, rad²/s²)."""
        rows = [[self.P_psi, self.P_pb], [self.P_pb, self.P_b]]
        return np.stack([np.stack(row, -1) for row in rows], -2)


def predict_heading(h: HeadingState, omega: FloatArray, q: FilterNoise) -> HeadingState:
    """Time update of ``[ψ, b]`` over ``dt_s`` at the bias-corrected gyro rate ``ω = g − b̂``.

    ``x⁻ = F x + B g``, ``P⁻ = F P Fᵀ + Q`` with ``F = [[1, −dt], [0, 1]]`` (Farrell 2008; see
    :func:`usvsim.nav.models.heading_filter_model`); ψ is left unwrapped.
    """
    dt = q.dt_s
    P_pb = h.P_pb - dt * h.P_b
    return HeadingState(
        psi=h.psi + dt * omega,
        b=h.b,
        P_psi=h.P_psi - dt * (h.P_pb + P_pb) + q.q_psi,
        P_pb=P_pb,
        P_b=h.P_b + q.q_bias,
    )


def predict_position(x: PositionState, omega: FloatArray, q: FilterNoise) -> PositionState:
    """Time update of the position filter over ``dt_s`` turning at ``omega`` (rad/s, (N,)).

    In complex form ``p⁻ = p + G w``, ``w⁻ = E w``, ``Λ⁻ = F Λ Fᴴ + Q`` with
    ``F = [[1, G], [0, E]]`` (coordinated turn with known rate, Bar-Shalom et al. 2001, Ch. 11;
    :func:`usvsim.nav.models.turn_factors`).
    """
    dt = q.dt_s
    # CV: G = dt, E = 1 (Python scalars, cheaper than arrays); aided: per-boat turn factors.
    G: ComplexArray | float = dt
    E: ComplexArray | float = 1.0
    if q.turn_rate_aided:
        G, E = turn_factors(omega, dt)
    L_pw_G = x.L_pw + G * x.L_ww  # Λ_pw + G Λ_ww
    # Λ_pp + 2 Re(Ḡ Λ_pw) + |G|² Λ_ww = Λ_pp + Re(Ḡ (Λ_pw + Λ_pw + G Λ_ww))
    return PositionState(
        p=x.p + G * x.w,
        w=E * x.w,
        L_pp=x.L_pp + (np.conjugate(G) * (x.L_pw + L_pw_G)).real + q.q_pp,
        L_pw=L_pw_G * np.conjugate(E) + q.q_pw,
        L_ww=x.L_ww + q.q_ww,
    )


def update_position(x: PositionState, z: ComplexArray, q: FilterNoise) -> PositionState:
    """GNSS update with ``z = x_N + i y_E`` (N,): ``K = [Λ_pp, conj Λ_pw] / S``.

    ``Λ⁺ = Λ − K S Kᴴ`` (Simon 2006, *Optimal State Estimation*, Ch. 5), element-wise.
    """
    S = x.L_pp + q.r_gps
    y = z - x.p
    k_p, k_w = x.L_pp / S, x.L_pw.conjugate() / S
    return PositionState(
        p=x.p + k_p * y,
        w=x.w + k_w * y,
        L_pp=q.r_gps * k_p,  # Λ_pp (1 − Λ_pp / S) = R Λ_pp / S
        L_pw=x.L_pw * (1.0 - k_p),
        L_ww=x.L_ww - (k_w * x.L_pw).real,  # Λ_ww − |Λ_pw|² / S
    )


def update_velocity(x: PositionState, z: ComplexArray, q: FilterNoise) -> PositionState:
    """GNSS velocity update, ``z = v_N + i v_E`` (N,): ``H = [0, 1]``, ``K = [Λ_pw, Λ_ww]/S``.

    ``Λ⁺ = Λ − K S Kᴴ`` (Simon 2006, Ch. 5): Λ_pp −= |Λ_pw|²/S, Λ_pw −= Λ_pw Λ_ww/S,
    Λ_ww −= Λ_ww²/S.
    """
    S = x.L_ww + q.r_gps_vel
    y = z - x.w
    k_p, k_w = x.L_pw / S, x.L_ww / S
    return PositionState(
        p=x.p + k_p * y,
        w=x.w + k_w * y,
        L_pp=x.L_pp - (k_p * x.L_pw.conjugate()).real,
        L_pw=x.L_pw * (1.0 - k_w),
        L_ww=q.r_gps_vel * k_w,
    )


def update_heading(h: HeadingState, z: FloatArray, q: FilterNoise) -> HeadingState:
    """Compass update with ``z`` (N,) rad: innovation ``ssa(z − ψ⁻)``, ``K = P Hᵀ / S``.

    Simon (2006), Ch. 5; the innovation is wrapped with the one ``ssa`` (Fossen 2021).
    """
    S = h.P_psi + q.r_compass
    y = ssa(z - h.psi)
    k_psi, k_b = h.P_psi / S, h.P_pb / S
    return HeadingState(
        psi=h.psi + k_psi * y,
        b=h.b + k_b * y,
        P_psi=q.r_compass * k_psi,  # P_ψψ (1 − P_ψψ / S) = R P_ψψ / S
        P_pb=h.P_pb * (1.0 - k_psi),
        P_b=h.P_b - k_b * h.P_pb,
    )
