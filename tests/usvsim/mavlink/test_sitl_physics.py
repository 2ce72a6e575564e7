"""ArduPilot SITL JSON backend (usvsim.mavlink.sitl_physics) against a fake SITL sending PWM."""

import json
import math
import socket
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from usvsim.mavlink.sitl_physics import (
    JsonPhysics,
    ServoFrame,
    actuator_command,
    pack_servo_frame,
    parse_servo_frame,
    serve,
)
from usvsim.vessel.vessels import get_vessel

RATE_HZ = 50


@pytest.fixture
def backend() -> Iterator[tuple[JsonPhysics, int]]:
    physics = JsonPhysics(get_vessel("default"))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    stop = threading.Event()
    thread = threading.Thread(target=serve, args=(physics, sock, 0.0, stop), daemon=True)
    thread.start()
    yield physics, sock.getsockname()[1]
    stop.set()
    thread.join(5.0)
    sock.close()


def fly(port: int, pwm: list[int], n: int, first: int = 0, channels: int = 16) -> list[dict]:
    """Fake ArduPilot: send n frames, wait (deadline 2 s) for each JSON reply."""
    sitl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sitl.settimeout(2.0)
    replies = []
    try:
        for k in range(first, first + n):
            ch = (pwm + [1500] * channels)[:channels]
            sitl.sendto(pack_servo_frame(ServoFrame(RATE_HZ, k, tuple(ch))), ("127.0.0.1", port))
            data = sitl.recv(4096)
            assert data.startswith(b"\n") and data.endswith(b"\n")
            replies.append(json.loads(data))
    finally:
        sitl.close()
    return replies


def test_frame_codec_round_trip_16_and_32_channels() -> None:
    for n in (16, 32):
        f = ServoFrame(400, 7, tuple(range(1000, 1000 + n)))
        assert parse_servo_frame(pack_servo_frame(f)) == f
    with pytest.raises(ValueError, match="magic"):
        parse_servo_frame(b"\x00" * 40)
    with pytest.raises(ValueError, match="must be 40 bytes"):
        parse_servo_frame(pack_servo_frame(ServoFrame(400, 1, (1500,) * 16))[:-2])


def test_pwm_maps_to_waterjet_thrust_and_nozzle() -> None:
    act = get_vessel("default").actuation
    assert actuator_command(1500, 1500, act) == (0.0, 0.0)
    thrust, nozzle = actuator_command(1900, 1900, act)
    assert thrust == act.a1_max and nozzle == pytest.approx(math.radians(27.0))
    assert actuator_command(1100, 1100, act) == (act.a1_min, -act.a2_max)  # reversing bucket
    assert act.a1_min == pytest.approx(-0.4 * act.a1_max)
    no_bucket = get_vessel("loe-default").actuation
    assert actuator_command(1500, 1100, no_bucket) == (0.0, 0.0)  # no astern thrust


def test_replies_parse_with_increasing_timestamps(backend) -> None:
    _, port = backend
    replies = fly(port, [1500, 1500, 1700], 100)
    t = np.array([r["timestamp"] for r in replies])
    assert np.all(np.diff(t) > 0)
    np.testing.assert_allclose(np.diff(t), 1.0 / RATE_HZ, rtol=1e-9)
    last = replies[-1]
    assert set(last) == {"timestamp", "imu", "position", "velocity", "attitude"}
    assert last["imu"]["accel_body"][2] == pytest.approx(-9.80665)
    assert last["velocity"][0] > 0.5  # throttle forward at heading 0: moving north


def test_boat_turns_the_way_the_steering_pwm_says(backend) -> None:
    _, port = backend
    fly(port, [1500, 1500, 1800], 5 * RATE_HZ)  # 5 s straight, building speed
    right = fly(port, [1900, 1500, 1800], 3 * RATE_HZ, first=5 * RATE_HZ)
    assert right[-1]["imu"]["gyro"][2] > math.radians(3.0)  # starboard: yaw rate > 0
    assert right[-1]["attitude"][2] > math.radians(5.0)
    left = fly(port, [1100, 1500, 1800], 6 * RATE_HZ, first=8 * RATE_HZ)
    assert left[-1]["imu"]["gyro"][2] < -math.radians(3.0)


def test_repeated_frame_is_answered_without_stepping_and_restart_resets(backend) -> None:
    physics, port = backend
    a = fly(port, [1500, 1500, 1800], 10)
    b = fly(port, [1500, 1500, 1800], 1, first=9)  # re-send of frame 9
    assert b[0] == a[-1]
    c = fly(port, [1500, 1500, 1500], 1, first=0, channels=32)  # SITL restarted
    assert c[0]["timestamp"] == pytest.approx(1.0 / RATE_HZ)
    assert physics.last_count == 0
