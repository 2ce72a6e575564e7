"""The one module that imports pymavlink: a narrow, typed MAVLink 2 link for both ends.

Both the companion-computer side (:mod:`usvsim.mavlink.bridge`) and the vehicle side
(:mod:`usvsim.mavlink.sitl`) talk through :class:`MavlinkLink`: incoming packets are decoded into
the small frozen dataclasses of :mod:`usvsim.mavlink.messages` (:class:`Received` wrapping
:class:`Heartbeat`, :class:`GlobalPosition`, ...), outgoing ones are built by typed methods
(``send_heading(psi_rad, speed_mps)``). No pymavlink object leaves this module.

Protocol choices (ArduPilot Rover, boat frame; checked against ``Rover/GCS_Mavlink.cpp``):

* Heading + speed in GUIDED: ``SET_POSITION_TARGET_LOCAL_NED`` in ``MAV_FRAME_LOCAL_NED`` with
  ``type_mask`` :data:`TYPE_MASK_VELOCITY_YAW` (position, vz, acceleration and yaw rate ignored).
  Rover takes the speed as ``|(vx, vy)|`` and the *sign of vx* as the driving direction, and the
  heading from ``yaw`` (absolute in LOCAL_NED; BODY frames would make it relative). We therefore
  send ``vx = speed, vy = 0, yaw = ψ``: forward at ``speed`` on absolute heading ψ.
* Alternative: ``SET_ATTITUDE_TARGET`` with the yaw quaternion, body rates ignored and thrust
  used (:data:`ATTITUDE_MASK_YAW_THRUST`); Rover maps ``thrust ∈ [-1, 1]`` to ``thrust · WP_SPEED``.
* Neither is acknowledged by Rover, and GUIDED drops a heading/speed target after ~3 s: senders
  must stream them (5-10 Hz).
* MAVLink 2 always (the v2 parser also reads v1 packets); optional signing with a 32-byte key.

Connection errors are :class:`usvsim.mavlink.connection.LinkError` (a
:class:`usvsim.common.errors.UserError`) with one line naming the URL and what is allowed
(:func:`usvsim.mavlink.connection.check_url`) or what failed (refused, unknown host, no
heartbeat); a signing key file that is missing or malformed is one too.

The tlog written with ``tlog_path`` is the standard format (MAVProxy, pymavlink ``mavlogdump``):
per packet an 8-byte big-endian wall-clock time in µs, then the raw packet, both directions.
"""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav2

from usvsim.mavlink import messages as msgs
from usvsim.mavlink.connection import (
    HeartbeatTimeoutError,
    LinkError,
    check_url,
    load_signing_key,
)

__all__ = [
    "HeartbeatTimeoutError",
    "LinkError",
    "MavlinkLink",
    "check_url",
    "load_signing_key",
    "message_id",
    "read_tlog",
]

_UNSIGNED_OK = frozenset({mav2.MAVLINK_MSG_ID_RADIO_STATUS})  # as ArduPilot accepts


def message_id(name: str) -> int:
    """MAVLink message id of ``name`` (e.g. ``"GLOBAL_POSITION_INT"`` -> 33)."""
    try:
        return int(getattr(mav2, f"MAVLINK_MSG_ID_{name}"))
    except AttributeError:
        raise ValueError(f"unknown MAVLink message {name!r}") from None


def _decode(m: Any) -> msgs.Message | None:
    """Typed view of a pymavlink message; ``None`` for types this project does not use."""
    kind = m.get_type()
    if kind == "HEARTBEAT":
        return msgs.Heartbeat(m.type, m.autopilot, m.base_mode, m.custom_mode, m.system_status)
    if kind == "GLOBAL_POSITION_INT":
        hdg = math.nan if m.hdg == 65535 else math.radians(m.hdg / 100.0)
        return msgs.GlobalPosition(
            m.time_boot_ms, m.lat * 1e-7, m.lon * 1e-7, m.vx / 100.0, m.vy / 100.0, hdg
        )
    if kind == "ATTITUDE":
        return msgs.Attitude(m.time_boot_ms, m.roll, m.pitch, m.yaw, m.yawspeed)
    if kind == "VFR_HUD":
        return msgs.VfrHud(m.groundspeed, m.heading, m.throttle)
    if kind == "GPS_RAW_INT":
        return msgs.GpsRaw(
            m.time_usec, m.fix_type, m.lat * 1e-7, m.lon * 1e-7, m.satellites_visible
        )
    if kind == "SYS_STATUS":
        return msgs.SysStatus(m.voltage_battery / 1000.0)
    if kind == "STATUSTEXT":
        text = m.text if isinstance(m.text, str) else bytes(m.text).decode("ascii", "replace")
        return msgs.StatusText(m.severity, text.rstrip("\x00"))
    if kind == "COMMAND_ACK":
        return msgs.CommandAck(m.command, m.result)
    if kind == "COMMAND_LONG":
        p = (m.param1, m.param2, m.param3, m.param4, m.param5, m.param6, m.param7)
        return msgs.CommandLong(m.target_system, m.target_component, m.command, p)
    if kind == "SET_MODE":
        return msgs.SetMode(m.target_system, m.base_mode, m.custom_mode)
    if kind in ("SET_POSITION_TARGET_LOCAL_NED", "SET_POSITION_TARGET_GLOBAL_INT"):
        return msgs.SetPositionTarget(
            m.target_system,
            m.coordinate_frame,
            m.type_mask,
            m.vx,
            m.vy,
            m.yaw,
            m.yaw_rate,
            kind.endswith("GLOBAL_INT"),
        )
    if kind == "SET_ATTITUDE_TARGET":
        q = (float(m.q[0]), float(m.q[1]), float(m.q[2]), float(m.q[3]))
        return msgs.SetAttitudeTarget(m.target_system, m.type_mask, q, m.thrust, m.body_yaw_rate)
    return None


def read_tlog(path: str | Path) -> list[tuple[float, msgs.Received]]:
    """Decoded packets of a tlog (both directions), with their wall-clock stamps (s).

    Packets of types this module does not decode are skipped; signatures are not checked.
    """
    data = Path(path).read_bytes()
    parser = mav2.MAVLink(None)
    parser.robust_parsing = True
    out: list[tuple[float, msgs.Received]] = []
    i = 0
    while i + 8 + 12 <= len(data):
        stamp = struct.unpack_from(">Q", data, i)[0] / 1e6
        i += 8
        if data[i] == 0xFD:  # MAVLink 2: 10-byte header, payload, CRC, optional signature
            size = 12 + data[i + 1] + (13 if data[i + 2] & 1 else 0)
        else:  # MAVLink 1
            size = 8 + data[i + 1]
        for m in parser.parse_buffer(data[i : i + size]) or []:
            typed = None if m.get_type() == "BAD_DATA" else _decode(m)
            if typed is not None:
                out.append((stamp, msgs.Received(m.get_srcSystem(), m.get_srcComponent(), typed)))
        i += size
    return out


class MavlinkLink:
    """A MAVLink 2 connection (``tcp:``, ``tcpin:``, ``udp:``, ``udpin:``, ``udpout:``, serial).

    Parameters
    ----------
    url : str
        pymavlink connection string; a port of 0 in ``udpin:``/``tcpin:`` lets the OS choose
        (read it back from :attr:`local_port`).
    system_id, component_id : int
        Our own ids (GCS default 255/190; a vehicle uses 1/1).
    signing_key : bytes, optional
        32-byte key: outgoing packets are signed and unsigned incoming ones are rejected
        (counted in :attr:`rejected_unsigned`), except RADIO_STATUS as in ArduPilot.
    tlog_path : path, optional
        Record every packet in and out (see the module docstring).
    clock : callable, optional
        Wall clock for tlog stamps (s); default :func:`time.time`.
    """

    def __init__(
        self,
        url: str,
        *,
        system_id: int = 255,
        component_id: int = 190,
        signing_key: bytes | None = None,
        tlog_path: str | Path | None = None,
        clock: Callable[[], float] = time.time,
    ) -> None:
        if not (1 <= system_id <= 255 and 0 <= component_id <= 255):
            raise ValueError(f"bad MAVLink ids {system_id}/{component_id}")
        self.url = url
        self.system_id = system_id
        self.component_id = component_id
        self._clock = clock
        check_url(url)
        try:
            self._conn = mavutil.mavlink_connection(
                url, source_system=system_id, source_component=component_id, retries=0
            )
        except OSError as err:
            raise LinkError(f"cannot open MAVLink link {url}: {err.strerror or err}") from None
        mav = mav2.MAVLink(self._conn, srcSystem=system_id, srcComponent=component_id)
        mav.robust_parsing = True  # malformed bytes become BAD_DATA, never an exception
        # Force MAVLink 2 (pymavlink picks v1 unless an environment variable says otherwise).
        self._conn.mav = mav
        self._conn.first_byte = False
        self._conn.WIRE_PROTOCOL_VERSION = "2.0"
        self._mav = mav
        self._tlog: IO[bytes] | None = None
        if tlog_path is not None:
            self._tlog = open(tlog_path, "wb")
            mav.set_send_callback(self._record_out)
        if signing_key is not None:
            if len(signing_key) != 32:
                raise ValueError("signing key must be 32 bytes")
            self._conn.setup_signing(
                signing_key,
                sign_outgoing=True,
                allow_unsigned_callback=self._allow_unsigned,
                link_id=0,
            )
        self.bad_packets = 0
        self.packets_in = 0
        self._boot = time.monotonic()

    # --- housekeeping ----------------------------------------------------------------------

    @property
    def local_port(self) -> int:
        """Port our socket is bound to (for ``udpin:``/``tcpin:`` with port 0)."""
        sock = getattr(self._conn, "listen", None) or self._conn.port
        return int(sock.getsockname()[1])

    @property
    def rejected_unsigned(self) -> int:
        """Incoming packets rejected because signing is on and they were unsigned or bad."""
        return int(self._mav.signing.reject_count)

    @staticmethod
    def _allow_unsigned(_mav: Any, msg_id: int) -> bool:
        return msg_id in _UNSIGNED_OK

    def _record(self, buf: bytes) -> None:
        if self._tlog is not None:
            self._tlog.write(struct.pack(">Q", int(self._clock() * 1e6)) + bytes(buf))

    def _record_out(self, msg: Any) -> None:
        self._record(msg.get_msgbuf())

    def close(self) -> None:
        """Close the socket and the tlog."""
        self._conn.close()
        if self._tlog is not None:
            self._tlog.close()
            self._tlog = None

    def __enter__(self) -> MavlinkLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- receiving -------------------------------------------------------------------------

    def poll(self, timeout_s: float = 0.0, max_packets: int = 1000) -> list[msgs.Received]:
        """Everything that has arrived (waiting up to ``timeout_s`` for the first byte).

        Malformed packets (bad CRC, unknown id, truncated, bad or missing signature) are
        counted in :attr:`bad_packets` and dropped; types this module does not decode are
        dropped too.
        """
        out: list[msgs.Received] = []
        if timeout_s > 0:
            self._conn.select(timeout_s)
        for m in self._read(max_packets):
            if m.get_type() == "BAD_DATA":
                self.bad_packets += 1
                continue
            self.packets_in += 1
            self._record(m.get_msgbuf())
            typed = _decode(m)
            if typed is not None:
                out.append(msgs.Received(m.get_srcSystem(), m.get_srcComponent(), typed))
        return out

    def _read(self, max_packets: int) -> list[Any]:
        """Raw pymavlink messages available now.

        On UDP every datagram is parsed on its own: a truncated or garbage frame is dropped at
        the datagram's end instead of swallowing the valid packets of the next datagrams.
        """
        msgs: list[Any] = []
        if not isinstance(self._conn, mavutil.mavudp):
            while len(msgs) < max_packets and (m := self._conn.recv_msg()) is not None:
                msgs.append(m)
            return msgs
        while len(msgs) < max_packets:
            data = self._conn.recv()
            if not data:
                break
            msgs += self._mav.parse_buffer(data) or []
            if self._mav.buf_len() > 0:  # partial frame left: the datagram ended mid-packet
                self._mav.buf, self._mav.buf_index = bytearray(), 0
                self._mav.expected_length = mav2.HEADER_LEN_V1 + 2
                self._mav.have_prefix_error = False
                self.bad_packets += 1
        return msgs

    def wait_heartbeat(
        self, timeout_s: float, accept: Callable[[msgs.Received], bool] | None = None
    ) -> msgs.Received:
        """First HEARTBEAT from a non-GCS system (or one ``accept`` takes), wall-clock deadline.

        Raises
        ------
        HeartbeatTimeoutError
            (a ``TimeoutError`` and :class:`LinkError`) if none arrives within ``timeout_s``.
        """
        deadline = time.monotonic() + timeout_s
        while (left := deadline - time.monotonic()) > 0:
            self.send_gcs_heartbeat()  # UDP servers learn our address from this
            for r in self.poll(min(left, 0.25)):
                if not isinstance(r.message, msgs.Heartbeat):
                    continue
                ok = accept(r) if accept else r.message.type != msgs.MAV_TYPE_GCS
                if ok:
                    return r
        raise HeartbeatTimeoutError(
            f"no vehicle HEARTBEAT on {self.url} within {timeout_s:g} s (is the vehicle running "
            "and the URL right? --heartbeat-timeout-s waits longer)"
        )

    # --- sending: companion computer / GCS side --------------------------------------------

    def _ms(self) -> int:
        return int((time.monotonic() - self._boot) * 1000.0) & 0xFFFFFFFF

    def send_gcs_heartbeat(self) -> None:
        self._mav.heartbeat_send(
            msgs.MAV_TYPE_GCS, msgs.MAV_AUTOPILOT_INVALID, 0, 0, msgs.MAV_STATE_ACTIVE
        )

    def send_heading(
        self, target_system: int, psi_rad: float, speed_mps: float, target_component: int = 1
    ) -> None:
        """Rover GUIDED heading + speed: SET_POSITION_TARGET_LOCAL_NED, velocity + yaw.

        ``psi_rad`` absolute heading (rad, clockwise from north), ``speed_mps`` >= 0 forward.
        """
        if not (math.isfinite(psi_rad) and math.isfinite(speed_mps) and speed_mps >= 0):
            raise ValueError(f"bad heading setpoint psi={psi_rad!r} speed={speed_mps!r}")
        self._mav.set_position_target_local_ned_send(
            self._ms(),
            target_system,
            target_component,
            msgs.MAV_FRAME_LOCAL_NED,
            msgs.TYPE_MASK_VELOCITY_YAW,
            0.0,
            0.0,
            0.0,
            speed_mps,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            psi_rad,
            0.0,
        )

    def send_attitude_target(
        self, target_system: int, psi_rad: float, thrust: float, target_component: int = 1
    ) -> None:
        """Rover GUIDED alternative: SET_ATTITUDE_TARGET, yaw quaternion, thrust in [0, 1]
        (Rover: speed = thrust · WP_SPEED)."""
        if not (math.isfinite(psi_rad) and math.isfinite(thrust) and 0 <= thrust <= 1):
            raise ValueError(f"bad attitude setpoint psi={psi_rad!r} thrust={thrust!r}")
        q = [math.cos(psi_rad / 2.0), 0.0, 0.0, math.sin(psi_rad / 2.0)]
        self._mav.set_attitude_target_send(
            self._ms(),
            target_system,
            target_component,
            msgs.ATTITUDE_MASK_YAW_THRUST,
            q,
            0.0,
            0.0,
            0.0,
            thrust,
        )

    def set_mode(self, target_system: int, mode: msgs.RoverMode, target_component: int = 1) -> None:
        """MAV_CMD_DO_SET_MODE with the Rover custom mode (acknowledged by COMMAND_ACK)."""
        self._command(
            target_system,
            target_component,
            msgs.MavCommand.DO_SET_MODE,
            float(msgs.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED),
            float(int(mode)),
        )

    def send_set_mode_message(self, target_system: int, mode: msgs.RoverMode) -> None:
        """The older SET_MODE message (ArduPilot acks it with command id 11)."""
        self._mav.set_mode_send(target_system, msgs.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, int(mode))

    def arm(self, target_system: int, arm: bool = True, target_component: int = 1) -> None:
        self._command(
            target_system,
            target_component,
            msgs.MavCommand.COMPONENT_ARM_DISARM,
            1.0 if arm else 0.0,
        )

    def request_message_interval(
        self, target_system: int, message: str, rate_hz: float, target_component: int = 1
    ) -> None:
        """MAV_CMD_SET_MESSAGE_INTERVAL for ``message`` at ``rate_hz`` (0 disables)."""
        interval_us = -1.0 if rate_hz <= 0 else 1e6 / rate_hz
        self._command(
            target_system,
            target_component,
            msgs.MavCommand.SET_MESSAGE_INTERVAL,
            float(message_id(message)),
            interval_us,
        )

    def _command(
        self, target_system: int, target_component: int, command: int, *params: float
    ) -> None:
        p = [*params, *([0.0] * (7 - len(params)))]
        self._mav.command_long_send(target_system, target_component, int(command), 0, *p)

    def send_raw(self, data: bytes) -> None:
        """Write raw bytes (tests: malformed input)."""
        self._conn.write(data)

    # --- sending: vehicle side -------------------------------------------------------------

    def send_vehicle_heartbeat(
        self, mode: msgs.RoverMode, armed: bool, vehicle_type: int = msgs.MAV_TYPE_SURFACE_BOAT
    ) -> None:
        base = msgs.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
            msgs.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0
        )
        if mode == msgs.RoverMode.GUIDED:
            base |= msgs.MAV_MODE_FLAG_GUIDED_ENABLED
        state = msgs.MAV_STATE_ACTIVE if armed else msgs.MAV_STATE_STANDBY
        self._mav.heartbeat_send(
            vehicle_type, msgs.MAV_AUTOPILOT_ARDUPILOTMEGA, base, int(mode), state
        )

    def send_global_position(self, p: msgs.GlobalPosition) -> None:
        hdg = (
            65535
            if not math.isfinite(p.heading_rad)
            else round(math.degrees(p.heading_rad) % 360.0 * 100.0) % 36000
        )
        self._mav.global_position_int_send(
            p.time_boot_ms & 0xFFFFFFFF,
            round(p.lat_deg * 1e7),
            round(p.lon_deg * 1e7),
            0,
            0,
            round(p.vn_mps * 100.0),
            round(p.ve_mps * 100.0),
            0,
            hdg,
        )

    def send_attitude(self, a: msgs.Attitude) -> None:
        self._mav.attitude_send(
            a.time_boot_ms & 0xFFFFFFFF,
            a.roll_rad,
            a.pitch_rad,
            a.yaw_rad,
            0.0,
            0.0,
            a.yaw_rate_radps,
        )

    def send_vfr_hud(self, v: msgs.VfrHud) -> None:
        self._mav.vfr_hud_send(
            0.0, v.groundspeed_mps, v.heading_deg % 360, v.throttle_pct, 0.0, 0.0
        )

    def send_gps_raw(self, g: msgs.GpsRaw, speed_mps: float, course_rad: float) -> None:
        cog = round(math.degrees(course_rad) % 360.0 * 100.0) % 36000
        self._mav.gps_raw_int_send(
            g.time_usec,
            g.fix_type,
            round(g.lat_deg * 1e7),
            round(g.lon_deg * 1e7),
            0,
            80,
            120,
            round(speed_mps * 100.0),
            cog,
            g.satellites,
        )

    def send_sys_status(self, s: msgs.SysStatus) -> None:
        self._mav.sys_status_send(0, 0, 0, 0, round(s.voltage_v * 1000.0), -1, -1, 0, 0, 0, 0, 0, 0)

    def send_statustext(self, severity: int, text: str) -> None:
        self._mav.statustext_send(severity, text[:50].encode("ascii", "replace"))

    def send_command_ack(
        self, command: int, result: int, target_system: int = 0, target_component: int = 0
    ) -> None:
        self._mav.command_ack_send(int(command), int(result), 0, 0, target_system, target_component)
