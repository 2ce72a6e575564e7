"""Latitude/longitude <-> local NED (north, east) around an origin: flat-earth, WGS-84 radii.

The flat-earth approximation linearises the geodetic-to-NED transformation at the origin
(Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed., §2.4,
eqs. 2.112, 2.118-2.119; Farrell 2008, *Aided Navigation*, §2.3.3)::

    x_N = (μ − μ0) (R_M + h0)               R_M = a (1 − e²) / (1 − e² sin² μ0)^{3/2}
    y_E = ssa(l − l0) (R_N + h0) cos μ0     R_N = a / (1 − e² sin² μ0)^{1/2}

with μ the latitude, l the longitude (rad), R_M the meridian and R_N the prime-vertical radius
of curvature of the WGS-84 ellipsoid (NIMA TR8350.2: a = 6 378 137 m, f = 1/298.257223563).
The error grows with the square of the distance: under 1 cm for the few hundred metres of a
pole-avoidance mission. Altitude is ignored (h0 = 0, a boat at sea level).

>>> o = GeoOrigin(0.0, 0.0)
>>> round(float(ned_from_geodetic(0.0, 1.0, o)[1]), 3)
111319.491
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.common.angles import ssa

__all__ = ["WGS84_A_M", "WGS84_F", "GeoOrigin", "geodetic_from_ned", "ned_from_geodetic"]

WGS84_A_M = 6_378_137.0  # m, semi-major axis (NIMA TR8350.2, Table 3.1)
WGS84_F = 1.0 / 298.257223563  # -, flattening (NIMA TR8350.2, Table 3.1)
_E2 = WGS84_F * (2.0 - WGS84_F)  # -, first eccentricity squared


@dataclass(frozen=True)
class GeoOrigin:
    """Origin of the local NED frame: latitude and longitude in degrees (WGS-84).

    Raises
    ------
    ValueError
        If the latitude is outside [-89, 89]° (the flat-earth frame degenerates at the poles)
        or the longitude outside [-180, 180]°, or either is not finite.
    """

    lat_deg: float
    lon_deg: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lat_deg) and -89.0 <= self.lat_deg <= 89.0):
            raise ValueError(
                f"origin latitude must be finite and in [-89, 89] deg, got {self.lat_deg!r}"
            )
        if not (math.isfinite(self.lon_deg) and -180.0 <= self.lon_deg <= 180.0):
            raise ValueError(
                f"origin longitude must be finite and in [-180, 180] deg, got {self.lon_deg!r}"
            )

    @property
    def meridian_radius_m(self) -> float:
        """R_M (m), radius of curvature in the meridian at the origin."""
        s2 = math.sin(math.radians(self.lat_deg)) ** 2
        return WGS84_A_M * (1.0 - _E2) / (1.0 - _E2 * s2) ** 1.5

    @property
    def normal_radius_m(self) -> float:
        """R_N (m), radius of curvature in the prime vertical at the origin."""
        s2 = math.sin(math.radians(self.lat_deg)) ** 2
        return WGS84_A_M / math.sqrt(1.0 - _E2 * s2)


def ned_from_geodetic(
    lat_deg: ArrayLike, lon_deg: ArrayLike, origin: GeoOrigin
) -> NDArray[np.float64]:
    """North and east (m) of points given in degrees; shape ``(..., 2)`` for inputs ``(...)``.

    Longitude differences are wrapped with :func:`usvsim.common.angles.ssa`, so a mission across the
    ±180° meridian works.
    """
    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    d_lat = np.radians(lat - origin.lat_deg)
    d_lon = ssa(np.radians(lon - origin.lon_deg))
    north = d_lat * origin.meridian_radius_m
    east = d_lon * origin.normal_radius_m * math.cos(math.radians(origin.lat_deg))
    return np.stack(np.broadcast_arrays(north, east), axis=-1)


def geodetic_from_ned(
    north_m: ArrayLike, east_m: ArrayLike, origin: GeoOrigin
) -> NDArray[np.float64]:
    """Latitude and longitude (deg) of NED points (m); shape ``(..., 2)``, the exact inverse
    of :func:`ned_from_geodetic` (longitude wrapped to [-180, 180))."""
    north = np.asarray(north_m, dtype=float)
    east = np.asarray(east_m, dtype=float)
    lat = origin.lat_deg + np.degrees(north / origin.meridian_radius_m)
    d_lon = east / (origin.normal_radius_m * math.cos(math.radians(origin.lat_deg)))
    lon = np.degrees(ssa(np.radians(origin.lon_deg) + d_lon))
    return np.stack(np.broadcast_arrays(lat, lon), axis=-1)
