"""The typed MAVLink adapter (usvsim.mavlink.link) on loopback: OS-assigned ports, deadlines."""

import math
import socket
import struct
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mav2

from usvsim.mavlink import messages
from usvsim.mavlink.link import LinkLostError, MavlinkLink, load_signing_key, read_tlog
from usvsim.mavlink.messages import (
    TYPE_MASK_VELOCITY_YAW,
    CommandLong,
    GlobalPosition,
    Heartbeat,
    MavCommand,
    Received,
    RoverMode,
    SetAttitudeTarget,
    SetPositionTarget,
)

KEY = bytes(range(32))


@pytest.fixture
def pair() -> Iterator[tuple[MavlinkLink, MavlinkLink]]:
    vehicle = MavlinkLink("udpin:127.0.0.1:0", system_id=1, component_id=1)
    gcs = MavlinkLink(f"udpout:127.0.0.1:{vehicle.local_port}")
    yield vehicle, gcs
    gcs.close()
    vehicle.close()


def collect(
    link: MavlinkLink, want: Callable[[list[Received]], bool], timeout_s: float = 2.0
) -> list[Received]:
    got: list[Received] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not want(got):
        got += link.poll(0.05)
    return got


def test_type_mask_is_rovers_velocity_and_yaw() -> None:
    # ignore x y z (7), vz (32), ax ay az (448), yaw rate (2048); use vx, vy, yaw
    assert TYPE_MASK_VELOCITY_YAW == 2535


@pytest.mark.parametrize(
    "name",
    [n for n in messages.__all__ if n.startswith("MAV_")],
)
def test_message_constants_equal_pymavlinks(name: str) -> None:
    """The pure-Python enum values of usvsim.mavlink.messages are MAVLink common.xml's."""
    assert getattr(messages, name) == getattr(mav2, name)


def test_mav_commands_equal_pymavlinks() -> None:
    ours = [int(c) for c in MavCommand]
    assert ours == [176, 400, 511, 512, 520, 11]
    assert ours == [
        mav2.MAV_CMD_DO_SET_MODE,
        mav2.MAV_CMD_COMPONENT_ARM_DISARM,
        mav2.MAV_CMD_SET_MESSAGE_INTERVAL,
        mav2.MAV_CMD_REQUEST_MESSAGE,
        mav2.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
        mav2.MAVLINK_MSG_ID_SET_MODE,
    ]


def test_sensor_and_ekf_bits_equal_pymavlinks() -> None:
    from usvsim.mavlink.messages import EKF, SysStatusSensor

    names = {"GYRO": "3D_GYRO", "ACCEL": "3D_ACCEL", "MAG": "3D_MAG"}
    for bit in SysStatusSensor:
        assert bit.name is not None
        plain = bit.name in ("PREARM_CHECK", "GEOFENCE", "AHRS")
        full = "MAV_SYS_STATUS_" + ("" if plain else "SENSOR_")
        assert int(bit) == getattr(mav2, full + names.get(bit.name, bit.name))
    for flag in EKF:
        assert int(flag) == getattr(mav2, f"EKF_{flag.name}")


def test_heading_setpoint_is_forward_speed_with_absolute_yaw(pair) -> None:
    vehicle, gcs = pair
    gcs.send_heading(1, math.radians(200.0), 2.5)  # a southerly heading: vx must stay > 0
    got = collect(vehicle, lambda g: len(g) >= 1)
    sp = got[0].message
    assert isinstance(sp, SetPositionTarget)
    assert (sp.frame, sp.type_mask, sp.vx_mps, sp.vy_mps) == (1, 2535, 2.5, 0.0)
    assert sp.yaw_rad == pytest.approx(math.radians(200.0), abs=1e-6)
    assert sp.uses_velocity_and_yaw


def test_attitude_target_carries_yaw_and_thrust(pair) -> None:
    vehicle, gcs = pair
    gcs.send_attitude_target(1, -2.0, 0.5)
    sp = collect(vehicle, lambda g: len(g) >= 1)[0].message
    assert isinstance(sp, SetAttitudeTarget)
    assert sp.type_mask == 7 and sp.thrust == 0.5
    assert sp.yaw_rad == pytest.approx(-2.0, abs=1e-6)


def test_commands_are_command_long(pair) -> None:
    vehicle, gcs = pair
    gcs.set_mode(1, RoverMode.GUIDED)
    gcs.arm(1)
    gcs.request_message_interval(1, "GLOBAL_POSITION_INT", 10.0)
    got = [r.message for r in collect(vehicle, lambda g: len(g) >= 3)]
    assert got == [
        CommandLong(1, 1, 176, (1.0, 15.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
        CommandLong(1, 1, 400, (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
        CommandLong(1, 1, 511, (33.0, 100000.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
    ]


def test_vehicle_telemetry_round_trip(pair) -> None:
    vehicle, gcs = pair
    gcs.send_gcs_heartbeat()  # the UDP server learns our address
    collect(vehicle, lambda g: len(g) >= 1)
    vehicle.send_vehicle_heartbeat(RoverMode.GUIDED, armed=True)
    vehicle.send_global_position(GlobalPosition(1500, 63.1234567, 10.7654321, 1.25, -0.5, 1.0))
    got = collect(gcs, lambda g: len(g) >= 2)
    hb, pos = got[0].message, got[1].message
    assert isinstance(hb, Heartbeat) and hb.armed and hb.is_boat_or_rover
    assert hb.custom_mode == 15 and got[0].src_system == 1
    assert isinstance(pos, GlobalPosition)
    assert (pos.time_boot_ms, pos.vn_mps, pos.ve_mps) == (1500, 1.25, -0.5)
    assert pos.lat_deg == pytest.approx(63.1234567, abs=1e-9)
    assert pos.heading_rad == pytest.approx(1.0, abs=1e-3)  # centidegrees


def test_malformed_bytes_are_dropped_and_parsing_recovers(pair) -> None:
    vehicle, gcs = pair
    gcs.send_raw(b"\x00\x01garbage\xff" * 4)
    gcs.send_raw(bytes([0xFD, 3, 0, 0, 0, 255, 190, 0, 0, 0, 1, 2, 3, 0xAA, 0xBB]))  # bad CRC
    gcs.arm(1)
    got = collect(vehicle, lambda g: any(isinstance(r.message, CommandLong) for r in g))
    assert any(isinstance(r.message, CommandLong) for r in got)
    assert vehicle.bad_packets >= 1


def test_signing_rejects_unsigned_and_accepts_signed() -> None:
    vehicle = MavlinkLink("udpin:127.0.0.1:0", system_id=1, component_id=1, signing_key=KEY)
    unsigned = MavlinkLink(f"udpout:127.0.0.1:{vehicle.local_port}")
    signed = MavlinkLink(f"udpout:127.0.0.1:{vehicle.local_port}", signing_key=KEY)
    try:
        unsigned.arm(1)
        signed.set_mode(1, RoverMode.HOLD)
        got = collect(vehicle, lambda g: len(g) >= 1)
        assert [r.message.command for r in got if isinstance(r.message, CommandLong)] == [176]
        assert vehicle.rejected_unsigned == 1
    finally:
        for link in (unsigned, signed, vehicle):
            link.close()


def test_tlog_records_both_directions(pair, tmp_path: Path) -> None:
    vehicle, _ = pair
    path = tmp_path / "link.tlog"
    gcs = MavlinkLink(f"udpout:127.0.0.1:{vehicle.local_port}", tlog_path=path)
    gcs.send_gcs_heartbeat()
    collect(vehicle, lambda g: len(g) >= 1)
    vehicle.send_vehicle_heartbeat(RoverMode.HOLD, armed=False)
    collect(gcs, lambda g: len(g) >= 1)
    gcs.close()
    data = path.read_bytes()
    # [8-byte big-endian µs][MAVLink 2 packet]: heartbeat = 10 + 9 payload + 2 CRC = 21 bytes
    assert len(data) == 2 * (8 + 21)
    assert data[8] == 0xFD and data[8 + 29] == 0xFD
    assert abs(int.from_bytes(data[:8], "big") / 1e6 - time.time()) < 60
    decoded = read_tlog(path)
    assert [(r.src_system, type(r.message).__name__) for _, r in decoded] == [
        (255, "Heartbeat"),
        (1, "Heartbeat"),
    ]


def test_signing_key_file_formats(tmp_path: Path) -> None:
    raw, hexfile, bad = tmp_path / "raw", tmp_path / "hex", tmp_path / "bad"
    raw.write_bytes(KEY)
    hexfile.write_text(KEY.hex() + "\n")
    bad.write_text("secret-but-short")
    assert load_signing_key(raw) == KEY == load_signing_key(hexfile)
    with pytest.raises(ValueError) as err:
        load_signing_key(bad)
    assert "secret" not in str(err.value)


def test_a_peer_reset_mid_read_is_a_lost_link_not_a_traceback() -> None:
    """RST after data: the readiness check sees the data, the read then meets ECONNRESET.

    Found by CI: a vehicle closing its end while the bridge read raised pymavlink's raw
    ``ConnectionResetError`` instead of :class:`LinkLostError`, so no failsafe ran.
    """
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    link = MavlinkLink(f"tcp:127.0.0.1:{server.getsockname()[1]}")
    peer, _ = server.accept()
    mav = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
    frame = mav.heartbeat_encode(10, 3, 0, 0, 0).pack(mav)
    peer.sendall(frame + frame[:5])  # one whole packet, then half of the next
    peer.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    peer.close()  # linger 0: the kernel sends RST, not FIN
    server.close()
    time.sleep(0.05)
    with pytest.raises(LinkLostError, match="reset by the peer"):
        for _ in range(3):
            link.poll(0.05)
    assert link.lost is not None
    with pytest.raises(LinkLostError):
        link.poll(0.0)  # stays lost
    link.close()
