"""ArduPilot SITL JSON backend (usvsim.mavlink.sitl_physics) against a fake SITL sending PWM.

Every reply is read the way ArduPilot reads it: :func:`sim_json_scan` re-implements the key
scanning of ``libraries/SITL/SIM_JSON.cpp`` (``JSON::parse_sensors`` and the keytable of
``SIM_JSON.h``), not Python's ``json``, which also accepts what SITL cannot read.
"""

import json
import math
import re
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from usvsim.mavlink.sitl_physics import (
    JsonPhysics,
    ServoFrame,
    ServoMapping,
    SitlPhysicsArgs,
    actuator_command,
    pack_servo_frame,
    parse_servo_frame,
    serve,
)
from usvsim.vessel.vessels import get_vessel

RATE_HZ = 50

# SIM_JSON.h keytable: (section, key, type, required); "" is the top level
SIM_JSON_KEYS = (
    ("", "timestamp", "double", True),
    ("imu", "gyro", "vector3f", True),
    ("imu", "accel_body", "vector3f", True),
    ("", "position", "vector3d", True),
    ("", "attitude", "vector3f", False),
    ("", "quaternion", "quaternion", False),
    ("", "velocity", "vector3f", True),
)
# what strtod/atof and sscanf("%f") accept after leading whitespace (decimal forms only; the
# hexadecimal, inf and nan forms would be accepted by C too, and are refused here on purpose)
_C_FLOAT = re.compile(r"[ \t\n\v\f\r]*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)")


def _c_float(text: str, at: int) -> tuple[float, int]:
    """``%f`` / ``atof`` at ``text[at:]``: the value and the index after it (ValueError if none)."""
    m = _C_FLOAT.match(text, at)
    if m is None:
        raise ValueError(f"no number at {text[at : at + 12]!r}")
    return float(m.group(1)), m.end()


def _c_vector(text: str, at: int, n: int) -> list[float]:
    """``sscanf(p, "[%f, %f, %f]")``: '[' and ',' are literals that must be the next character;
    the format's space matches any whitespace, even none; %f skips leading whitespace."""
    if text[at : at + 1] != "[":
        raise ValueError(f"expected '[' at {text[at : at + 12]!r}")
    values, i = [], at + 1
    for k in range(n):
        value, i = _c_float(text, i)
        values.append(value)
        if k < n - 1:
            if text[i : i + 1] != ",":
                raise ValueError(f"expected ',' at {text[i : i + 12]!r}")
            i += 1
    return values


def sim_json_scan(line: str) -> dict[str, object]:
    """Read one sensor line as SIM_JSON.cpp does; ValueError where SITL would fail.

    For each key: ``p = strstr(json, section) + strlen(section) + 1``, ``p = strstr(p, key)``,
    ``p += strlen(key) + 2``, then ``atof(p)`` or ``sscanf(p, "[%f, %f, %f]")``.
    """
    out: dict[str, object] = {}
    for section, key, kind, required in SIM_JSON_KEYS:
        p = line.find(section)
        if p < 0:
            if required:
                raise ValueError(f"Failed to find {section}")
            continue
        p = line.find(key, p + len(section) + 1)
        if p < 0:
            if required:
                raise ValueError(f"Failed to find key {section}/{key}")
            continue
        p += len(key) + 2
        if kind == "double":
            out[key] = _c_float(line, p)[0]
        else:
            try:
                out[key] = _c_vector(line, p, 4 if kind == "quaternion" else 3)
            except ValueError as err:
                raise ValueError(f"Failed to parse Vector3f for {section}/{key}: {err}") from None
    if "attitude" not in out and "quaternion" not in out:
        raise ValueError("Did not receive attitude or quaternion")
    return out


def sitl_reads(datagram: bytes) -> dict[str, object]:
    """recv_fdm: newlines become NULs and the line between the last two is parsed."""
    text = datagram.decode("ascii")
    lines = text.split("\n")
    assert len(lines) >= 3 and lines[-1] == "", "a reply must be a line between two newlines"
    return sim_json_scan(lines[-2])


@pytest.fixture
def backend() -> Iterator[tuple[JsonPhysics, int]]:
    with serving(JsonPhysics(get_vessel("default"))) as served:
        yield served


@contextmanager
def serving(physics: JsonPhysics) -> Iterator[tuple[JsonPhysics, int]]:
    """``physics`` served on a loopback port the OS chose, in a thread, until the block ends."""
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
            scanned = sitl_reads(data)  # what ArduPilot reads, strictly
            reply = json.loads(data)
            assert scanned["timestamp"] == reply["timestamp"]
            for key in ("gyro", "accel_body"):
                np.testing.assert_allclose(scanned[key], reply["imu"][key], rtol=1e-15)
            for key in ("position", "velocity", "attitude"):
                np.testing.assert_allclose(scanned[key], reply[key], rtol=1e-15)
            replies.append(reply)
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


def test_sim_json_scanner_refuses_what_sitl_cannot_read() -> None:
    """The scanner reproduces the failure real ArduPilot showed with json.dumps' defaults."""
    state = JsonPhysics(get_vessel("default")).state_dict()
    with pytest.raises(ValueError, match="Failed to parse Vector3f for imu/gyro"):
        sim_json_scan(json.dumps(state))  # '"gyro": [' : the space after the colon
    assert sim_json_scan(json.dumps(state, separators=(",", ":")))["timestamp"] == 0.0
    with pytest.raises(ValueError, match="Failed to find key imu/accel_body"):
        sim_json_scan('{"timestamp":1,"imu":{"gyro":[0,0,0]},"position":[0,0,0]}')
    with pytest.raises(ValueError, match="expected ','"):
        sim_json_scan(json.dumps(state, separators=(" ,", ":")))


def test_pwm_maps_to_waterjet_thrust_and_nozzle() -> None:
    act = get_vessel("default").actuation
    assert actuator_command(1500, 1500, act) == (0.0, 0.0)
    thrust, nozzle = actuator_command(2000, 2000, act)  # rover.parm SERVOn_MAX
    assert thrust == act.a1_max and nozzle == pytest.approx(math.radians(27.0))
    assert actuator_command(1000, 1000, act) == (act.a1_min, -act.a2_max)  # reversing bucket
    assert actuator_command(1750, 1750, act) == pytest.approx((0.5 * act.a1_max, 0.5 * act.a2_max))
    assert act.a1_min == pytest.approx(-0.4 * act.a1_max)
    no_bucket = get_vessel("loe-default").actuation
    assert actuator_command(1500, 1000, no_bucket) == (0.0, 0.0)  # no astern thrust


def test_pwm_ranges_and_channels_come_from_the_options() -> None:
    act = get_vessel("default").actuation
    old = ServoMapping(2, 4, (1100, 1500, 1900), (1100, 1520, 1900))
    assert actuator_command(1900, 1900, act, old) == (act.a1_max, act.a2_max)
    assert actuator_command(1700, 1520, act, old) == pytest.approx((0.0, 0.5 * act.a2_max))
    args = SitlPhysicsArgs(steering_channel=2, throttle_channel=4, steering_pwm_min=1100)
    assert args.mapping() == ServoMapping(2, 4, (1100, 1500, 2000), (1000, 1500, 2000))
    assert SitlPhysicsArgs().mapping() == ServoMapping()  # defaults: the shipped .parm
    with pytest.raises(ValueError, match="steering-pwm-min < --steering-pwm-trim"):
        SitlPhysicsArgs(steering_pwm_trim=2100, steering_pwm_max=2000).check()
    physics = JsonPhysics(get_vessel("default"), mapping=old)
    frame = [1500] * 16
    frame[1], frame[3] = 1900, 1900  # SERVO2 steering hard to starboard, SERVO4 full throttle
    for k in range(RATE_HZ):
        physics.handle(ServoFrame(RATE_HZ, k, tuple(frame)))
    assert physics.x[5] > 0.0 and physics.x[3] > 0.2  # turning to starboard, moving ahead


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
    right = fly(port, [2000, 1500, 1800], 3 * RATE_HZ, first=5 * RATE_HZ)
    assert right[-1]["imu"]["gyro"][2] > math.radians(3.0)  # starboard: yaw rate > 0
    assert right[-1]["attitude"][2] > math.radians(5.0)
    left = fly(port, [1000, 1500, 1800], 6 * RATE_HZ, first=8 * RATE_HZ)
    assert left[-1]["imu"]["gyro"][2] < -math.radians(3.0)


def test_repeated_frame_is_answered_without_stepping_and_restart_resets(backend) -> None:
    physics, port = backend
    a = fly(port, [1500, 1500, 1800], 10)
    b = fly(port, [1500, 1500, 1800], 1, first=9)  # re-send of frame 9
    assert b[0] == a[-1]
    c = fly(port, [1500, 1500, 1500], 1, first=0, channels=32)  # SITL restarted
    assert c[0]["timestamp"] == pytest.approx(1.0 / RATE_HZ)
    assert physics.last_count == 0


def test_wind_and_waves_push_the_idle_boat_downwind() -> None:
    """--wind 10 --wind-dir 90 (from the east) --sea-state 3, neutral servos, 20 s at 50 Hz
    over the socket: the calm boat stays put, the windy one drifts west (downwind) at a speed
    below the at-rest balance of the weather tests (0.573 m/s; measured 0.33 m/s over the 20 s,
    0.43 m/s at the end, still accelerating) and its reported heading and position carry the
    wave motion (measured: the reported heading differs from the true one by up to 0.34°)."""
    from usvsim.evaluation.manoeuvre import TrialWeather

    n = 20 * RATE_HZ
    with serving(JsonPhysics(get_vessel("default"))) as (_, port):
        calm = fly(port, [1500, 1500, 1500], n, first=1)
    weather = TrialWeather(10.0, 90.0, 3, seed=0)
    with serving(JsonPhysics(get_vessel("default"), weather=weather)) as (physics, port):
        windy = fly(port, [1500, 1500, 1500], n, first=1)
        true_psi = float(physics.x[2])
    assert calm[-1]["position"] == [0.0, 0.0, 0.0]
    east = np.array([r["position"][1] for r in windy])
    assert 0.05 < -east[-1] / 20.0 < 0.573
    assert windy[-1]["velocity"][1] < -0.05  # over ground, westward
    assert windy[-1]["attitude"][2] != true_psi  # the compass sees the wave yaw
