"""Preprocessing (study Sect. 3.5.1): timestamp matching, actions, observations, tlog import."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from learning.imitation.demonstrations import SITE_ORIGIN, Recording
from learning.imitation.preprocess import (
    decision_track,
    encode_actions,
    expert_data,
    interpolate_heading,
    interpolate_position,
    recording_from_tlog,
)
from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import Attitude, GlobalPosition
from usvsim.nav.geo import geodetic_from_ned
from usvsim.task.observations import relative_polar

POLES = [[0.0, 0.0], [500.0, 500.0]]


def _heading(t: np.ndarray) -> np.ndarray:
    """A known heading profile crossing north (wrap): 350° + 25° sin(t / 6)."""
    return np.radians(350.0 + 25.0 * np.sin(t / 6.0))


def _position(t: np.ndarray) -> np.ndarray:
    """Positions of a 3 m/s boat on that heading (fine numerical integration)."""
    tf = np.linspace(0.0, 80.0, 80001)
    v = 3.0 * np.column_stack([np.cos(_heading(tf)), np.sin(_heading(tf))])
    xy = np.vstack([[0.0, 0.0], np.cumsum((v[1:] + v[:-1]) / 2 * np.diff(tf)[:, None], axis=0)])
    return np.column_stack([np.interp(t, tf, xy[:, 0]), np.interp(t, tf, xy[:, 1])]) + np.array(
        [-60.0, 0.0]
    )


def _synthetic(rng: np.random.Generator) -> Recording:
    t_gps = np.arange(0.3, 75.0, 1 / 1.3)
    t_gps = np.sort(t_gps + rng.normal(0, 0.02, t_gps.size))
    t_cmp = np.arange(0.05, 75.0, 1 / 7.0)
    t_cmp = np.sort(t_cmp + rng.normal(0, 0.01, t_cmp.size))
    ne = _position(t_gps)
    meta = {
        "format": "usvsim-demo/1",
        "run": 0,
        "pole_index": 0,
        "poles_ne": POLES,
        "pole_radius_m": 1.0,
        "origin_lat_deg": SITE_ORIGIN.lat_deg,
        "origin_lon_deg": SITE_ORIGIN.lon_deg,
    }
    return Recording(
        meta,
        t_gps,
        geodetic_from_ned(ne[:, 0], ne[:, 1], SITE_ORIGIN),
        t_cmp,
        np.mod(_heading(t_cmp), 2 * np.pi),
        np.zeros(0),
        np.zeros(0),
        np.zeros(0),
    )


def test_round_trip_recovers_known_actions() -> None:
    rec = _synthetic(np.random.default_rng(0))
    track = decision_track(rec)
    assert np.allclose(np.diff(track.t_s), 2.0)
    truth = np.degrees(np.diff(np.unwrap(_heading(track.t_s))))
    # linear interpolation between 7 Hz samples of a smooth profile: error < 0.01°
    np.testing.assert_allclose(np.degrees(track.heading_change_rad), truth, atol=0.01)
    np.testing.assert_allclose(track.pos_ne, _position(track.t_s), atol=0.02)
    np.testing.assert_allclose(track.goal_ne, _position(rec.gps_t_s[-1:])[0], atol=1e-6)


def test_matching_with_jitter_and_different_rates() -> None:
    rng = np.random.default_rng(3)
    t_fix = np.sort(rng.uniform(0.0, 10.0, 11))  # irregular, ~1 Hz
    t_cmp = np.sort(np.arange(0.0, 10.0, 0.1) + rng.normal(0, 0.01, 100))  # 10 Hz, jittered
    query = np.array([2.0, 4.0, 6.0])
    line = np.column_stack([2.0 * t_fix, -1.0 * t_fix])  # uniform motion: linear is exact
    np.testing.assert_allclose(
        interpolate_position(query, t_fix, line), np.column_stack([2 * query, -query]), atol=1e-12
    )
    psi = np.radians(170.0 + 5.0 * t_cmp)  # crosses ±180° at t = 2 s
    np.testing.assert_allclose(
        np.degrees(interpolate_heading(query, t_cmp, psi)), [-180.0, -170.0, -160.0], atol=1e-9
    )
    with pytest.raises(ValueError, match="outside the GPS span"):
        interpolate_position(np.array([t_fix[0] - 1.0]), t_fix, line)


def test_categorical_and_gaussian_encoding() -> None:
    dpsi = np.radians([-30.0, -31.0, -1.5, 0.0, 0.7, 0.8, 29.9, 45.0])
    np.testing.assert_array_equal(
        encode_actions(dpsi, "categorical"), [0, 0, 19, 20, 20, 21, 40, 40]
    )
    np.testing.assert_allclose(
        encode_actions(dpsi, "gaussian")[:, 0],
        [-1, -1, -0.05, 0, 0.7 / 30, 0.8 / 30, 29.9 / 30, 1],
        atol=1e-7,
    )


def test_observations_regenerated_by_the_env_builder() -> None:
    rec = _synthetic(np.random.default_rng(1))
    data = expert_data([rec], "positional", "categorical")
    track = data.tracks[0]
    r_p, b_p = relative_polar(track.pos_ne[:-1], track.psi_rad[:-1], np.zeros((len(data), 2)))
    np.testing.assert_allclose(data.obs[:, 0], r_p, rtol=1e-6)
    np.testing.assert_allclose(data.obs[:, 1], b_p, atol=1e-6)
    assert data.obs[-1, 2] == pytest.approx(np.hypot(*(track.goal_ne - track.pos_ne[-2])), rel=1e-6)
    assert data.last.sum() == 1 and data.last[-1]
    radar = expert_data([rec], "radar+goal", "gaussian")
    assert radar.obs["radar"].shape == (len(data), 1, 50, 119)
    lit = radar.obs["radar"].reshape(len(data), -1).max(axis=1) == 255
    np.testing.assert_array_equal(lit, np.abs(b_p) <= math.radians(120.0))  # pole in view


def test_tlog_import_reads_a_pymavlink_log(tmp_path: Path) -> None:
    path = tmp_path / "drive.tlog"
    sink = MavlinkLink("udpin:127.0.0.1:0")
    boat = MavlinkLink(
        f"udpout:127.0.0.1:{sink.local_port}", system_id=1, component_id=1, tlog_path=path
    )
    t_gps = np.arange(0.0, 30.0, 0.5)
    t_att = np.arange(0.1, 30.0, 0.1)
    ne = _position(t_gps)
    latlon = geodetic_from_ned(ne[:, 0], ne[:, 1], SITE_ORIGIN)
    events = [(t, "g", i) for i, t in enumerate(t_gps)] + [(t, "a", i) for i, t in enumerate(t_att)]
    for t, kind, i in sorted(events):
        if kind == "g":
            boat.send_global_position(
                GlobalPosition(round(t * 1e3), latlon[i, 0], latlon[i, 1], 3.0, 0.0, math.nan)
            )
        else:
            yaw = float(np.angle(np.exp(1j * _heading(np.array([t]))[0])))
            boat.send_attitude(Attitude(round(t * 1e3), 0.0, 0.0, yaw, 0.0))
    boat.close()
    sink.close()
    rec = recording_from_tlog(path, origin=SITE_ORIGIN, poles_ne=POLES, pole_index=0)
    assert rec.gps_t_s.size == t_gps.size and rec.compass_t_s.size == t_att.size
    np.testing.assert_allclose(rec.gps_ne, ne, atol=0.02)  # 1e-7 deg ≈ 1 cm
    track = decision_track(rec)
    truth = np.degrees(np.diff(np.unwrap(_heading(track.t_s))))
    np.testing.assert_allclose(np.degrees(track.heading_change_rad), truth, atol=0.01)
