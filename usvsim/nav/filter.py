"""Navigation estimate of N boats from noisy GNSS, compass and gyro: two linear Kalman filters.

Everything downstream (guidance, observations, the MAVLink bridge) reads the vessel's state from
here, never from the plant's true state.

The filter models and their configuration are in :mod:`usvsim.nav.models`; the compiled
CasADi twin of :meth:`Navigator.step` in :mod:`usvsim.nav.compiled`.

Batching (exact, no loop over boats)
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
covariance is recovered exactly as (see :meth:`Navigator.position_covariance`)::

    P = [[Λ_pp, 0,     Re Λ_pw, −Im Λ_pw],
         [0,    Λ_pp,  Im Λ_pw,  Re Λ_pw],
         [Re,   Im,    Λ_ww,     0      ],
         [−Im,  Re,    0,        Λ_ww   ]]

The 2×2 heading covariance is kept as its three entries per boat. All updates are then
element-wise on ``(N,)`` arrays; the tests check both filters against filterpy's ``KalmanFilter``
run per boat on the full 4×4 / 2×2 model, to 1e-9.

Timing convention
-----------------
``step(k, η, ν, rng)`` takes the true state at ``t_k = k dt_s`` (the plant's state *after* its
k-th step), propagates the estimate from ``t_{k-1}`` to ``t_k`` with the gyro read at ``t_k``,
then applies the GNSS / compass samples that fire at step ``k``
(:func:`usvsim.nav.sensors.sensor_fires`).

Shapes
------
================  ==============  ================================================
name              shape           meaning
================  ==============  ================================================
``eta``           ``(N, 3)``      true ``[x_N, y_E, ψ]`` (m, m, rad)
``nu``            ``(N, 3)``      true ``[u, v, r]`` (m/s, m/s, rad/s), body frame
``pos_ne``        ``(N, 2)``      estimated position (m)
``vel_ne``        ``(N, 2)``      estimated velocity over ground, NED (m/s)
``psi``           ``(N,)``        estimated heading (rad) in [-π, π)
``yaw_rate``      ``(N,)``        bias-corrected gyro rate ``g − b̂`` (rad/s)
================  ==============  ================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.nav.models import NavConfig, heading_filter_model, position_filter_model, turn_factors
from usvsim.nav.sensors import (
    _as_checked,
    _check_step_index,
    _draw_compass,
    _draw_gps,
    _draw_gps_velocity,
    _draw_gyro,
    period_steps,
    sample_gyro_bias,
)

__all__ = [
    "NAV_NS",
    "NAV_STATE_FIELDS",
    "NavEstimate",
    "Navigator",
    "export_nav_state",
    "import_nav_state",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass(frozen=True)
class NavEstimate:
    """Navigation estimate of N boats (leading axes ``(N,)``, or ``(N, T)`` for a trajectory).

    Attributes
    ----------
    pos_ne : ndarray, shape (..., 2)
        Position [x_N, y_E] (m).
    vel_ne : ndarray, shape (..., 2)
        Velocity over ground [v_N, v_E] (m/s).
    psi : ndarray, shape (...)
        Heading ψ (rad), in [-π, π).
    yaw_rate : ndarray, shape (...)
        Bias-corrected gyro yaw rate (rad/s).
    """

    pos_ne: FloatArray
    vel_ne: FloatArray
    psi: FloatArray
    yaw_rate: FloatArray

    @property
    def sog_mps(self) -> FloatArray:
        """Speed over ground ``|v_NE|`` (m/s), shape (...)."""
        return np.hypot(self.vel_ne[..., 0], self.vel_ne[..., 1])

    @property
    def cog_rad(self) -> FloatArray:
        """Course over ground ``atan2(v_E, v_N)`` (rad, clockwise from north), shape (...)."""
        return np.arctan2(self.vel_ne[..., 1], self.vel_ne[..., 0])


def _as_ne(z: ComplexArray) -> FloatArray:
    """View complex ``x_N + i y_E`` of shape (N,) as real ``[x_N, y_E]`` of shape (N, 2)."""
    return z[:, None].view(np.float64)


def _as_complex(ne: FloatArray) -> ComplexArray:
    """Complex ``x_N + i y_E`` (N,) from real ``[x_N, y_E]`` (N, 2) (a view when contiguous)."""
    return np.ascontiguousarray(ne, dtype=np.float64).view(np.complex128)[:, 0]


class Navigator:
    """Batched navigation filter of N boats: position KF (GNSS) + heading KF (gyro, compass).

    Parameters
    ----------
    cfg : NavConfig
        Filter and sensor configuration.
    n_boats : int
        Number of boats N (>= 1).

    Notes
    -----
    Holds the filter states and the true gyro bias of each boat (drawn at :meth:`reset`), so one
    ``Navigator`` belongs to one simulation. All randomness comes from the ``rng`` passed to
    :meth:`reset` and :meth:`step`, in a fixed order, so the same seed gives the same estimates.
    The arrays on ``self`` are replaced, never written in place, once a :class:`NavEstimate`
    (whose fields are views of them) may hold them.
    """

    def __init__(self, cfg: NavConfig, n_boats: int) -> None:
        if not isinstance(cfg, NavConfig):
            raise ValueError(f"cfg must be a NavConfig, got {cfg!r}")
        if isinstance(n_boats, bool) or not isinstance(n_boats, (int, np.integer)) or n_boats < 1:
            raise ValueError(f"n_boats must be a positive integer, got {n_boats!r}")
        self.cfg = cfg
        self.n_boats = int(n_boats)
        pm, hm = position_filter_model(cfg), heading_filter_model(cfg)
        # Per-axis entries of the (isotropic) position Q and R; see the module docstring.
        self._q_pp, self._q_pw, self._q_ww = pm.Q[0, 0], pm.Q[0, 2], pm.Q[2, 2]
        self._r_gps = pm.R[0, 0]
        self._r_gps_vel = cfg.sensors.gps_velocity_sigma_mps**2
        self._q_psi, self._q_bias = hm.Q[0, 0], hm.Q[1, 1]
        self._r_compass = hm.R[0, 0]
        self._gps_period = period_steps(cfg.sensors.gps_rate_hz, cfg.dt_s)
        self._compass_period = period_steps(cfg.sensors.compass_rate_hz, cfg.dt_s)

        n = self.n_boats
        nan, cnan = np.full(n, np.nan), np.full(n, np.nan + 0j)
        # Position filter: complex means p = x_N + i y_E, w = v_N + i v_E; covariance Λ.
        self._p, self._w, self._L_pw = cnan, cnan.copy(), cnan.copy()
        self._L_pp, self._L_ww = nan, nan.copy()
        # Heading filter: means ψ, b̂; covariance [[P_psi, P_pb], [P_pb, P_b]].
        self._psi, self._b, self._yaw_rate = nan.copy(), nan.copy(), nan.copy()
        self._P_psi, self._P_pb, self._P_b = nan.copy(), nan.copy(), nan.copy()
        self._gyro_bias = nan.copy()  # true bias of each boat's gyro, rad/s
        self._ready = np.zeros(n, dtype=bool)
        self._all_ready = False

    def reset(
        self,
        eta: FloatArray,
        nu: FloatArray,
        rng: np.random.Generator,
        mask: NDArray[np.bool_] | None = None,
    ) -> NavEstimate:
        """Start the filters of (some) boats at a first GNSS + compass fix of the true state.

        Position = a GNSS fix, velocity = true ``R(ψ)[u, v]`` + ``N(0, init_vel_sigma² I)``
        (Doppler), heading = a compass reading, bias estimate 0; covariances are the matching
        ``diag(σ_gps², σ_gps², σ_v², σ_v²)`` and ``diag(σ_c², σ_b0²)``. A new true gyro bias is
        drawn for every reset boat.

        Parameters
        ----------
        eta : ndarray, shape (N, 3)
            True ``[x_N, y_E, ψ]`` (m, m, rad).
        nu : ndarray, shape (N, 3)
            True ``[u, v, r]`` (m/s, m/s, rad/s).
        rng : numpy.random.Generator
            Draws, for the k reset boats in order: GNSS (k, 2), compass (k,), velocity (k, 2),
            bias (k,), gyro (k,).
        mask : ndarray of bool, shape (N,), optional
            Boats to reset; default all. Rows of ``eta``/``nu`` outside the mask are not used
            but must still be finite.

        Returns
        -------
        NavEstimate
            The estimate of all N boats after the reset.
        """
        eta, nu = self._check_states(eta, nu)
        if mask is None:
            idx = np.arange(self.n_boats)
        else:
            m = np.asarray(mask)
            if m.dtype != np.bool_ or m.shape != (self.n_boats,):
                raise ValueError(
                    f"mask must be a bool array of shape ({self.n_boats},), "
                    f"got dtype {m.dtype} and shape {m.shape}"
                )
            idx = np.flatnonzero(m)
        s, k = self.cfg.sensors, idx.size
        psi_true = eta[idx, 2]
        gps = _draw_gps(eta[idx, :2], rng, s)
        compass = _draw_compass(psi_true, rng, s)
        # Body velocity to NED: w = (u + i v) e^{iψ}, i.e. R(ψ) [u, v].
        w = (nu[idx, 0] + 1j * nu[idx, 1]) * np.exp(1j * psi_true)
        w = w + _as_complex(rng.normal(0.0, self.cfg.init_vel_sigma_mps, size=(k, 2)))
        bias = sample_gyro_bias(k, rng, s)
        gyro = _draw_gyro(nu[idx, 2], bias, rng, s)

        new = {
            "_p": _as_complex(gps),
            "_w": w,
            "_L_pp": s.gps_sigma_m**2,
            "_L_pw": 0.0,
            "_L_ww": self.cfg.init_vel_sigma_mps**2,
            "_psi": compass,
            "_b": 0.0,
            "_P_psi": s.compass_sigma_rad**2,
            "_P_pb": 0.0,
            "_P_b": s.gyro_bias_sigma_radps**2,
            "_gyro_bias": bias,
            "_yaw_rate": gyro,
        }
        for name, value in new.items():
            array = getattr(self, name).copy()  # copy: earlier NavEstimates view the old one
            array[idx] = value
            setattr(self, name, array)
        self._ready[idx] = True
        self._all_ready = bool(self._ready.all())
        return self.estimate

    @property
    def estimate(self) -> NavEstimate:
        """Current estimate of all N boats (arrays of shape (N, ...), read them, don't write)."""
        return NavEstimate(
            pos_ne=_as_ne(self._p), vel_ne=_as_ne(self._w), psi=self._psi, yaw_rate=self._yaw_rate
        )

    @property
    def gyro_bias_estimate(self) -> FloatArray:
        """Estimated gyro bias b̂ of each boat (rad/s), shape (N,)."""
        return self._b

    @property
    def true_gyro_bias(self) -> FloatArray:
        """Simulated true gyro bias of each boat (rad/s), shape (N,), for diagnostics."""
        return self._gyro_bias

    @property
    def position_covariance(self) -> FloatArray:
        """Covariance of ``[x_N, y_E, v_N, v_E]``, shape (N, 4, 4) (m², m²/s, m²/s²)."""
        pp, ww, re, im = self._L_pp, self._L_ww, self._L_pw.real, self._L_pw.imag
        zero = np.zeros_like(pp)
        rows = [[pp, zero, re, -im], [zero, pp, im, re], [re, im, ww, zero], [-im, re, zero, ww]]
        return np.stack([np.stack(row, -1) for row in rows], -2)

    @property
    def heading_covariance(self) -> FloatArray:
        """Covariance of ``[ψ, b]``, shape (N, 2, 2) (rad², rad²/s, rad²/s²)."""
        rows = [[self._P_psi, self._P_pb], [self._P_pb, self._P_b]]
        return np.stack([np.stack(row, -1) for row in rows], -2)

    def step(
        self,
        step_index: int,
        eta_true: FloatArray,
        nu_true: FloatArray,
        rng: np.random.Generator,
    ) -> NavEstimate:
        """Advance both filters by one plant step ``dt_s`` and fuse the sensors that fire.

        Parameters
        ----------
        step_index : int
            Plant step counter k (>= 0) of the state passed in (time ``k dt_s``); GNSS and
            compass fire when ``k`` is a multiple of their period in steps.
        eta_true : ndarray, shape (N, 3)
            True ``[x_N, y_E, ψ]`` at step k (m, m, rad).
        nu_true : ndarray, shape (N, 3)
            True ``[u, v, r]`` at step k (m/s, m/s, rad/s).
        rng : numpy.random.Generator
            Draws in order: gyro (N,), then GNSS (N, 2) and compass (N,) when they fire.

        Returns
        -------
        NavEstimate
            Estimate at step k, arrays of shape (N, ...).

        Raises
        ------
        ValueError
            On wrong shapes, NaN/inf, or a bad ``step_index``.
        RuntimeError
            If some boat has never been reset.
        """
        k = _check_step_index(step_index)
        if not self._all_ready:
            raise RuntimeError("Navigator.reset() must initialise every boat before step()")
        eta, nu = self._check_states(eta_true, nu_true)
        s = self.cfg.sensors
        gyro = _draw_gyro(nu[:, 2], self._gyro_bias, rng, s)
        self._predict(gyro)
        if k % self._gps_period == 0:
            self._update_position(_as_complex(_draw_gps(eta[:, :2], rng, s)))
            if self.cfg.gnss_velocity:
                # true velocity over ground R(ψ)[u, v] = (u + i v) e^{iψ}
                vel = (nu[:, 0] + 1j * nu[:, 1]) * np.exp(1j * eta[:, 2])
                self._update_velocity(_as_complex(_draw_gps_velocity(_as_ne(vel), rng, s)))
        if k % self._compass_period == 0:
            # Unwrapped reading: the innovation is wrapped, so ssa here would be redundant.
            self._update_heading(_draw_compass(eta[:, 2], rng, s, wrap=False))
        self._psi = ssa(self._psi)
        self._yaw_rate = gyro - self._b
        return self.estimate

    def _predict(self, gyro: FloatArray) -> None:
        """Time update of both filters over ``dt_s`` with the gyro reading ``gyro`` (N,).

        Heading: ``x⁻ = F x + B g``, ``P⁻ = F P Fᵀ + Q`` with ``F = [[1, −dt], [0, 1]]``; ψ is
        left unwrapped until the end of :meth:`step`. Position, in complex form:
        ``p⁻ = p + G w``, ``w⁻ = E w``, ``Λ⁻ = F Λ Fᴴ + Q`` with ``F = [[1, G], [0, E]]``.
        """
        dt = self.cfg.dt_s
        omega = gyro - self._b  # bias-corrected rate with the prior bias, rad/s
        self._psi = self._psi + dt * omega
        P_pb = self._P_pb - dt * self._P_b
        self._P_psi = self._P_psi - dt * (self._P_pb + P_pb) + self._q_psi
        self._P_pb, self._P_b = P_pb, self._P_b + self._q_bias

        # CV: G = dt, E = 1 (Python scalars, cheaper than arrays); aided: per-boat turn factors.
        G: ComplexArray | float = dt
        E: ComplexArray | float = 1.0
        if self.cfg.turn_rate_aided:
            G, E = turn_factors(omega, dt)
        L_pw_G = self._L_pw + G * self._L_ww  # Λ_pw + G Λ_ww
        # Λ_pp + 2 Re(Ḡ Λ_pw) + |G|² Λ_ww = Λ_pp + Re(Ḡ (Λ_pw + Λ_pw + G Λ_ww))
        self._L_pp = self._L_pp + (np.conjugate(G) * (self._L_pw + L_pw_G)).real + self._q_pp
        self._L_pw = L_pw_G * np.conjugate(E) + self._q_pw
        self._L_ww = self._L_ww + self._q_ww
        self._p = self._p + G * self._w
        self._w = E * self._w

    def _update_position(self, z: ComplexArray) -> None:
        """GNSS update with ``z = x_N + i y_E`` (N,): ``K = [Λ_pp, conj Λ_pw] / S``.

        ``Λ⁺ = Λ − K S Kᴴ`` (Simon 2006, *Optimal State Estimation*, Ch. 5), element-wise.
        """
        S = self._L_pp + self._r_gps
        y = z - self._p
        k_p, k_w = self._L_pp / S, self._L_pw.conjugate() / S
        self._p = self._p + k_p * y
        self._w = self._w + k_w * y
        self._L_ww = self._L_ww - (k_w * self._L_pw).real  # Λ_ww − |Λ_pw|² / S
        self._L_pw = self._L_pw * (1.0 - k_p)
        self._L_pp = self._r_gps * k_p  # Λ_pp (1 − Λ_pp / S) = R Λ_pp / S

    def _update_velocity(self, z: ComplexArray) -> None:
        """GNSS velocity update, ``z = v_N + i v_E`` (N,): ``H = [0, 1]``, ``K = [Λ_pw, Λ_ww]/S``.

        ``Λ⁺ = Λ − K S Kᴴ``: Λ_pp −= |Λ_pw|²/S, Λ_pw −= Λ_pw Λ_ww/S, Λ_ww −= Λ_ww²/S.
        """
        S = self._L_ww + self._r_gps_vel
        y = z - self._w
        k_p, k_w = self._L_pw / S, self._L_ww / S
        self._p = self._p + k_p * y
        self._w = self._w + k_w * y
        self._L_pp = self._L_pp - (k_p * self._L_pw.conjugate()).real
        self._L_pw = self._L_pw * (1.0 - k_w)
        self._L_ww = self._r_gps_vel * k_w

    def _update_heading(self, z: FloatArray) -> None:
        """Compass update with ``z`` (N,) rad: innovation ``ssa(z − ψ⁻)``, ``K = P Hᵀ / S``."""
        S = self._P_psi + self._r_compass
        y = ssa(z - self._psi)
        k_psi, k_b = self._P_psi / S, self._P_pb / S
        self._psi = self._psi + k_psi * y
        self._b = self._b + k_b * y
        self._P_b = self._P_b - k_b * self._P_pb
        self._P_pb = self._P_pb * (1.0 - k_psi)
        self._P_psi = self._r_compass * k_psi  # P_ψψ (1 − P_ψψ / S) = R P_ψψ / S

    def run(
        self,
        eta_traj: FloatArray,
        nu_traj: FloatArray,
        rng: np.random.Generator,
        first_step_index: int,
    ) -> NavEstimate:
        """Filter a stretch of T plant steps (e.g. one decision period of 20 steps).

        Same as ``step(first_step_index + j, eta_traj[:, j], nu_traj[:, j], rng)`` for
        ``j = 0 .. T-1``; loops over T in Python, never over boats.

        Parameters
        ----------
        eta_traj : ndarray, shape (N, T, 3)
            True ``[x_N, y_E, ψ]`` at steps ``first_step_index .. first_step_index + T - 1``.
        nu_traj : ndarray, shape (N, T, 3)
            True ``[u, v, r]`` at the same steps.
        rng : numpy.random.Generator
        first_step_index : int
            Plant step counter of ``eta_traj[:, 0]``.

        Returns
        -------
        NavEstimate
            Arrays of shape (N, T, ...): the estimate after each step.
        """
        k0 = _check_step_index(first_step_index)
        eta = np.asarray(eta_traj, dtype=np.float64)
        nu = np.asarray(nu_traj, dtype=np.float64)
        for name, a in (("eta_traj", eta), ("nu_traj", nu)):
            if a.ndim != 3 or a.shape[0] != self.n_boats or a.shape[2] != 3:
                raise ValueError(f"{name} must have shape ({self.n_boats}, T, 3), got {a.shape}")
        if eta.shape != nu.shape:
            raise ValueError(f"eta_traj {eta.shape} and nu_traj {nu.shape} must have one shape")
        n, T = eta.shape[:2]
        pos, vel = np.empty((n, T, 2)), np.empty((n, T, 2))
        psi, rate = np.empty((n, T)), np.empty((n, T))
        for j in range(T):
            est = self.step(k0 + j, eta[:, j], nu[:, j], rng)
            pos[:, j], vel[:, j], psi[:, j], rate[:, j] = (
                est.pos_ne,
                est.vel_ne,
                est.psi,
                est.yaw_rate,
            )
        return NavEstimate(pos_ne=pos, vel_ne=vel, psi=psi, yaw_rate=rate)

    def _check_states(self, eta: FloatArray, nu: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Validate shape (N, 3) and finiteness of ``eta`` and ``nu``; return float64 arrays."""
        eta = _as_checked("eta", eta, (3,))
        nu = _as_checked("nu", nu, (3,))
        if eta.shape[0] != self.n_boats or nu.shape[0] != self.n_boats:
            raise ValueError(
                f"eta and nu must have {self.n_boats} rows (n_boats), "
                f"got {eta.shape[0]} and {nu.shape[0]}"
            )
        return eta, nu


# --- the filter state as a flat array (the compiled twin's layout, usvsim.nav.compiled) -------

#: Layout of the filter state of one boat (15 entries), as exported by :func:`export_nav_state`
#: and stepped by :func:`usvsim.nav.compiled.build_nav_step`.
NAV_STATE_FIELDS = (
    "p_n", "p_e", "w_n", "w_e", "L_pp", "L_pw_re", "L_pw_im", "L_ww",
    "psi", "b", "P_psi", "P_pb", "P_b", "gyro_bias", "yaw_rate",
)  # fmt: skip
NAV_NS = len(NAV_STATE_FIELDS)


def export_nav_state(nav: Navigator) -> FloatArray:
    """The navigator's filter states as an (N, 15) array (layout :data:`NAV_STATE_FIELDS`)."""
    return np.column_stack([
        nav._p.real, nav._p.imag, nav._w.real, nav._w.imag, nav._L_pp, nav._L_pw.real,
        nav._L_pw.imag, nav._L_ww, nav._psi, nav._b, nav._P_psi, nav._P_pb, nav._P_b,
        nav._gyro_bias, nav._yaw_rate,
    ])  # fmt: skip


def import_nav_state(nav: Navigator, state: FloatArray) -> None:
    """Load (N, 15) filter states (from the compiled path) back into ``nav``."""
    s = np.asarray(state, dtype=np.float64)
    if s.shape != (nav.n_boats, NAV_NS):
        raise ValueError(f"nav state must have shape ({nav.n_boats}, {NAV_NS}), got {s.shape}")
    nav._p = s[:, 0] + 1j * s[:, 1]
    nav._w = s[:, 2] + 1j * s[:, 3]
    nav._L_pp, nav._L_pw, nav._L_ww = s[:, 4].copy(), s[:, 5] + 1j * s[:, 6], s[:, 7].copy()
    nav._psi, nav._b = s[:, 8].copy(), s[:, 9].copy()
    nav._P_psi, nav._P_pb, nav._P_b = s[:, 10].copy(), s[:, 11].copy(), s[:, 12].copy()
    nav._gyro_bias, nav._yaw_rate = s[:, 13].copy(), s[:, 14].copy()
