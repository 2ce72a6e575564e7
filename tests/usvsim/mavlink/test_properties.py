"""Property tests (hypothesis) of the MAVLink side's parsers and decoders: mission files, the
link's packet decoding, ArduPilot's servo frames. Random and mutated inputs give a valid object
or the documented error, never another exception, within a deadline."""

from __future__ import annotations

import json
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import GlobalPosition, Heartbeat
from usvsim.mavlink.mission import Mission, MissionError, load_mission, parse_mission
from usvsim.mavlink.sitl_physics import ServoFrame, parse_servo_frame

VALID = {
    "origin": {"lat": 63.4305, "lon": 10.3951},
    "poles": [{"lat": 63.4305, "lon": 10.3951}],
    "goal": {"lat": 63.4312, "lon": 10.3975},
    "pole_radius_m": 1.0,
    "goal_radius_m": 10.0,
    "cruise_speed_mps": 3.0,
}
numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**6), 10**6),
    st.floats(-100, 100),
)
json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), numbers, st.text(max_size=8)),
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)


@st.composite
def mutated_missions(draw: st.DrawFn) -> dict:
    """A valid mission with one key path replaced, removed or added."""
    data = json.loads(json.dumps(VALID))
    key = draw(st.sampled_from([*VALID, "extra"]))
    action = draw(st.sampled_from(["replace", "delete", "nested"]))
    if action == "delete":
        data.pop(key, None)
    elif action == "nested" and isinstance(data.get(key), dict | list):
        inner = data[key][0] if isinstance(data[key], list) else data[key]
        inner[draw(st.sampled_from(["lat", "lon", "alt"]))] = draw(json_values)
    else:
        data[key] = draw(json_values)
    return data


@settings(database=None, max_examples=400, deadline=500)
@given(st.data())
def test_mutated_missions_parse_or_raise_mission_error(data: st.DataObject) -> None:
    mission = data.draw(st.one_of(json_values, mutated_missions()))
    try:
        parsed = parse_mission(mission, "m.json")
    except MissionError as err:
        assert str(err).startswith("m.json")
        return
    assert isinstance(parsed, Mission)
    assert parsed.goal_radius_m > 0 and parsed.pole_radius_m > 0


@settings(
    database=None,
    max_examples=200,
    deadline=500,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(raw=st.binary(max_size=200), suffix=st.sampled_from([".json", ".yaml", ".txt"]))
def test_random_mission_files_load_or_raise_mission_error(
    tmp_path: Path, raw: bytes, suffix: str
) -> None:
    path = tmp_path / f"m{suffix}"
    path.write_bytes(raw)
    try:
        assert isinstance(load_mission(path), Mission)
    except MissionError as err:
        assert str(path) in str(err)


@settings(database=None, max_examples=300, deadline=200)
@given(st.binary(max_size=200))
def test_servo_frames_decode_or_raise_value_error(data: bytes) -> None:
    try:
        frame = parse_servo_frame(data)
    except ValueError:
        return
    assert isinstance(frame, ServoFrame) and len(frame.pwm_us) in (16, 32)


@pytest.fixture(scope="module")
def link_pair() -> Iterator[tuple[MavlinkLink, socket.socket]]:
    link = MavlinkLink("udpin:127.0.0.1:0", system_id=1, component_id=1)
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sender.connect(("127.0.0.1", link.local_port))
    yield link, sender
    sender.close()
    link.close()


def _valid_packets() -> list[bytes]:
    """A heartbeat and a position packet as another MAVLink 2 node sends them."""
    from pymavlink.dialects.v20 import ardupilotmega as mav2

    mav = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
    hb = mav.heartbeat_encode(11, 3, 129, 15, 4).pack(mav, force_mavlink1=False)
    pos = mav.global_position_int_encode(1000, 634305000, 103951000, 0, 0, 30, 0, 0, 9000)
    return [bytes(hb), bytes(pos.pack(mav, force_mavlink1=False))]


PACKETS = _valid_packets()


@st.composite
def datagrams(draw: st.DrawFn) -> bytes:
    """Garbage, or valid packets with bytes flipped, cut or inserted."""
    if draw(st.booleans()):
        return draw(st.binary(min_size=1, max_size=300))
    data = bytearray(b"".join(draw(st.lists(st.sampled_from(PACKETS), min_size=1, max_size=3))))
    for _ in range(draw(st.integers(0, 4))):
        i = draw(st.integers(0, len(data) - 1))
        op = draw(st.sampled_from(["flip", "cut", "insert"]))
        if op == "flip":
            data[i] ^= draw(st.integers(1, 255))
        elif op == "cut":
            del data[i:]
            if not data:
                data = bytearray(b"\xfd")
        else:
            data[i:i] = draw(st.binary(min_size=1, max_size=4))
    return bytes(data)


@settings(
    database=None,
    max_examples=300,
    deadline=1000,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(datagrams())
def test_the_link_decodes_mutated_packets_or_counts_them_bad(
    link_pair: tuple[MavlinkLink, socket.socket], data: bytes
) -> None:
    link, sender = link_pair
    before = (link.bad_packets, link.packets_in)
    sender.send(data)
    got, deadline = [], time.monotonic() + 0.5
    while time.monotonic() < deadline and (link.bad_packets, link.packets_in) == before:
        got += link.poll(0.02)
    for r in got:  # every decoded message is typed, with finite numbers where it has them
        assert isinstance(r.message, Heartbeat | GlobalPosition) or r.message is not None
    # a clean valid datagram always decodes to exactly its messages
    link.poll(0.0)
    sender.send(PACKETS[0])
    clean, deadline = [], time.monotonic() + 1.0
    while time.monotonic() < deadline and not clean:
        clean += link.poll(0.02)
    assert [type(r.message) for r in clean] == [Heartbeat]
