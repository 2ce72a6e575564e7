"""Navigation estimate of N boats from noisy GNSS, compass and gyro: two linear Kalman filters.

Everything downstream (guidance, observations, the MAVLink bridge) reads the vessel's state from
here, never from the plant's true state.

The filter models and their configuration are in :mod:`usvsim.nav.models`, their update
equations (exact, element-wise over the boats) in :mod:`usvsim.nav.kalman`, the compiled CasADi
twin of :meth:`Navigator.step` in :mod:`usvsim.nav.compiled`. :meth:`Navigator.reset` and
:meth:`Navigator.step` simulate the sensors from the true state, then run the measurement-driven
:meth:`Navigator.start` and :meth:`Navigator.fuse`, which also serve real readings (the MAVLink
bridge's :class:`usvsim.nav.telemetry.TelemetryEstimator`).

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

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.nav.kalman import (
    FilterNoise,
    HeadingState,
    PositionState,
    as_complex,
    as_ne,
    predict_heading,
    predict_position,
    update_heading,
    update_position,
    update_velocity,
)
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import (
    as_checked,
    check_step_index,
    draw_compass,
    draw_gps,
    draw_gps_velocity,
    draw_gyro,
    period_steps,
)
from usvsim.nav.start import first_fix, start_variances

__all__ = ["NavEstimate", "Navigator"]

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
        self._noise = FilterNoise.from_config(cfg)
        self._gps_period = period_steps(cfg.sensors.gps_rate_hz, cfg.dt_s)
        self._compass_period = period_steps(cfg.sensors.compass_rate_hz, cfg.dt_s)

        n = self.n_boats
        nan, cnan = np.full(n, np.nan), np.full(n, np.nan + 0j)
        self._pos = PositionState(
            p=cnan, w=cnan.copy(), L_pp=nan, L_pw=cnan.copy(), L_ww=nan.copy()
        )
        self._head = HeadingState(*(nan.copy() for _ in range(5)))
        self._yaw_rate = nan.copy()  # bias-corrected gyro rate g − b̂, rad/s
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
        idx = self._boats(mask)
        fix = first_fix(self.cfg, eta[idx], nu[idx], rng)
        self._gyro_bias = self._gyro_bias.copy()  # copy: earlier estimates may view it
        self._gyro_bias[idx] = fix.gyro_bias_radps
        return self._start(idx, as_complex(fix.pos_ne), fix.vel_ne, fix.heading_rad, fix.gyro_radps)

    def start(
        self,
        pos_ne: FloatArray,
        vel_ne: FloatArray,
        heading_rad: FloatArray,
        gyro_radps: FloatArray,
    ) -> NavEstimate:
        """Start the filters of all boats at a given first fix (real sensors, telemetry).

        The measurement-driven half of :meth:`reset`, which draws these readings from the true
        state and then calls it: the same means and covariances.

        Parameters
        ----------
        pos_ne : ndarray, shape (N, 2)
            GNSS position [x_N, y_E] (m).
        vel_ne : ndarray, shape (N, 2)
            GNSS velocity over ground [v_N, v_E] (m/s).
        heading_rad : ndarray, shape (N,)
            Compass heading (rad).
        gyro_radps : ndarray, shape (N,)
            Gyro yaw rate (rad/s); the first yaw-rate estimate (the bias estimate starts at 0).

        Returns
        -------
        NavEstimate
            The estimate of all N boats.
        """
        p = as_complex(self._checked_rows("pos_ne", pos_ne, (2,)))
        w = as_complex(self._checked_rows("vel_ne", vel_ne, (2,)))
        psi = self._checked_rows("heading_rad", heading_rad, ())
        gyro = self._checked_rows("gyro_radps", gyro_radps, ())
        return self._start(np.arange(self.n_boats), p, w, psi, gyro)

    def _start(
        self,
        idx: NDArray[np.intp],
        p: ComplexArray,
        w: ComplexArray,
        psi: FloatArray,
        gyro: FloatArray,
    ) -> NavEstimate:
        """Set boats ``idx`` to the first fix ``p``, ``w`` (complex NE), ``psi`` and ``gyro``."""
        L_pp, L_ww, P_psi, P_b = start_variances(self.cfg)

        def rows(old: NDArray[Any], value: object) -> NDArray[Any]:
            new = old.copy()  # copy: earlier NavEstimates view the old array
            new[idx] = value
            return new

        x, h = self._pos, self._head
        self._pos = PositionState(
            p=rows(x.p, p),
            w=rows(x.w, w),
            L_pp=rows(x.L_pp, L_pp),
            L_pw=rows(x.L_pw, 0.0),
            L_ww=rows(x.L_ww, L_ww),
        )
        self._head = HeadingState(
            psi=rows(h.psi, psi),
            b=rows(h.b, 0.0),
            P_psi=rows(h.P_psi, P_psi),
            P_pb=rows(h.P_pb, 0.0),
            P_b=rows(h.P_b, P_b),
        )
        self._yaw_rate = rows(self._yaw_rate, gyro)
        self._ready[idx] = True
        self._all_ready = bool(self._ready.all())
        return self.estimate

    @property
    def estimate(self) -> NavEstimate:
        """Current estimate of all N boats (arrays of shape (N, ...), read them, don't write)."""
        return NavEstimate(
            pos_ne=as_ne(self._pos.p),
            vel_ne=as_ne(self._pos.w),
            psi=self._head.psi,
            yaw_rate=self._yaw_rate,
        )

    @property
    def gyro_bias_estimate(self) -> FloatArray:
        """Estimated gyro bias b̂ of each boat (rad/s), shape (N,)."""
        return self._head.b

    @property
    def true_gyro_bias(self) -> FloatArray:
        """Simulated true gyro bias of each boat (rad/s), shape (N,), for diagnostics."""
        return self._gyro_bias

    @property
    def position_covariance(self) -> FloatArray:
        """Covariance of ``[x_N, y_E, v_N, v_E]``, shape (N, 4, 4) (m², m²/s, m²/s²)."""
        return self._pos.covariance

    @property
    def heading_covariance(self) -> FloatArray:
        """Covariance of ``[ψ, b]``, shape (N, 2, 2) (rad², rad²/s, rad²/s²)."""
        return self._head.covariance

    @property
    def filter_state(self) -> tuple[PositionState, HeadingState]:
        """Means and covariances of both filters of all N boats (read them, don't write)."""
        return self._pos, self._head

    def load_state(
        self,
        pos: PositionState,
        head: HeadingState,
        yaw_rate: FloatArray,
        true_gyro_bias: FloatArray,
    ) -> None:
        """Replace the filter states of all N boats (e.g. stepped in compiled code), shapes (N,)."""
        self._pos, self._head = pos, head
        self._yaw_rate, self._gyro_bias = yaw_rate, true_gyro_bias

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
        k = check_step_index(step_index)
        if not self._all_ready:
            raise RuntimeError("Navigator.reset() must initialise every boat before step()")
        eta, nu = self._check_states(eta_true, nu_true)
        s = self.cfg.sensors
        gyro = draw_gyro(nu[:, 2], self._gyro_bias, rng, s)
        gps = vel = compass = None
        if k % self._gps_period == 0:
            gps = draw_gps(eta[:, :2], rng, s)
            if self.cfg.gnss_velocity:
                # true velocity over ground R(ψ)[u, v] = (u + i v) e^{iψ}
                vel_true = (nu[:, 0] + 1j * nu[:, 1]) * np.exp(1j * eta[:, 2])
                vel = draw_gps_velocity(as_ne(vel_true), rng, s)
        if k % self._compass_period == 0:
            # Unwrapped reading: the innovation is wrapped, so ssa here would be redundant.
            compass = draw_compass(eta[:, 2], rng, s, wrap=False)
        return self._fuse(gyro, gps, vel, compass, 1)

    def fuse(
        self,
        gyro_radps: FloatArray,
        pos_ne: FloatArray | None = None,
        vel_ne: FloatArray | None = None,
        heading_rad: FloatArray | None = None,
        n_predict: int = 1,
    ) -> NavEstimate:
        """Advance the filters with given sensor readings (real sensors, telemetry).

        The measurement-driven half of :meth:`step`, which draws these readings from the true
        state and then calls it: ``n_predict`` time updates of ``dt_s`` each with the gyro
        reading, then the GNSS position, GNSS velocity and compass updates of the readings
        given (``None``: that sensor did not fire), ψ wrapped to [-π, π) at the end.

        Parameters
        ----------
        gyro_radps : ndarray, shape (N,)
            Gyro yaw rate (rad/s), held over the ``n_predict`` steps.
        pos_ne : ndarray, shape (N, 2), optional
            GNSS position [x_N, y_E] (m).
        vel_ne : ndarray, shape (N, 2), optional
            GNSS velocity over ground [v_N, v_E] (m/s), fused whatever ``cfg.gnss_velocity``
            says (that flag only switches the simulated receiver of :meth:`step`).
        heading_rad : ndarray, shape (N,), optional
            Compass heading (rad), any range: the innovation is wrapped.
        n_predict : int
            Plant steps since the last call (>= 0), e.g. more than 1 after lost telemetry.

        Returns
        -------
        NavEstimate
            The estimate after the readings, arrays of shape (N, ...).
        """
        if not self._all_ready:
            raise RuntimeError("Navigator.start() or reset() must initialise every boat first")
        gyro = self._checked_rows("gyro_radps", gyro_radps, ())
        pos = None if pos_ne is None else self._checked_rows("pos_ne", pos_ne, (2,))
        vel = None if vel_ne is None else self._checked_rows("vel_ne", vel_ne, (2,))
        psi = None if heading_rad is None else self._checked_rows("heading_rad", heading_rad, ())
        if (
            isinstance(n_predict, bool)
            or not isinstance(n_predict, (int, np.integer))
            or n_predict < 0
        ):
            raise ValueError(f"n_predict must be a non-negative integer, got {n_predict!r}")
        return self._fuse(gyro, pos, vel, psi, int(n_predict))

    def _fuse(
        self,
        gyro: FloatArray,
        pos_ne: FloatArray | None,
        vel_ne: FloatArray | None,
        heading: FloatArray | None,
        n_predict: int,
    ) -> NavEstimate:
        """:meth:`fuse` without input checks (for :meth:`step`)."""
        x, h, q = self._pos, self._head, self._noise
        for _ in range(n_predict):
            omega = gyro - h.b  # bias-corrected rate with the prior bias, rad/s
            h, x = predict_heading(h, omega, q), predict_position(x, omega, q)
        if pos_ne is not None:
            x = update_position(x, as_complex(pos_ne), q)
        if vel_ne is not None:
            x = update_velocity(x, as_complex(vel_ne), q)
        if heading is not None:
            h = update_heading(h, heading, q)
        self._pos, self._head = x, replace(h, psi=ssa(h.psi))
        self._yaw_rate = gyro - h.b
        return self.estimate

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
        k0 = check_step_index(first_step_index)
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
            pos[:, j], vel[:, j] = est.pos_ne, est.vel_ne
            psi[:, j], rate[:, j] = est.psi, est.yaw_rate
        return NavEstimate(pos_ne=pos, vel_ne=vel, psi=psi, yaw_rate=rate)

    def _boats(self, mask: NDArray[np.bool_] | None) -> NDArray[np.intp]:
        """Indices of the boats in ``mask`` (all when ``None``), after checking it."""
        if mask is None:
            return np.arange(self.n_boats)
        m = np.asarray(mask)
        if m.dtype != np.bool_ or m.shape != (self.n_boats,):
            raise ValueError(
                f"mask must be a bool array of shape ({self.n_boats},), "
                f"got dtype {m.dtype} and shape {m.shape}"
            )
        return np.flatnonzero(m)

    def _checked_rows(self, name: str, array: object, tail: tuple[int, ...]) -> FloatArray:
        """``array`` as float64 of shape (N, *tail), finite; raise ``ValueError`` otherwise."""
        a = as_checked(name, array, tail)
        if a.shape[0] != self.n_boats:
            raise ValueError(f"{name} must have {self.n_boats} rows (n_boats), got {a.shape[0]}")
        return a

    def _check_states(self, eta: FloatArray, nu: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Validate shape (N, 3) and finiteness of ``eta`` and ``nu``; return float64 arrays."""
        return self._checked_rows("eta", eta, (3,)), self._checked_rows("nu", nu, (3,))
