"""A ground-station session against ``usvsim sitl`` with plain pymavlink, as MAVProxy does it on
connect: autopilot version, parameter fetch, read and set, mission list and upload (and the
empty fence and rally lists), mode changes both ways, arming and disarming, AUTO along the
uploaded mission, mission clear. Every request must be answered (deadlines, loopback)."""

import math
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav2

from usvsim.mavlink.rover_protocol import sitl_parameters
from usvsim.mavlink.sitl import RoverSitl, SitlArgs
from usvsim.nav.geo import GeoOrigin, geodetic_from_ned
from usvsim.vessel.autopilot import AutopilotConfig

LAT, LON = 63.4305, 10.3951


@pytest.fixture
def session() -> Iterator[tuple[RoverSitl, Any]]:
    args = SitlArgs(listen="udpin:127.0.0.1:0", speedup=100.0, ekf_delay_s=0.0, lat=LAT, lon=LON)
    sitl = RoverSitl(args)
    with sitl.serving_in_background(60.0):
        conn = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{sitl.link.local_port}", source_system=255, source_component=190
        )
        conn.mav = mav2.MAVLink(conn, srcSystem=255, srcComponent=190)
        conn.mav.heartbeat_send(6, 8, 0, 0, 4)  # the SITL learns our address from it
        assert conn.wait_heartbeat(timeout=5.0) is not None
        yield sitl, conn
        conn.close()


def receive(
    conn: Any, kind: str, until: Callable[[Any], bool] = lambda m: True, timeout_s: float = 5.0
) -> Any:
    """The first ``kind`` message for which ``until`` holds, within the deadline."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        m = conn.recv_match(type=kind, blocking=True, timeout=min(left, 0.2))
        if m is not None and until(m):
            return m
    raise AssertionError(f"no {kind} within {timeout_s} s")


def ack(conn: Any, command: int) -> int:
    m = receive(conn, "COMMAND_ACK", lambda m: m.command == command)
    assert (m.target_system, m.target_component) == (255, 190)
    return int(m.result)


def test_version_and_parameters(session: tuple[RoverSitl, Any]) -> None:
    sitl, conn = session
    conn.mav.request_data_stream_send(1, 1, 0, 4, 1)  # MAVProxy's first request: harmless
    conn.mav.command_long_send(1, 1, mav2.MAV_CMD_REQUEST_MESSAGE, 0, 148, 0, 0, 0, 0, 0, 0)
    version = receive(conn, "AUTOPILOT_VERSION")
    assert version.flight_sw_version >> 24 == 4 and version.capabilities & 4
    assert ack(conn, mav2.MAV_CMD_REQUEST_MESSAGE) == 0

    conn.mav.param_request_list_send(1, 1)  # "param fetch"
    names = [p.name for p in sitl_parameters(1, 3.0, 5.0, 2.0, 100.0, AutopilotConfig())]
    got: dict[int, Any] = {}
    while len(got) < len(names):
        m = receive(conn, "PARAM_VALUE")
        assert m.param_count == len(names)
        got[m.param_index] = m
    assert [got[i].param_id for i in range(len(names))] == names

    conn.mav.param_request_read_send(1, 1, b"WP_SPEED", -1)
    assert receive(conn, "PARAM_VALUE").param_value == pytest.approx(3.0)
    conn.mav.param_request_read_send(1, 1, b"", 0)
    assert receive(conn, "PARAM_VALUE").param_id == names[0]
    conn.mav.param_set_send(1, 1, b"WP_SPEED", 4.0, mav2.MAV_PARAM_TYPE_REAL32)
    m = receive(conn, "PARAM_VALUE", lambda m: m.param_id == "WP_SPEED")
    assert m.param_value == pytest.approx(4.0) and sitl.params["WP_SPEED"] == 4.0
    conn.mav.param_set_send(1, 1, b"LOIT_RADIUS", -1.0, mav2.MAV_PARAM_TYPE_REAL32)
    m = receive(conn, "PARAM_VALUE", lambda m: m.param_id == "LOIT_RADIUS")
    assert m.param_value == pytest.approx(2.0)  # refused: the value in force comes back
    conn.mav.param_set_send(1, 1, b"ATC_STR_RAT_FF", 0.5, mav2.MAV_PARAM_TYPE_REAL32)
    receive(conn, "PARAM_VALUE", lambda m: m.param_id == "ATC_STR_RAT_FF")
    assert sitl.autopilot.rover_rate_ff == pytest.approx(0.5)


def download(conn: Any, mission_type: int = 0) -> list[Any]:
    conn.mav.mission_request_list_send(1, 1, mission_type)
    count = receive(conn, "MISSION_COUNT", lambda m: m.mission_type == mission_type).count
    items = []
    for seq in range(count):
        conn.mav.mission_request_int_send(1, 1, seq, mission_type)
        items.append(receive(conn, "MISSION_ITEM_INT", lambda m, s=seq: m.seq == s))
    conn.mav.mission_ack_send(1, 1, 0, mission_type)
    return items


def upload(conn: Any, points: list[tuple[float, float]]) -> int:
    """Home placeholder + NAV_WAYPOINTs, answering the vehicle's requests; the ACK result."""
    items = [(LAT, LON), *points]
    conn.mav.mission_count_send(1, 1, len(items), 0)
    while True:
        m = receive(conn, ["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"])
        if m.get_type() == "MISSION_ACK":
            return int(m.type)
        lat, lon = items[m.seq]
        conn.mav.mission_item_int_send(
            1, 1, m.seq, 6, 16, 0, 1, 0, 0, 0, 0, round(lat * 1e7), round(lon * 1e7), 0.0, 0
        )


def test_mission_list_upload_auto_and_clear(session: tuple[RoverSitl, Any]) -> None:
    sitl, conn = session
    home = download(conn)  # "wp list" on a fresh vehicle: home only
    assert len(home) == 1 and home[0].x == round(LAT * 1e7)
    assert download(conn, 1) == [] and download(conn, 2) == []  # fence, rally: empty
    origin = GeoOrigin(LAT, LON)
    ne = [(60.0, 0.0), (60.0, 60.0)]
    points = [tuple(float(v) for v in geodetic_from_ned(n, e, origin)) for n, e in ne]
    assert upload(conn, points) == mav2.MAV_MISSION_ACCEPTED
    listed = download(conn)
    assert len(listed) == 3 and [it.command for it in listed[1:]] == [16, 16]
    assert [(it.x, it.y) for it in listed[1:]] == [
        (round(a * 1e7), round(b * 1e7)) for a, b in points
    ]

    conn.mav.command_long_send(1, 1, 176, 0, 1, 10, 0, 0, 0, 0, 0)  # DO_SET_MODE AUTO
    assert ack(conn, 176) == 0
    conn.arducopter_arm()
    assert ack(conn, 400) == 0
    reached = [receive(conn, "MISSION_ITEM_REACHED", timeout_s=10.0).seq for _ in range(2)]
    assert reached == [1, 2]
    assert np.hypot(*(sitl.state.x[0, 0:2] - np.array(ne[1]))) < 10.0  # WP_RADIUS 5 m

    conn.mav.mission_clear_all_send(1, 1, 0)
    assert receive(conn, "MISSION_ACK").type == 0
    assert len(download(conn)) == 1


def test_mode_changes_and_arming_are_answered(session: tuple[RoverSitl, Any]) -> None:
    sitl, conn = session
    conn.mav.set_mode_send(1, 1, 15)  # MAVProxy "mode GUIDED" (the SET_MODE message)
    assert ack(conn, 11) == 0
    conn.mav.command_long_send(1, 1, 176, 0, 1, 5, 0, 0, 0, 0, 0)  # LOITER by command
    assert ack(conn, 176) == 0
    conn.mav.command_long_send(1, 1, 176, 0, 1, 10, 0, 0, 0, 0, 0)  # AUTO, no mission
    reason = receive(conn, "STATUSTEXT", lambda m: "AUTO" in m.text)  # sent before the ACK
    assert "no waypoint" in reason.text
    assert ack(conn, 176) == mav2.MAV_RESULT_FAILED
    conn.arducopter_arm()
    assert ack(conn, 400) == 0
    hb = receive(conn, "HEARTBEAT", lambda m: m.base_mode & 128)
    assert hb.custom_mode == 5
    conn.arducopter_disarm()
    assert ack(conn, 400) == 0
    receive(conn, "HEARTBEAT", lambda m: not m.base_mode & 128)
    status = receive(conn, "SYS_STATUS")
    assert not status.onboard_control_sensors_present & mav2.MAV_SYS_STATUS_GEOFENCE
    assert status.onboard_control_sensors_health & mav2.MAV_SYS_STATUS_PREARM_CHECK
    assert sitl.mode == 5 and not sitl.armed and math.isfinite(sitl.time_ms)
