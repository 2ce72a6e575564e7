"""Wind: per-episode mean speed and direction, gusts, and the forces on the hull above water.

Forces and yaw moment (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion
Control*, 2nd ed., §10.1, the "ships at high speed" form)::

    u_w = V_w cos(β_w - ψ),  v_w = V_w sin(β_w - ψ)        (wind velocity in body axes)
    u_rw = u - u_w,  v_rw = v - v_w,  V_rw² = u_rw² + v_rw²,  γ_rw = -atan2(v_rw, u_rw)
    X = ½ ρ_a V_rw² C_X A_F,  Y = ½ ρ_a V_rw² C_Y A_L,  N = ½ ρ_a V_rw² C_N A_L L_oa
    C_X = -c_x cos γ_rw,  C_Y = c_y sin γ_rw,  C_N = c_n sin 2γ_rw

β_w is the direction the wind blows TOWARDS (rad, NED, as Fossen's β_Vw); a wind "from the
north" has β_w = π. Fossen gives c_x ∈ [0.50, 0.90], c_y ∈ [0.70, 0.95], c_n ∈ [0.05, 0.20].

Gusts: the wind speed is V_w(t) = V̄ + g(t) with g a first-order Gauss–Markov process
ġ = -g / T_g + w (the process Fossen 2021 §10.3 uses for a slowly varying current; a simpler
stand-in for the Harris and NORSOK gust spectra of §10.1, which it does not reproduce), discretised
exactly: g_{k+1} = a g_k + σ_g √(1 - a²) ξ_k, a = exp(-Δt / T_g), stationary std σ_g = I_u V̄.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.common.errors import UserError

__all__ = [
    "RHO_AIR",
    "USV105_WINDAGE",
    "WIND_SPEED_MAX_MPS",
    "GustParams",
    "WindState",
    "Windage",
    "draw_wind",
    "gust_step",
    "wind_coefficients",
    "wind_forces",
]

RHO_AIR = 1.225  # kg/m³, ISO 2533 standard atmosphere at sea level, 15 °C
WIND_SPEED_MAX_MPS = 40.0  # m/s, accepted mean wind (Beaufort 12 starts at 32.7 m/s, WMO No. 8)


@dataclass(frozen=True)
class Windage:
    """Projected areas above water and wind coefficients of one hull (Fossen 2021 §10.1)."""

    frontal_area_m2: float  # m², A_F: projection on the y-z plane
    lateral_area_m2: float  # m², A_L: projection on the x-z plane
    length_m: float  # m, L_oa, moment arm scale of C_N
    c_x: float = 0.70  # -, Fossen 2021 §10.1 range [0.50, 0.90]; midpoint ASSUMED
    c_y: float = 0.825  # -, Fossen 2021 §10.1 range [0.70, 0.95]; midpoint ASSUMED
    c_n: float = 0.125  # -, Fossen 2021 §10.1 range [0.05, 0.20]; midpoint ASSUMED

    def __post_init__(self) -> None:
        for name in ("frontal_area_m2", "lateral_area_m2", "length_m"):
            if not getattr(self, name) > 0:
                raise UserError(f"Windage.{name} must be > 0, got {getattr(self, name)}")


# usv105 (L = 10.5 m, B = 3.5 m, Vedeler 2019): no drawing of the superstructure was found, so the
# heights are ASSUMED: freeboard 1.0 m over the length, a wheelhouse 4.0 m long, 2.5 m wide and
# 1.5 m high. A_F = 3.5 * 1.0 + 2.5 * 1.5 = 7.25 m², A_L = 10.5 * 1.0 + 4.0 * 1.5 = 16.5 m².
USV105_WINDAGE = Windage(frontal_area_m2=7.25, lateral_area_m2=16.5, length_m=10.5)


@dataclass(frozen=True)
class GustParams:
    """First-order Gauss–Markov gust model (module docstring)."""

    intensity: float = 0.10  # -, σ_g / V̄; ASSUMED, offshore turbulence intensity is ~0.06-0.12
    time_constant_s: float = 10.0  # s, T_g; ASSUMED (order of L_u / V̄ for a ~100 m scale)

    def __post_init__(self) -> None:
        if not 0.0 <= self.intensity <= 0.5:
            raise UserError(f"gust intensity must lie in [0, 0.5], got {self.intensity}")
        if not self.time_constant_s > 0:
            raise UserError(f"gust time constant must be > 0 s, got {self.time_constant_s}")


@dataclass(frozen=True)
class WindState:
    """Wind of N boats: mean speed (m/s), direction towards (rad, NED) and gust (m/s), each (N,)."""

    mean_speed_mps: NDArray[np.float64]
    direction_rad: NDArray[np.float64]
    gust_mps: NDArray[np.float64]

    @property
    def speed_mps(self) -> NDArray[np.float64]:
        """Instantaneous wind speed V̄ + g (m/s, ≥ 0), shape (N,)."""
        return np.maximum(self.mean_speed_mps + self.gust_mps, 0.0)


def _check_speed(speed: NDArray[np.float64]) -> None:
    if not np.all(np.isfinite(speed)) or np.any(speed < 0) or np.any(speed > WIND_SPEED_MAX_MPS):
        raise UserError(
            f"wind speed must lie in [0, {WIND_SPEED_MAX_MPS:g}] m/s, got "
            f"{np.atleast_1d(speed).tolist()[:4]}"
        )


def draw_wind(
    rng: np.random.Generator,
    n: int,
    speed_range_mps: tuple[float, float],
    direction_rad: float | None = None,
    gusts: GustParams = GustParams(),
) -> WindState:
    """Draw one episode's wind for ``n`` boats: V̄ ~ U(range), β_w ~ U[0, 2π) unless given.

    The gust starts from its stationary distribution N(0, σ_g²), so there is no transient.
    """
    lo, hi = speed_range_mps
    _check_speed(np.array([lo, hi], dtype=float))
    if lo > hi:
        raise UserError(f"wind speed range must be (low, high) with low <= high, got {lo}, {hi}")
    if direction_rad is not None and not math.isfinite(direction_rad):
        raise UserError(f"wind direction must be a finite angle in rad, got {direction_rad}")
    mean = rng.uniform(lo, hi, size=n)
    if direction_rad is None:
        direction = rng.uniform(0.0, 2.0 * math.pi, size=n)
    else:
        direction = np.full(n, float(direction_rad))
    gust = gusts.intensity * mean * rng.standard_normal(n)
    return WindState(mean, direction, gust)


def gust_step(
    state: WindState,
    rng: np.random.Generator,
    dt_s: float,
    gusts: GustParams = GustParams(),
) -> WindState:
    """Advance the gusts of every boat by ``dt_s`` (exact discretisation of ġ = -g/T_g + w)."""
    a = math.exp(-dt_s / gusts.time_constant_s)
    sigma = gusts.intensity * state.mean_speed_mps
    gust = a * state.gust_mps + sigma * math.sqrt(1.0 - a * a) * rng.standard_normal(
        state.gust_mps.shape
    )
    return WindState(state.mean_speed_mps, state.direction_rad, gust)


def wind_coefficients(
    gamma_rw: ArrayLike, windage: Windage = USV105_WINDAGE
) -> NDArray[np.float64]:
    """C_X, C_Y, C_N at relative wind angle γ_rw (rad, 0: wind on the bow); shape (..., 3)."""
    g = np.asarray(gamma_rw, dtype=float)
    return np.stack(
        [-windage.c_x * np.cos(g), windage.c_y * np.sin(g), windage.c_n * np.sin(2.0 * g)], -1
    )


def wind_forces(
    nu: ArrayLike,
    psi_rad: ArrayLike,
    speed_mps: ArrayLike,
    direction_rad: ArrayLike,
    windage: Windage = USV105_WINDAGE,
    rho_air: float = RHO_AIR,
) -> NDArray[np.float64]:
    """τ_wind = [X (N), Y (N), N (N m)] on N boats, shape (N, 3) (module docstring's equations).

    ``nu`` (N, 3) body velocities [u, v, r] over ground (m/s, rad/s), ``psi_rad`` (N,) heading,
    ``speed_mps`` (N,) wind speed, ``direction_rad`` (N,) direction the wind blows towards.
    """
    nu = np.atleast_2d(np.asarray(nu, dtype=float))
    rel = np.asarray(direction_rad, dtype=float) - np.asarray(psi_rad, dtype=float)
    speed = np.asarray(speed_mps, dtype=float)
    u_rw = nu[:, 0] - speed * np.cos(rel)
    v_rw = nu[:, 1] - speed * np.sin(rel)
    q = 0.5 * rho_air * (u_rw**2 + v_rw**2)  # Pa, dynamic pressure of the relative wind
    c = wind_coefficients(-np.arctan2(v_rw, u_rw), windage)
    scale = np.array(
        [
            windage.frontal_area_m2,
            windage.lateral_area_m2,
            windage.lateral_area_m2 * windage.length_m,
        ]
    )
    return q[:, None] * c * scale
