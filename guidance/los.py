"""Line-of-sight (LOS) guidance for straight-line path following of N boats.

Three guidance laws give a heading reference from the path errors of :mod:`guidance.waypoints`
(π_p path-tangential angle, y_e cross-track error, Δ lookahead distance):

``los``   proportional LOS (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion
          Control*, 2nd ed., §12.4.2; MSS ``LOSchi``)::

              ψ_d = π_p − atan(y_e / Δ)

          Used as a *heading* reference (our autopilot steers heading), a current or sideslip
          crossing the path leaves a steady offset: sin(atan(y_e/Δ)) = V_⊥/U, e.g.
          y_e = Δ tan(asin(V_⊥/U)) = 3.38 m for V_⊥ = 0.5 m/s, U = 3 m/s, Δ = 20 m
          (3.27 m measured with the plant in tests/test_guidance.py).
``ilos``  integral LOS (Børhaug, Pavlov & Pettersen 2008, "Integral LOS control for path
          following of underactuated marine surface vessels in the presence of constant ocean
          currents", IEEE CDC; Fossen 2021, §12.4.3; MSS ``ILOSpsi``)::

              ψ_d = π_p − atan((y_e + κ y_int) / Δ)
              ẏ_int = Δ y_e / (Δ² + (y_e + κ y_int)²)

``alos``  adaptive LOS (Fossen 2023, "An adaptive line-of-sight (ALOS) guidance law for path
          following of aircraft and marine craft", IEEE TCST 31(6), 2887–2894; MSS ``ALOSpsi``)::

              ψ_d = π_p − β̂ − atan(y_e / Δ)
              dβ̂/dt = γ Δ / √(Δ² + y_e²) · y_e

          β̂ estimates the crab angle (sideslip + current) and removes the offset.

Both integral states are propagated with forward Euler after the command is formed, as MSS does.
Linearised about the path (y_e ≪ Δ) at speed U both close the loop ÿ_e + (U/Δ) ẏ_e + U g y_e = 0
with g = κ/Δ² (ILOS) or g = γ (ALOS); critical damping at κ = U/4, γ = U/(4Δ²). The defaults
(Δ = 20 m, U = 3 m/s) are about 2/3 of critical, overdamped in this model; the vessel's
autopilot and sway lags still give a few metres of overshoot from a 20 m offset (see the tests).

LOS observer
------------
The raw command jumps when the segment switches. It is smoothed by a second-order observer
(after MSS ``LOSobserver``; we use the α-β form with the gains of a critically damped pair of
poles at −ω_f, stated in the task brief, instead of MSS's filtered differentiator)::

    e = ssa(ψ_d − ψ̂),   ψ̂[k+1] = ψ̂[k] + h (r̂[k] + K1 e),   r̂[k+1] = r̂[k] + h K2 e
    K1 = 2 ω_f,  K2 = ω_f²  ⇒  ψ̂/ψ_d = (K1 s + K2) / (s + ω_f)²

ψ̂ is the heading reference, r̂ an estimate of the LOS rate (usable as a feed-forward). The
discrete error dynamics have the double eigenvalue 1 − h ω_f, so the observer is stable for
0 < h ω_f < 2 (dead-beat at h ω_f = 1). Jump bound: from rest (e = r̂ = 0) a command jump A
moves ψ̂ in the next step by exactly h K1 A and, as the continuous step response's rate
A ω_f e^{−ω_f t} (2 − ω_f t) peaks at t = 0, by no more than h K1 |A| in any later step (plus the
LOS command's own rate, ≤ U/Δ). Without the observer the reference jumps by the full A.
After a reset the observer starts at the boat's measured heading, so engaging guidance does not
jump the reference either.

Section numbers of Fossen (2021) are cited from memory (ch. 12, straight-line LOS path following);
the formulas themselves are checked against MSS ``LOSchi``/``ILOSpsi``/``ALOSpsi``.

Shapes: ``pos_m`` (N, 2) [x_N, y_E] m, ``psi_rad`` (N,), all outputs (N,).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from guidance.waypoints import (
    WaypointPath,
    advance_segments,
    as_mask,
    as_positions,
    check_switch_radius,
)
from usvsim.common.angles import ssa

__all__ = [
    "GuidanceLaw",
    "GuidanceOutput",
    "GuidanceState",
    "LOSConfig",
    "LOSGuidance",
    "initial_guidance_state",
    "los_step",
    "reset_guidance_state",
]

GuidanceLaw = Literal["los", "ilos", "alos"]


@dataclass(frozen=True)
class LOSConfig:
    """LOS guidance parameters (defaults: the 8 m default vessel at U = 3 m/s)."""

    law: GuidanceLaw = "alos"  # -, guidance law: "los", "ilos" or "alos"
    lookahead_m: float = 20.0  # m, Δ; ~2.5 lengths of the 8.3 m default boat (ASSUMED, tuned)
    switch_radius_m: float = 10.0  # m, R_switch, circle of acceptance (MSS ``ILOSpsi``)
    kappa_mps: float = 0.5  # m/s, ILOS integral gain κ; critical damping at κ = U/4 (see module)
    gamma_radpms: float = 1.25e-3  # rad/(m s), ALOS adaptation gain γ; critical γ = U/(4 Δ²)
    observer_omega_radps: float | None = 0.5  # rad/s, LOS observer ω_f (K1 = 2ω_f, K2 = ω_f²);
    # None passes the raw LOS command through. MSS ``LOSobserver`` suggests K_f of 0.1-0.5.

    def __post_init__(self) -> None:
        if self.law not in ("los", "ilos", "alos"):
            raise ValueError(f"law must be 'los', 'ilos' or 'alos', got {self.law!r}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "law" or value is None:
                continue
            if not np.isfinite(value):
                raise ValueError(f"LOSConfig.{f.name} must be finite, got {value}")
        if self.lookahead_m <= 0:
            raise ValueError(f"lookahead_m (Δ) must be > 0 m, got {self.lookahead_m}")
        if self.switch_radius_m <= 0:
            raise ValueError(f"switch_radius_m must be > 0 m, got {self.switch_radius_m}")
        if self.kappa_mps < 0 or self.gamma_radpms < 0:
            raise ValueError(
                f"kappa_mps and gamma_radpms must be ≥ 0, got {self.kappa_mps}, {self.gamma_radpms}"
            )
        if self.observer_omega_radps is not None and self.observer_omega_radps <= 0:
            raise ValueError(
                f"observer_omega_radps must be > 0 or None, got {self.observer_omega_radps}"
            )

    @property
    def observer_gains(self) -> tuple[float, float]:
        """(K1 [1/s], K2 [1/s²]) of the LOS observer; (0, 0) without observer."""
        w = self.observer_omega_radps
        return (0.0, 0.0) if w is None else (2.0 * w, w * w)


@dataclass(frozen=True)
class GuidanceState:
    """Guidance state of N boats; all arrays (N,)."""

    segment: NDArray[np.int64]  # -, active waypoint segment
    y_int: NDArray[np.float64]  # s, ILOS integral state (ẏ_int is dimensionless, κ y_int in m)
    beta_hat: NDArray[np.float64]  # rad, ALOS crab-angle estimate β̂
    psi_hat: NDArray[np.float64]  # rad, LOS observer angle ψ̂ (the heading reference)
    r_hat: NDArray[np.float64]  # rad/s, LOS observer rate r̂
    observer_ready: NDArray[np.bool_]  # -, False until the first update after a reset

    @property
    def n_boats(self) -> int:
        return int(self.segment.shape[0])


@dataclass(frozen=True)
class GuidanceOutput:
    """One guidance update of N boats; all arrays (N,)."""

    psi_ref_rad: NDArray[np.float64]  # rad, heading reference for the autopilot (observer output)
    psi_los_rad: NDArray[np.float64]  # rad, raw LOS command ψ_d (before the observer)
    r_ref_radps: NDArray[np.float64]  # rad/s, observer LOS-rate estimate r̂ (0 without observer)
    cross_track_m: NDArray[np.float64]  # m, y_e on the active segment (> 0 starboard of path)
    along_track_m: NDArray[np.float64]  # m, x_e from the active segment's start
    segment: NDArray[np.int64]  # -, active segment after this update
    switched: NDArray[np.bool_]  # -, segment advanced in this update
    finished: NDArray[np.bool_]  # -, within R_switch (along track) of the last waypoint


def initial_guidance_state(n_boats: int) -> GuidanceState:
    """Zero integral states, segment 0, observer waiting for its first heading."""
    z = np.zeros(n_boats)
    return GuidanceState(
        segment=np.zeros(n_boats, dtype=np.int64),
        y_int=z,
        beta_hat=z.copy(),
        psi_hat=z.copy(),
        r_hat=z.copy(),
        observer_ready=np.zeros(n_boats, dtype=bool),
    )


def reset_guidance_state(state: GuidanceState, mask: NDArray[np.bool_]) -> GuidanceState:
    """State with boats ``mask`` (N,) bool back to their initial values."""
    fresh = initial_guidance_state(state.n_boats)
    return GuidanceState(
        **{
            f.name: np.where(mask, getattr(fresh, f.name), getattr(state, f.name))
            for f in fields(GuidanceState)
        }
    )


def los_step(
    config: LOSConfig,
    path: WaypointPath,
    state: GuidanceState,
    pos_m: ArrayLike,
    psi_rad: ArrayLike,
    dt_s: float,
) -> tuple[GuidanceState, GuidanceOutput]:
    """One guidance update of N boats (pure function; see the module docstring for the laws).

    Parameters
    ----------
    config, path, state
        Parameters, waypoints (N boats) and the guidance state before the update.
    pos_m : (N, 2)
        Boat positions [x_N, y_E] (m), e.g. the navigation estimate.
    psi_rad : (N,)
        Measured headings (rad); used only to start the observer after a reset.
    dt_s : float
        Time since the last update (s), the Euler step h of the integral states and observer.

    Returns
    -------
    (GuidanceState, GuidanceOutput)
        The new state and the heading reference with the path errors.
    """
    n = path.n_boats
    if state.n_boats != n:
        raise ValueError(f"state has {state.n_boats} boats, path has {n}")
    pos = as_positions(pos_m, n)
    psi = np.asarray(psi_rad, dtype=float)
    if psi.shape != (n,) or not np.all(np.isfinite(psi)):
        raise ValueError(f"psi_rad must be finite with shape ({n},), got shape {psi.shape}")
    k1, k2 = config.observer_gains
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise ValueError(f"dt_s must be > 0 s, got {dt_s}")
    if config.observer_omega_radps is not None and dt_s * config.observer_omega_radps >= 2.0:
        raise ValueError(
            f"LOS observer unstable: dt_s · observer_omega_radps must be < 2, got "
            f"{dt_s} · {config.observer_omega_radps}"
        )

    err = advance_segments(path, state.segment, pos, config.switch_radius_m)
    y_e, delta, h = err.cross_track_m, config.lookahead_m, float(dt_s)
    y_int, beta_hat = state.y_int, state.beta_hat
    if config.law == "los":
        psi_d = err.path_angle_rad - np.arctan(y_e / delta)
    elif config.law == "ilos":
        s = y_e + config.kappa_mps * y_int
        psi_d = err.path_angle_rad - np.arctan(s / delta)
        y_int = y_int + h * delta * y_e / (delta**2 + s**2)
    else:  # "alos"
        psi_d = err.path_angle_rad - beta_hat - np.arctan(y_e / delta)
        beta_hat = beta_hat + h * config.gamma_radpms * delta * y_e / np.hypot(delta, y_e)
    psi_d = ssa(psi_d)

    if config.observer_omega_radps is None:
        psi_hat, r_hat = psi_d, np.zeros(n)
    else:
        psi_hat = np.where(state.observer_ready, state.psi_hat, ssa(psi))
        r_hat = np.where(state.observer_ready, state.r_hat, 0.0)
        e = ssa(psi_d - psi_hat)
        psi_hat, r_hat = ssa(psi_hat + h * (r_hat + k1 * e)), r_hat + h * k2 * e

    new_state = GuidanceState(
        segment=err.segment,
        y_int=y_int,
        beta_hat=beta_hat,
        psi_hat=psi_hat,
        r_hat=r_hat,
        observer_ready=np.ones(n, dtype=bool),
    )
    out = GuidanceOutput(
        psi_ref_rad=psi_hat,
        psi_los_rad=psi_d,
        r_ref_radps=r_hat,
        cross_track_m=y_e,
        along_track_m=err.along_track_m,
        segment=err.segment,
        switched=err.switched,
        finished=err.finished,
    )
    return new_state, out


class LOSGuidance:
    """LOS guidance of N boats: holds the path and :class:`GuidanceState`, calls :func:`los_step`.

    Parameters
    ----------
    path : WaypointPath
        Waypoints of the N boats.
    config : LOSConfig, optional
        Guidance law and parameters; default :class:`LOSConfig`.

    Examples
    --------
    >>> path = WaypointPath.from_lists([[(0.0, 0.0), (200.0, 0.0)]])
    >>> g = LOSGuidance(path, LOSConfig(law="los", observer_omega_radps=None))
    >>> out = g.update(np.array([[50.0, 20.0]]), np.array([0.0]), dt_s=0.1)
    >>> round(float(out.cross_track_m[0]), 3), round(float(out.psi_ref_rad[0]), 4)
    (20.0, -0.7854)
    """

    def __init__(self, path: WaypointPath, config: LOSConfig | None = None) -> None:
        self.config = config if config is not None else LOSConfig()
        check_switch_radius(path, self.config.switch_radius_m)
        self.path = path
        self.state = initial_guidance_state(path.n_boats)

    @property
    def n_boats(self) -> int:
        return self.path.n_boats

    def reset(self, mask: ArrayLike | None = None, path: WaypointPath | None = None) -> None:
        """Reset boats ``mask`` (N,) bool (default all): segment 0, zero integrals, observer
        restarted from the next measured heading; with ``path``, those boats take its waypoints.
        """
        m = as_mask(mask, self.n_boats)
        if path is not None:
            new_path = self.path.replace_rows(m, path)
            check_switch_radius(new_path, self.config.switch_radius_m)
            self.path = new_path
        self.state = reset_guidance_state(self.state, m)

    def update(self, pos_m: ArrayLike, psi_rad: ArrayLike, dt_s: float) -> GuidanceOutput:
        """Advance the guidance by ``dt_s`` (s) for positions (N, 2) m and headings (N,) rad."""
        self.state, out = los_step(self.config, self.path, self.state, pos_m, psi_rad, dt_s)
        return out
