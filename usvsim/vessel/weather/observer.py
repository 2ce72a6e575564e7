"""Heading wave filter: a Kalman observer that splits the compass heading into low-frequency
heading and wave-frequency yaw, so the autopilot does not chase the waves.

Fossen (2021), *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed., §13.3
(Kalman filter for heading autopilots with wave filtering). State z = [p₁, p₂, ψ, r, b]:

* wave yaw ψ_w = p₁ with the wave motion model of :mod:`usvsim.vessel.weather.waves` scaled to
  heading (p = c ξ, c = c_ψ k₀ ω₀ sin 2(β − ψ₀) the yaw per unit ξ₀ at the boat's initial
  heading): p⁺ = Φ p, process noise c² Q_d;
* low-frequency yaw, the design model of the autopilot m ṙ + d r = τ_N + b (Euler over Δt)
  with Norrbin's quadratic term d₂ r|r| fitted to the hull's steady turns
  (:mod:`usvsim.vessel.weather.turning`; without it the filter read turns as wave yaw):
  ψ⁺ = ψ + Δt r, r⁺ = r + Δt (τ_N + b − d r − d₂ r|r|) / m, b⁺ = b (a bias absorbing wind,
  drift and model error; a random walk);
* measurements: the compass y_ψ = ψ + p₁ + v_ψ and the rate gyro y_r = r + p₂ + v_r (p₂ = ṗ₁
  is the wave yaw rate, as the plant's sensed rate).

The gain is the steady-state Kalman gain L = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹ (5 × 2) from the discrete Riccati
equation, solved for all boats at once by a structured doubling (:func:`solve_filter_riccati`).
A calm sea (c = 0) leaves the wave states undriven; the filter then only smooths the heading
through its model.

The notch of :mod:`usvsim.vessel.weather.filters` was tried first: at usv105's autopilot
bandwidth (ω_n = 2 rad/s) the wave encounter frequency (0.8-1 rad/s in sea states 3-4) lies
inside the loop, and the notch's phase swing below ω₀ made the loop oscillate (30° step: 25°
overshoot, no settling), as Fossen warns for notches near the bandwidth.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.vessel.weather.riccati_kernel import riccati_doubling

__all__ = [
    "OBSERVER_STATES",
    "ObserverNoise",
    "measurement_information",
    "observer_correct",
    "observer_gains",
    "observer_predict",
    "solve_filter_riccati",
    "wrap_difference",
]

#: Observer states per boat, in order.
OBSERVER_STATES = ("psi_w", "psi_w2", "psi", "r", "bias")


@dataclass(frozen=True)
class ObserverNoise:
    """Tuning of the observer (standard deviations; ASSUMED, chosen on sea states 3-4)."""

    compass_rad: float = math.radians(0.3)  # rad; ASSUMED (usvsim's GNSS compass: 1°)
    gyro_rad_s: float = math.radians(0.1)  # rad/s, the gyro noise of usvsim's sensors
    psi_rad: float = 1e-4  # rad per step, low-frequency heading model error
    rate_rad_s2: float = 0.001  # rad/s², yaw acceleration model error
    bias_nm_per_step: float = 0.5  # N m per step, random walk of the yaw moment bias


def wrap_difference(angle: Any) -> Any:
    """A difference of two headings (each within about ±π) to [-π, π] by one ±2π (CasADi): two
    compares and selects, which vectorise in the compiled kernel; ``ssa`` (two fmod) and a
    floor cost 1.1× and 3× the whole weather kernel."""
    import casadi as ca

    two_pi = 2.0 * math.pi
    return (
        angle
        + ca.if_else(angle > math.pi, -two_pi, 0.0)
        + ca.if_else(angle < -math.pi, two_pi, 0.0)
    )


#: Measurement matrix H (2, 5): the compass reads ψ + p₁, the gyro r + p₂ (module docstring).
_H = np.array([[1.0, 0.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 1.0, 0.0]])
_H.flags.writeable = False


def solve_filter_riccati(
    a: NDArray[np.float64],
    h: NDArray[np.float64],
    q: NDArray[np.float64],
    r: NDArray[np.float64],
    tol: float = 1e-15,
    max_iter: int = 64,
    compiled: bool = True,
) -> NDArray[np.float64]:
    """Stationary prior covariances P (N, n, n) of N Kalman filters at once: the filter-form
    discrete Riccati equation P = A P Aᵀ − A P Hᵀ (H P Hᵀ + R)⁻¹ H P Aᵀ + Q, for ``a`` (N, n, n),
    ``h`` (m, n), ``q`` (N, n, n), ``r`` (m, m).

    The structure-preserving doubling algorithm (Chu, Fan & Lin 2005, *Linear Algebra Appl.*
    396, 55-80) on the dual (control-form) equation with A_c = Aᵀ, G = Hᵀ R⁻¹ H:
    W = I + G_k Q_k, A_{k+1} = A_k W⁻¹ A_k, G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ,
    Q_{k+1} = Q_k + A_kᵀ Q_k W⁻¹ A_k → P, quadratically (the error falls as ρ^(2^k), ρ the
    closed-loop spectral radius): a few dozen batched 5 × 5 solves for every boat together instead
    of one Schur-based solution (``scipy.linalg.solve_discrete_are``) per boat. Each boat stops
    when the largest change of its Q_k relative to its largest entry is below ``tol`` (so its
    result does not depend on the other boats); raises ``RuntimeError`` if one takes more than
    ``max_iter`` doublings (not stabilisable / detectable). ``compiled``: the same iteration in
    C (:mod:`usvsim.vessel.weather.riccati_kernel`, equal to rounding) where it builds."""
    return _doubling(a, h.T @ np.linalg.solve(r, h), q, tol, max_iter, compiled)


def _doubling(
    a: NDArray[np.float64],
    g0: NDArray[np.float64],
    q: NDArray[np.float64],
    tol: float,
    max_iter: int,
    compiled: bool,
) -> NDArray[np.float64]:
    """:func:`solve_filter_riccati` from G₀ = Hᵀ R⁻¹ H (n, n)."""
    fast = riccati_doubling(np.swapaxes(a, -1, -2), g0, q, tol, max_iter) if compiled else None
    if fast is not None:
        p, iters = fast
        if iters.min(initial=0) < 0:
            raise RuntimeError(f"Riccati doubling did not converge in {max_iter} steps")
        return p
    size = a.shape[-1]
    eye = np.eye(size)
    ak = np.swapaxes(a, -1, -2).copy()
    gk = np.broadcast_to(g0, ak.shape).copy()
    qk = q.copy()
    out, done = np.empty_like(qk), np.zeros(qk.shape[0], dtype=bool)
    for _ in range(max_iter):
        wag = np.linalg.solve(eye + gk @ qk, np.concatenate([ak, gk], axis=-1))
        wa, wg = wag[..., :size], wag[..., size:]  # W⁻¹ A_k, W⁻¹ G_k in one solve
        akt = np.swapaxes(ak, -1, -2)
        step = akt @ qk @ wa
        qk = qk + step
        gk = gk + ak @ wg @ akt
        ak = ak @ wa
        scale = np.abs(qk).max(axis=(-2, -1))
        now = (np.abs(step).max(axis=(-2, -1)) <= tol * scale) & ~done
        out[now] = 0.5 * (qk[now] + np.swapaxes(qk[now], -1, -2))
        done |= now
        if done.all():
            return out
    raise RuntimeError(f"Riccati doubling did not converge in {max_iter} steps")


@functools.lru_cache(maxsize=8)
def measurement_information(
    noise: ObserverNoise,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """R (2, 2) and G₀ = Hᵀ R⁻¹ H (5, 5) of ``noise``, once per tuning (read-only arrays): an
    episode start then builds only the per-boat A and Q."""
    r = np.diag([noise.compass_rad**2, noise.gyro_rad_s**2])
    g0 = _H.T @ np.linalg.solve(r, _H)
    r.flags.writeable = g0.flags.writeable = False
    return r, g0


def observer_gains(
    phi: NDArray[np.float64],
    chol: NDArray[np.float64],
    yaw_scale: NDArray[np.float64],
    m: float,
    d: float,
    dt_s: float,
    noise: ObserverNoise,
) -> NDArray[np.float64]:
    """Steady-state Kalman gains (N, 5, 2) (columns: compass, gyro) for N boats: wave transition
    ``phi`` (N, 2, 2) and noise factor ``chol`` (N, 2, 2) of
    :func:`usvsim.vessel.weather.waves.wave_motion_discrete`, ``yaw_scale`` c (N,) rad per
    unit ξ₀, the autopilot's design model m (kg m²), d (N m s/rad).

    All boats' Riccati equations solved together (:func:`solve_filter_riccati`).
    """
    n = phi.shape[0]
    if n == 0:
        return np.zeros((0, 5, 2))
    r, g0 = measurement_information(noise)
    a = np.zeros((n, 5, 5))
    a[:, 0:2, 0:2] = phi
    a[:, 2, 2], a[:, 2, 3] = 1.0, dt_s
    a[:, 3, 3], a[:, 3, 4] = 1.0 - dt_s * d / m, dt_s / m
    a[:, 4, 4] = 1.0
    c2 = (np.asarray(yaw_scale, dtype=float) ** 2)[:, None, None]
    q = np.zeros((n, 5, 5))
    q[:, 0:2, 0:2] = c2 * (chol @ np.swapaxes(chol, -1, -2))
    q[:, 0, 0] += 1e-12  # a regular DARE
    q[:, 1, 1] += 1e-12
    q[:, 2, 2] = noise.psi_rad**2
    q[:, 3, 3] = (dt_s * noise.rate_rad_s2) ** 2
    q[:, 4, 4] = noise.bias_nm_per_step**2
    p = _doubling(a, g0, q, 1e-15, 64, True)
    ph = p @ _H.T  # P Hᵀ (N, 5, 2)
    s = _H @ ph + r  # the innovation covariance (N, 2, 2), symmetric
    # L = P Hᵀ S⁻¹ with the 2 × 2 inverse written out (a batched LAPACK solve costs more here)
    det = (s[:, 0, 0] * s[:, 1, 1] - s[:, 0, 1] * s[:, 1, 0])[:, None]
    gains = np.empty((n, 5, 2))
    gains[:, :, 0] = (ph[:, :, 0] * s[:, 1, 1, None] - ph[:, :, 1] * s[:, 1, 0, None]) / det
    gains[:, :, 1] = (ph[:, :, 1] * s[:, 0, 0, None] - ph[:, :, 0] * s[:, 0, 1, None]) / det
    return gains


def observer_correct(
    z_prior: list[Any], psi_measured: Any, r_measured: Any, gains: list[Any]
) -> tuple[Any, Any, list[Any]]:
    """Correct the prior ``z_prior`` (5) with the compass ``psi_measured`` (rad) and the gyro
    ``r_measured`` (rad/s) (CasADi). Returns the low-frequency heading ψ̂ (rad, in [-π, π]),
    yaw rate r̂ (rad/s) and the corrected state (5); ``gains`` L row-major (10)."""
    nu_psi = wrap_difference(psi_measured - z_prior[2] - z_prior[0])
    nu_r = r_measured - z_prior[3] - z_prior[1]
    z = [z_prior[i] + gains[2 * i] * nu_psi + gains[2 * i + 1] * nu_r for i in range(5)]
    return wrap_difference(z[2]), z[3], z


def observer_predict(
    z: list[Any],
    tau_n: Any,
    phi: list[Any],
    m: float,
    d: float,
    dt_s: float,
    turn_damping: float = 0.0,
) -> list[Any]:
    """The next prior (5) from the corrected state ``z`` with the yaw moment ``tau_n`` (N m)
    applied over the step (CasADi); ``phi`` is Φ row-major (4). ``turn_damping`` d₂
    (N m s²/rad²) adds Norrbin's d₂ r|r| to the yaw model
    (:func:`usvsim.vessel.weather.turning.steady_turn_damping`): zero slope at r = 0, so the
    gains designed about the straight course stay valid."""
    damping = d * z[3] + turn_damping * z[3] * ca.fabs(z[3]) if turn_damping else d * z[3]
    return [
        phi[0] * z[0] + phi[1] * z[1],
        phi[2] * z[0] + phi[3] * z[1],
        wrap_difference(z[2] + dt_s * z[3]),
        z[3] + dt_s / m * (tau_n + z[4] - damping),
        z[4],
    ]
