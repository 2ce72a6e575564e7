"""The Rover-like MAVLink endpoint (usvsim.mavlink.sitl) on loopback, faster than real time.

A test whose result hangs on when the GCS's messages arrive in vehicle time (the guided
timeout) steps the vehicle itself (:func:`advance`) instead of serving it in a thread.
"""

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import (
    CommandAck,
    GlobalPosition,
    Heartbeat,
    Received,
    RoverMode,
    StatusText,
)
from usvsim.mavlink.sitl import RoverSitl, SitlArgs

# an endpoint thread that dies of an exception is a failure, not a warning
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")

SPEEDUP = 40.0
KEY = bytes(range(1, 33))


@contextmanager
def running(args: SitlArgs) -> Iterator[RoverSitl]:
    sitl = RoverSitl(args)
    with sitl.serving_in_background(60.0):
        yield sitl


def sitl_args(**kw: object) -> SitlArgs:
    """Loopback, fast, and (unless a test asks for it) no EKF start-up delay."""
    kw = {"ekf_delay_s": 0.0, "speedup": SPEEDUP, **kw}
    return SitlArgs(listen="udpin:127.0.0.1:0", **kw)  # type: ignore[arg-type]


@pytest.fixture
def sitl() -> Iterator[RoverSitl]:
    with running(sitl_args()) as s:
        yield s


@pytest.fixture
def gcs(sitl: RoverSitl) -> Iterator[MavlinkLink]:
    link = MavlinkLink(f"udpout:127.0.0.1:{sitl.link.local_port}")
    link.wait_heartbeat(5.0)
    yield link
    link.close()


def until(
    link: MavlinkLink,
    done: Callable[[list[Received]], bool],
    timeout_s: float = 5.0,
    each: Callable[[], None] | None = None,
) -> list[Received]:
    got: list[Received] = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not done(got):
        got += link.poll(0.02)
        if each:
            each()
    return got


def acks(got: list[Received]) -> list[tuple[int, int]]:
    return [(r.message.command, r.message.result) for r in got if isinstance(r.message, CommandAck)]


def test_heartbeat_is_an_ardupilot_boat_in_manual(gcs: MavlinkLink) -> None:
    hb = until(gcs, lambda g: any(isinstance(r.message, Heartbeat) for r in g))
    msg = next(r.message for r in hb if isinstance(r.message, Heartbeat))
    assert (msg.type, msg.autopilot, msg.custom_mode, msg.armed) == (11, 3, 0, False)


def test_mode_arm_and_interval_are_acknowledged(sitl: RoverSitl, gcs: MavlinkLink) -> None:
    gcs.set_mode(1, RoverMode.GUIDED)
    gcs.send_set_mode_message(1, RoverMode.LOITER)
    gcs.arm(1)
    gcs.request_message_interval(1, "GLOBAL_POSITION_INT", 10.0)
    gcs.set_mode(1, RoverMode.ACRO)  # not in the subset: denied
    got = until(gcs, lambda g: len(acks(g)) >= 5)
    assert acks(got) == [(176, 0), (11, 0), (400, 0), (511, 0), (176, 2)]
    assert sitl.mode == RoverMode.LOITER and sitl.armed


def test_telemetry_rate_follows_set_message_interval(gcs: MavlinkLink) -> None:
    gcs.request_message_interval(1, "GLOBAL_POSITION_INT", 10.0)
    until(gcs, lambda g: len(acks(g)) >= 1)
    got = until(gcs, lambda g: sum(isinstance(r.message, GlobalPosition) for r in g) >= 21)
    t = [r.message.time_boot_ms for r in got if isinstance(r.message, GlobalPosition)]
    assert np.all(np.diff(t[1:]) == 100)  # vehicle clock: every 100 ms


def test_guided_target_ignored_outside_guided(sitl: RoverSitl, gcs: MavlinkLink) -> None:
    gcs.set_mode(1, RoverMode.HOLD)
    gcs.arm(1)
    until(gcs, lambda g: len(acks(g)) >= 2)
    t_end = sitl.time_ms + 1000
    until(gcs, lambda g: sitl.time_ms > t_end, each=lambda: gcs.send_heading(1, 1.0, 3.0))
    assert sitl.record.targets == []
    assert float(np.hypot(*sitl.state.x[0, 3:5])) < 0.5  # waterjet idle thrust only


def test_guided_heading_and_speed_are_tracked(sitl: RoverSitl, gcs: MavlinkLink) -> None:
    gcs.set_mode(1, RoverMode.GUIDED)
    gcs.arm(1)
    until(gcs, lambda g: len(acks(g)) >= 2)
    t_end = sitl.time_ms + 40_000
    until(
        gcs,
        lambda g: sitl.time_ms > t_end,
        timeout_s=10.0,
        each=lambda: gcs.send_heading(1, math.radians(-90.0), 3.0),
    )
    x = sitl.state.x[0]
    assert math.degrees(x[2]) == pytest.approx(-90.0, abs=1.0)
    assert x[3] == pytest.approx(3.0, abs=0.1)


@contextmanager
def stepped(args: SitlArgs) -> Iterator[tuple[RoverSitl, MavlinkLink]]:
    """A vehicle the test steps itself, in vehicle time (no serving thread, no pacing), and a
    GCS: what the vehicle does then depends on no thread scheduling or machine load."""
    sitl = RoverSitl(args)
    gcs = MavlinkLink(f"udpout:127.0.0.1:{sitl.link.local_port}")
    try:
        yield sitl, gcs
    finally:
        gcs.close()
        sitl.link.close()


def delivered(sitl: RoverSitl, gcs: MavlinkLink, done: Callable[[], bool]) -> list[Received]:
    """Let the vehicle read what the GCS sent (no step, no vehicle time) until ``done()``."""
    got: list[Received] = []
    deadline = time.monotonic() + 5.0  # liveness only: loopback delivers within microseconds
    while not done():
        assert time.monotonic() < deadline, "the vehicle never received the GCS's message"
        sitl.handle_incoming(0.01)
        got += gcs.poll(0.0)
    return got


def advance(
    sitl: RoverSitl, gcs: MavlinkLink, vehicle_ms: int, each: Callable[[], None] | None = None
) -> list[Received]:
    """Step the vehicle through ``vehicle_ms`` of vehicle time as :meth:`RoverSitl.serve` does
    (incoming, step, telemetry); ``each`` (a GCS message) is sent before every step and read
    by the vehicle before that step."""
    got: list[Received] = []
    end_ms = sitl.time_ms + vehicle_ms
    while sitl.time_ms < end_ms:
        if each is not None:
            count = len(sitl.record.targets)
            each()
            got += delivered(sitl, gcs, lambda n=count: len(sitl.record.targets) > n)
        sitl.handle_incoming(0.0)
        sitl.step()
        sitl.send_telemetry()
        got += gcs.poll(0.0)
    return got + gcs.poll(0.05)


def test_guided_timeout_stops_and_holds_position() -> None:
    # stepped by the test: a GCS thread starved for 3 vehicle s (75 ms of wall clock at 40x,
    # common on a loaded 2-core machine) would otherwise time the target out mid-stream
    with stepped(sitl_args()) as (sitl, gcs):
        gcs.set_mode(1, RoverMode.GUIDED)
        gcs.arm(1)
        got = delivered(sitl, gcs, lambda: sitl.armed)
        got += until(gcs, lambda g: len(acks(got + g)) >= 2)
        assert acks(got) == [(176, 0), (400, 0)]
        advance(sitl, gcs, 20_000, each=lambda: gcs.send_heading(1, 0.0, 3.0))
        assert len(sitl.record.targets) == 200  # one target every 0.1 s step for 20 s
        last_target = sitl.record.targets[-1][0]
        got = advance(sitl, gcs, 25_000)
    assert len(sitl.record.guided_timeouts_s) == 1
    t_out = sitl.record.guided_timeouts_s[0]
    # Rover's 3 s, checked at every 0.1 s plant step: the first step more than 3 s after it
    assert 3.0 < t_out - last_target <= 3.0 + 0.1 + 1e-9
    assert any(isinstance(r.message, StatusText) and "timeout" in r.message.text for r in got)
    assert sitl.mode == RoverMode.GUIDED  # like Rover: the mode stays, the boat stops
    states = np.array(sitl.record.states)
    t = np.array(sitl.record.times_s)
    assert t[-1] >= t_out + 20.0
    speed = np.hypot(states[:, 3], states[:, 4])
    after = t > t_out + 1.0
    # no forward thrust (the reversing bucket brakes, as Rover's ATC_BRAKE), never speeds up
    # beyond a brake's overshoot astern, and comes to rest
    assert np.all(states[after, 6] < 0.01 * 24000.0)
    assert np.all(np.diff(speed[after]) <= 0.01)
    assert speed[-1] < 0.1 * speed[np.searchsorted(t, t_out)]


def test_foreign_target_and_malformed_packets_are_ignored(
    sitl: RoverSitl, gcs: MavlinkLink
) -> None:
    gcs.send_raw(b"\xfd\xff\x00garbage" * 10)
    gcs.set_mode(42, RoverMode.GUIDED)  # another vehicle's command
    gcs.arm(1)
    # a garbage frame header may hold the parser until enough bytes arrive to resynchronise:
    # keep the link alive with heartbeats, as the bridge does
    got = until(gcs, lambda g: len(acks(g)) >= 1, each=gcs.send_gcs_heartbeat)
    assert acks(got) == [(400, 0)]
    assert sitl.mode == RoverMode.MANUAL and sitl.armed


def test_signing_on_rejects_unsigned_commands(tmp_path: Path) -> None:
    key_file = tmp_path / "key"
    key_file.write_bytes(KEY)
    with running(sitl_args(signing_key=str(key_file))) as sitl:
        port = sitl.link.local_port
        unsigned = MavlinkLink(f"udpout:127.0.0.1:{port}")
        signed = MavlinkLink(f"udpout:127.0.0.1:{port}", signing_key=KEY)
        try:
            signed.wait_heartbeat(5.0)
            for _ in range(3):
                unsigned.arm(1)
            until(signed, lambda g: sitl.link.rejected_unsigned >= 3)
            assert not sitl.armed and sitl.link.rejected_unsigned >= 3
            signed.arm(1)
            got = until(signed, lambda g: len(acks(g)) >= 1)
            assert acks(got) == [(400, 0)] and sitl.armed
        finally:
            unsigned.close()
            signed.close()


def test_arming_is_refused_with_a_reason_until_the_ekf_is_ready() -> None:
    """As real ArduPilot: the pre-arm bit comes first (half the delay), arming only with the EKF."""
    from usvsim.mavlink.messages import EkfStatus, SysStatus

    with running(sitl_args(ekf_delay_s=8.0)) as sitl:
        gcs = MavlinkLink(f"udpout:127.0.0.1:{sitl.link.local_port}")
        try:
            gcs.wait_heartbeat(5.0)
            gcs.arm(1)
            early = until(gcs, lambda g: len(acks(g)) >= 1)
            t_refused = sitl.time_ms / 1000.0
            assert acks(early) == [(400, 4)] and not sitl.armed  # MAV_RESULT_FAILED
            texts = [r.message.text for r in early if isinstance(r.message, StatusText)]
            assert any(t.startswith("PreArm:") for t in texts)
            late = until(gcs, lambda g: sitl.time_ms > 8_500)
            status = [(sitl_t, r.message) for sitl_t, r in enumerate(late)]
            sys = [m for _, m in status if isinstance(m, SysStatus)]
            ekf = [m for _, m in status if isinstance(m, EkfStatus)]
            assert any(s.prearm_ok for s in sys) and any(not e.ready_to_arm for e in ekf)
            assert ekf[-1].ready_to_arm and sys[-1].prearm_ok
            gcs.arm(1)
            got = until(gcs, lambda g: len(acks(g)) >= 1)
            assert acks(got) == [(400, 0)] and sitl.armed and t_refused < 8.0
        finally:
            gcs.close()


def test_ack_is_addressed_to_the_sender_and_version_is_answered(
    sitl: RoverSitl, gcs: MavlinkLink
) -> None:
    from usvsim.mavlink.messages import AutopilotVersion, MavCommand

    gcs._command(1, 1, MavCommand.REQUEST_MESSAGE, 148.0)  # AUTOPILOT_VERSION
    got = until(
        gcs,
        lambda g: any(isinstance(r.message, AutopilotVersion) for r in g) and len(acks(g)) >= 1,
    )
    ack = next(r.message for r in got if isinstance(r.message, CommandAck))
    assert (ack.command, ack.result, ack.target_system, ack.target_component) == (512, 0, 255, 190)
    version = next(r.message for r in got if isinstance(r.message, AutopilotVersion))
    assert version.flight_sw_version >> 16 == (4 << 8) | 7  # 4.7
    assert version.capabilities & 4  # MISSION_INT


def test_sys_status_reports_sensors_and_no_geofence(gcs: MavlinkLink) -> None:
    from usvsim.mavlink.messages import SysStatus, SysStatusSensor

    got = until(gcs, lambda g: any(isinstance(r.message, SysStatus) for r in g))
    s = next(r.message for r in got if isinstance(r.message, SysStatus))
    assert s.present & SysStatusSensor.GPS and s.present & SysStatusSensor.AHRS
    assert s.present == s.enabled == s.health  # ekf_delay_s = 0: everything healthy
    assert not s.present & SysStatusSensor.GEOFENCE
    assert s.prearm_ok


def test_rtl_brings_the_boat_home_and_holds_there() -> None:
    args = sitl_args(heading_deg=90.0, speed_mps=3.0, speedup=100.0, wp_radius_m=5.0)
    with running(args) as sitl:
        gcs = MavlinkLink(f"udpout:127.0.0.1:{sitl.link.local_port}")
        try:
            gcs.wait_heartbeat(5.0)
            gcs.set_mode(1, RoverMode.GUIDED)
            gcs.arm(1)
            until(gcs, lambda g: len(acks(g)) >= 2)
            t_out = sitl.time_ms + 20_000
            until(gcs, lambda g: sitl.time_ms > t_out, each=lambda: gcs.send_heading(1, 1.6, 3.0))
            away = float(np.hypot(*sitl.state.x[0, 0:2]))
            gcs.set_mode(1, RoverMode.RTL)
            until(gcs, lambda g: len(acks(g)) >= 1)
            t_end = sitl.time_ms + 120_000
            until(gcs, lambda g: sitl.time_ms > t_end, timeout_s=10.0)
        finally:
            gcs.close()
    states = np.array(sitl.record.states)
    assert away > 50.0
    home_dist = np.hypot(states[-300:, 0], states[-300:, 1])  # the last 30 s
    assert home_dist.max() < 10.0  # WP_RADIUS 5 m, then it coasts to rest and holds


def _hold_north(args: SitlArgs, seconds: float) -> np.ndarray:
    """States (steps, 8) of a stepped vehicle in GUIDED holding north at 3 m/s."""
    with stepped(args) as (sitl, gcs):
        gcs.set_mode(1, RoverMode.GUIDED)
        gcs.arm(1)
        delivered(sitl, gcs, lambda: sitl.armed and sitl.mode == RoverMode.GUIDED)
        advance(sitl, gcs, round(seconds * 1000), each=lambda: gcs.send_heading(1, 0.0, 3.0))
        return np.array(sitl.record.states)


def test_heading_hold_in_beam_wind_and_waves_drifts_downwind() -> None:
    """--wind 10 --wind-dir 90 (from the east) --sea-state 3: the boat holds north as in calm
    water and drifts west (downwind) of the calm track; the navigation estimate follows it.
    Measured (seed 0, 40 s): east -7.5 m against 0.0 m in calm (0.19 m/s of leeway; wind
    alone 0.20 m/s; the at-rest balance of the weather tests is 0.573 m/s), heading RMS error
    over the last 20 s 0.22°."""
    calm = _hold_north(sitl_args(), 40.0)
    windy = _hold_north(sitl_args(wind=10.0, wind_dir=90.0, sea_state=3), 40.0)
    assert abs(calm[-1, 1]) < 0.1
    drift_mps = (calm[-1, 1] - windy[-1, 1]) / 40.0
    assert 0.05 < drift_mps < 0.573  # downwind (west), below the drift of a boat at rest
    late = windy[len(windy) // 2 :]
    assert np.sqrt(np.mean(late[:, 2] ** 2)) < math.radians(3.0)  # heading held
    assert np.all(late[:, 3] > 2.5)  # and the speed
    # same seed, same run
    np.testing.assert_array_equal(
        windy, _hold_north(sitl_args(wind=10.0, wind_dir=90.0, sea_state=3), 40.0)
    )


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--sea-state", "9"], "sea-state"),
        (["--wind", "-1"], "wind"),
        (["--wind", "50"], "wind"),
        (["--wind-dir", "360"], "wind-dir"),
    ],
)
@pytest.mark.parametrize("command", ["sitl", "sitl-physics"])
def test_bad_weather_options_exit_2_with_one_line(
    command: str, argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from usvsim.cli.main import main

    try:
        code = main([command, *argv])
    except SystemExit as exit_info:  # argparse's own checks exit instead of returning
        code = exit_info.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
