"""Wind and wave drift loads as CasADi expressions, for the compiled plant kernel.

The same formulas as the NumPy reference functions (tested equal):

* wind: :func:`usvsim.vessel.weather.wind.wind_forces` (Fossen 2021 §10.1) written without
  the angle: cos γ_rw = u_rw / V_rw, sin γ_rw = −v_rw / V_rw give X = −½ρ c_x A_F u_rw V_rw,
  Y = −½ρ c_y A_L v_rw V_rw, N = −ρ c_n A_L L u_rw v_rw (one square root, no atan2), taken as the
  *excess* over the calm-air load, τ_wind(V_w) − τ_wind(0). The hull's surge resistance
  (vessels.py) already lumps the air drag of the boat running through still air (ASSUMED: its
  damping was not identified with the superstructure removed), so only the wind adds a load.
  With V_w = 0 the load is exactly 0 (a gate, not a difference of equal numbers, so that the
  compiled kernel gives today's bits in calm air); at rest it equals τ_wind (ν = 0 gives
  τ_wind(0) = 0), so the drift-at-rest balance of the wind tests is unchanged.
* wave drift: :func:`usvsim.vessel.weather.waves.mean_drift_force` (wall-sided short-wave
  asymptote with Ursell's reflection, Faltinsen 1990 ch. 5). Its spectral integral depends only
  on (H_s, T_p) and is computed once per episode as the drift pressure p_d
  (:func:`usvsim.vessel.weather.waves.drift_pressure`, N/m); the kernel maps it onto the
  illuminated waterline segments for the boat's heading at every sub-step.

Hull data (:class:`WeatherHull`): the windage and waterline of usv105 for every vessel unless
given (ASSUMED for the other presets; their areas and waterlines are not in their sources).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from usvsim.vessel.weather.waves import USV105_WATERLINE, WaterlinePolygon
from usvsim.vessel.weather.wind import RHO_AIR, USV105_WINDAGE, Windage

__all__ = [
    "USV105_HULL",
    "WeatherHull",
    "drift_loads",
    "environment_loads",
    "relative_drift_loads",
    "relative_trig",
    "relative_wind_loads",
    "wind_loads",
]


@dataclass(frozen=True)
class WeatherHull:
    """What the weather acts on: areas and coefficients above water, waterline below."""

    windage: Windage = USV105_WINDAGE
    waterline: WaterlinePolygon = USV105_WATERLINE
    rho_air: float = RHO_AIR  # kg/m³


USV105_HULL = WeatherHull()


def _wind_load(w: Windage, rho_air: float, u_rw: Any, v_rw: Any) -> Any:
    """τ_wind [X, Y, N] for the relative wind (u_rw, v_rw) in body axes (m/s)."""
    speed = ca.sqrt(u_rw**2 + v_rw**2)  # m/s, V_rw
    return ca.vertcat(
        (-0.5 * rho_air * w.c_x * w.frontal_area_m2) * u_rw * speed,
        (-0.5 * rho_air * w.c_y * w.lateral_area_m2) * v_rw * speed,
        (-rho_air * w.c_n * w.lateral_area_m2 * w.length_m) * u_rw * v_rw,
    )


def wind_loads(hull: WeatherHull, nu: Any, psi: Any, speed: Any, direction: Any) -> Any:
    """Wind load in excess of still air [X (N), Y (N), N (N m)] (module docstring).

    ``nu`` [u, v, r] over ground, ``psi`` heading (rad), ``speed`` wind speed (m/s, ≥ 0),
    ``direction`` the direction it blows towards (rad, NED).
    """
    rel = direction - psi
    return relative_wind_loads(hull, nu, speed, ca.cos(rel), ca.sin(rel))


def relative_wind_loads(hull: WeatherHull, nu: Any, speed: Any, cos_rel: Any, sin_rel: Any) -> Any:
    """:func:`wind_loads` given cos and sin of the wind's direction relative to the heading."""
    windy = _wind_load(hull.windage, hull.rho_air, nu[0] - speed * cos_rel, nu[1] - speed * sin_rel)
    still = _wind_load(hull.windage, hull.rho_air, nu[0], nu[1])
    return ca.if_else(speed > 0, windy - still, ca.DM.zeros(3))


def drift_loads(hull: WeatherHull, psi: Any, pressure: Any, direction: Any) -> Any:
    """Mean wave drift [X (N), Y (N), N (N m)] in body axes.

    ``pressure`` p_d = ρ g ∫ S R² dω (N/m) of the sea state, ``direction`` the direction the
    waves travel towards (rad, NED). A segment of length ℓ, outward normal n, lit by waves along
    k̂ (n·k̂ < 0) takes p_d (n·k̂)² ℓ along −n.
    """
    rel = direction - psi
    return relative_drift_loads(hull, pressure, ca.cos(rel), ca.sin(rel))


def relative_drift_loads(hull: WeatherHull, pressure: Any, kx: Any, ky: Any) -> Any:
    """:func:`drift_loads` given k̂ = (cos, sin) of the waves' direction relative to the heading.

    Per segment i the lit share min(n_i·k̂, 0)² (= (n·k̂)² where lit, else 0) times the
    constants −ℓ n_x, −ℓ n_y and the moment arm −ℓ (m_x n_y − m_y n_x) of the waterline; terms
    whose constant is 0 (the sides along x, the stern across) are left out of the sums.
    """
    v = np.asarray(hull.waterline.vertices, dtype=float)
    edge = np.roll(v, -1, axis=0) - v
    length = np.hypot(edge[:, 0], edge[:, 1])
    normal = np.stack([-edge[:, 1], edge[:, 0]], -1) / length[:, None]
    mid = v + 0.5 * edge
    sums: list[Any] = [0.0, 0.0, 0.0]
    for (nx, ny), ell, (mx, my) in zip(normal, length, mid, strict=True):  # 5 segments, symbolic
        nk = (kx * float(nx) if nx else 0.0) + (ky * float(ny) if ny else 0.0)
        lit = ca.fmin(nk, 0.0) ** 2
        for k, const in enumerate((-ell * nx, -ell * ny, -ell * (mx * ny - my * nx))):
            if const != 0.0:
                sums[k] = sums[k] + float(const) * lit
    return pressure * ca.vertcat(*sums)


def environment_loads(
    hull: WeatherHull,
    nu: Any,
    psi: Any,
    wind_speed: Any,
    wind_direction: Any,
    drift_pressure: Any,
    wave_direction: Any,
) -> Any:
    """τ_env = wind excess + wave drift [X (N), Y (N), N (N m)] (see the two functions)."""
    return wind_loads(hull, nu, psi, wind_speed, wind_direction) + drift_loads(
        hull, psi, drift_pressure, wave_direction
    )


def relative_trig(cos_dir: Any, sin_dir: Any, cos_psi: Any, sin_psi: Any) -> tuple[Any, Any]:
    """cos and sin of (β − ψ) from those of a direction β and the heading ψ (angle difference
    formulas): the compiled kernel gets cos β, sin β per episode and shares cos ψ, sin ψ with
    the vessel's kinematics, so the loads cost no trigonometric call."""
    return cos_dir * cos_psi + sin_dir * sin_psi, sin_dir * cos_psi - cos_dir * sin_psi
