"""Flat-earth geodetic <-> NED conversion (usvsim.nav.geo)."""

import math

import numpy as np
import pytest

from usvsim.nav.geo import WGS84_A_M, GeoOrigin, geodetic_from_ned, ned_from_geodetic


def test_one_degree_of_longitude_on_the_equator_is_a_pi_over_180() -> None:
    ne = ned_from_geodetic(0.0, 1.0, GeoOrigin(0.0, 0.0))
    assert ne[1] == pytest.approx(WGS84_A_M * math.pi / 180.0, rel=1e-12)
    assert ne[0] == 0.0


def test_one_arc_minute_of_latitude_on_the_equator_uses_the_meridian_radius() -> None:
    # R_M(0) = a (1 - e²) = 6 335 439.327 m (WGS-84) -> 1' = 1842.905 m
    ne = ned_from_geodetic(1.0 / 60.0, 0.0, GeoOrigin(0.0, 0.0))
    assert ne[0] == pytest.approx(1842.905, abs=1e-3)


def test_east_distance_shrinks_with_cos_latitude() -> None:
    o60 = GeoOrigin(60.0, 10.0)
    east = ned_from_geodetic(60.0, 10.001, o60)[1]
    assert east == pytest.approx(math.radians(0.001) * o60.normal_radius_m * 0.5, rel=1e-9)


def test_round_trip_is_exact_to_micrometres() -> None:
    origin = GeoOrigin(63.4305, 10.3951)  # Trondheim harbour
    rng = np.random.default_rng(0)
    ne = rng.uniform(-500.0, 500.0, (100, 2))
    latlon = geodetic_from_ned(ne[:, 0], ne[:, 1], origin)
    back = ned_from_geodetic(latlon[:, 0], latlon[:, 1], origin)
    assert np.max(np.abs(back - ne)) < 1e-6


def test_longitude_difference_wraps_across_the_antimeridian() -> None:
    origin = GeoOrigin(0.0, 179.9999)
    ne = ned_from_geodetic(0.0, -179.9999, origin)
    assert ne[1] == pytest.approx(WGS84_A_M * math.radians(0.0002), rel=1e-9)


@pytest.mark.parametrize(("lat", "lon"), [(90.0, 0.0), (0.0, 181.0), (math.nan, 0.0)])
def test_bad_origin_raises(lat: float, lon: float) -> None:
    with pytest.raises(ValueError, match="origin"):
        GeoOrigin(lat, lon)
