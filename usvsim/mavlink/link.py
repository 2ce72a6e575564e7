"""The one module that imports pymavlink: a narrow, typed MAVLink 2 link for both ends.

Why this module is long: it is the one pymavlink adapter (the architecture allows no second),
so the decoder of every message type the project reads and the typed sender of every one it
writes, for both the companion side and the vehicle side, live here; each is a few lines.

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

Link loss: on TCP a closed or reset peer raises :class:`LinkLostError` from :meth:`MavlinkLink.poll`
or a send, once, instead of pymavlink's "EOF on TCP socket" printed on every read (which made a
busy loop of any wait); :meth:`MavlinkLink.reconnect` opens the same URL again (one attempt, a
refused connection is a :class:`LinkError`), keeping the tlog and the signing key.

Connection errors are :class:`usvsim.mavlink.connection.LinkError` (a
:class:`usvsim.common.errors.UserError`) with one line naming the URL and what is allowed
(:func:`usvsim.mavlink.connection.check_url`) or what failed (refused, unknown host, no
heartbeat); a signing key file that is missing or malformed is one too.

The tlog written with ``tlog_path`` is the standard format (MAVProxy, pymavlink ``mavlogdump``):
per packet an 8-byte big-endian wall-clock time in µs, then the raw packet, both directions.
"""

from __future__ import annotations

import contextlib
import errno
import math
import select
import socket
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
    LinkLostError,
    check_url,
    load_signing_key,
)

__all__ = [
    "HeartbeatTimeoutError",
    "LinkError",
    "LinkLostError",
    "MavlinkLink",
    "check_url",
    "load_signing_key",
    "message_id",
    "read_tlog",
]

_MAV_PARAM_TYPE_REAL32 = mav2.MAV_PARAM_TYPE_REAL32
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
        return msgs.SysStatus(
            m.voltage_battery / 1000.0,
            m.onboard_control_sensors_present,
            m.onboard_control_sensors_enabled,
            m.onboard_control_sensors_health,
        )
    if kind == "EKF_STATUS_REPORT":
        return msgs.EkfStatus(m.flags)
    if kind == "STATUSTEXT":
        return msgs.StatusText(m.severity, _text(m.text))
    if kind == "COMMAND_ACK":
        return msgs.CommandAck(m.command, m.result, m.target_system, m.target_component)
    return _decode_protocol(kind, m)


def _text(raw: Any) -> str:
    text = raw if isinstance(raw, str) else bytes(raw).decode("ascii", "replace")
    return text.rstrip("\x00")


def _decode_protocol(kind: str, m: Any) -> msgs.Message | None:
    """The parameter, mission, version, command and setpoint messages (see :func:`_decode`)."""
    if kind == "PARAM_VALUE":
        return msgs.ParamValue(_text(m.param_id), m.param_value, m.param_index, m.param_count)
    if kind == "PARAM_REQUEST_LIST":
        return msgs.ParamRequestList(m.target_system)
    if kind == "PARAM_REQUEST_READ":
        return msgs.ParamRequestRead(m.target_system, _text(m.param_id), m.param_index)
    if kind == "PARAM_SET":
        return msgs.ParamSet(m.target_system, _text(m.param_id), m.param_value)
    mtype = getattr(m, "mission_type", 0)
    if kind == "MISSION_COUNT":
        return msgs.MissionCount(m.target_system, m.count, mtype)
    if kind == "MISSION_REQUEST_LIST":
        return msgs.MissionRequestList(m.target_system, mtype)
    if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
        return msgs.MissionRequest(m.target_system, m.seq, kind.endswith("_INT"), mtype)
    if kind in ("MISSION_ITEM_INT", "MISSION_ITEM"):
        scale = 1e-7 if kind.endswith("_INT") else 1.0
        return msgs.MissionItem(
            m.target_system,
            m.seq,
            m.command,
            m.x * scale,
            m.y * scale,
            m.z,
            m.frame,
            (m.param1, m.param2, m.param3, m.param4),
            m.current,
            m.autocontinue,
            mtype,
        )
    if kind == "MISSION_ACK":
        return msgs.MissionAck(m.target_system, m.type, mtype)
    if kind == "MISSION_CLEAR_ALL":
        return msgs.MissionClearAll(m.target_system, mtype)
    if kind == "MISSION_CURRENT":
        return msgs.MissionCurrent(m.seq)
    if kind == "AUTOPILOT_VERSION":
        return msgs.AutopilotVersion(m.capabilities, m.flight_sw_version)
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
        self._signing_key = signing_key
        if signing_key is not None and len(signing_key) != 32:
            raise ValueError("signing key must be 32 bytes")
        self._tlog: IO[bytes] | None = None
        if tlog_path is not None:
            self._tlog = open(tlog_path, "wb")
        self.lost: str | None = None  # why the link was lost (TCP peer closed/reset), else None
        try:
            self._open()
        except LinkError:
            if self._tlog is not None:
                self._tlog.close()
            raise
        self.bad_packets = 0
        self.packets_in = 0
        self._boot = time.monotonic()

    def _open(self) -> None:
        """Open the pymavlink connection for :attr:`url` (MAVLink 2, signing, tlog callback)."""
        try:
            self._conn = mavutil.mavlink_connection(
                self.url,
                source_system=self.system_id,
                source_component=self.component_id,
                retries=0,
            )
        except OSError as err:
            raise LinkError(f"cannot open MAVLink link {self.url}: {err.strerror or err}") from None
        mav = mav2.MAVLink(self._conn, srcSystem=self.system_id, srcComponent=self.component_id)
        mav.robust_parsing = True  # malformed bytes become BAD_DATA, never an exception
        # Force MAVLink 2 (pymavlink picks v1 unless an environment variable says otherwise).
        self._conn.mav = mav
        self._conn.first_byte = False
        self._conn.WIRE_PROTOCOL_VERSION = "2.0"
        self._mav = mav
        if isinstance(self._conn, (mavutil.mavtcp, mavutil.mavtcpin)):
            self._conn.write = self._tcp_write  # errors become LinkLostError, never a print
        if self._tlog is not None:
            mav.set_send_callback(self._record_out)
        if self._signing_key is not None:
            self._conn.setup_signing(
                self._signing_key,
                sign_outgoing=True,
                allow_unsigned_callback=self._allow_unsigned,
                link_id=0,
            )
        self.lost = None

    def reconnect(self) -> None:
        """Close the connection and open :attr:`url` again (one attempt; tlog kept).

        Raises
        ------
        LinkError
            If the peer refuses or cannot be reached.
        """
        with contextlib.suppress(OSError):
            self._conn.close()
        self._open()

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

    def drop_client(self) -> bool:
        """``tcpin:`` only: close the connected client and listen for the next (fault tests).

        Returns False when no client is connected (or the link is not ``tcpin:``).
        """
        if not isinstance(self._conn, mavutil.mavtcpin) or self._conn.port is None:
            return False
        self._lose("dropped by this end")
        return True

    def close(self) -> None:
        """Close the socket and the tlog."""
        with contextlib.suppress(OSError):
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
        if self.lost is not None:
            raise LinkLostError(f"MAVLink link {self.url} lost: {self.lost}")
        if self._tcp_socket() is not None:
            self._check_tcp(timeout_s)
        elif timeout_s > 0:
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

    def _tcp_socket(self) -> socket.socket | None:
        """The connected TCP socket (``tcp:``, or ``tcpin:`` once a client is in), else None."""
        if isinstance(self._conn, (mavutil.mavtcp, mavutil.mavtcpin)):
            return self._conn.port
        return None

    def _lose(self, why: str) -> LinkLostError:
        self.lost = why
        if isinstance(self._conn, mavutil.mavtcpin):  # listen again for the next client
            with contextlib.suppress(OSError):
                self._conn.port.close()
            self._conn.port = None
            self._conn.fd = self._conn.listen.fileno()
            self.lost = None
        return LinkLostError(f"MAVLink link {self.url} lost: {why}")

    def _check_tcp(self, timeout_s: float) -> None:
        """Wait up to ``timeout_s`` for data; a readable socket with nothing to read is EOF."""
        sock = self._tcp_socket()
        assert sock is not None
        try:
            readable, _, _ = select.select([sock], [], [], max(timeout_s, 0.0))
            if readable and sock.recv(1, socket.MSG_PEEK) == b"":
                raise self._lose("the peer closed the connection (EOF)")
        except (ConnectionResetError, BrokenPipeError) as err:
            raise self._lose(f"connection reset by the peer ({err.strerror})") from None
        except BlockingIOError:
            return
        except OSError as err:
            if err.errno in (errno.EBADF, errno.ENOTCONN):
                raise self._lose(f"socket closed ({err.strerror})") from None
            raise

    def _tcp_write(self, buf: bytes) -> None:
        sock = self._tcp_socket()
        if sock is None:
            return  # tcpin: no client yet
        try:
            sock.sendall(buf)
        except (ConnectionResetError, BrokenPipeError) as err:
            raise self._lose(f"connection reset by the peer ({err.strerror})") from None
        except BlockingIOError:
            return  # send buffer full: drop, as a radio would

    def _read(self, max_packets: int) -> list[Any]:
        """Raw pymavlink messages available now.

        On UDP every datagram is parsed on its own: a truncated or garbage frame is dropped at
        the datagram's end instead of swallowing the valid packets of the next datagrams.
        """
        msgs: list[Any] = []
        if not isinstance(self._conn, mavutil.mavudp):
            try:
                while len(msgs) < max_packets and (m := self._conn.recv_msg()) is not None:
                    msgs.append(m)
            except (ConnectionResetError, BrokenPipeError) as err:
                # a peer that resets (RST) between the readiness check and the read
                raise self._lose(f"connection reset by the peer ({err.strerror})") from None
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

    def request_param(self, target_system: int, name: str, target_component: int = 1) -> None:
        """PARAM_REQUEST_READ by name (answered by PARAM_VALUE)."""
        self._mav.param_request_read_send(
            target_system, target_component, name.encode("ascii")[:16], -1
        )

    def request_param_list(self, target_system: int, target_component: int = 1) -> None:
        self._mav.param_request_list_send(target_system, target_component)

    def set_param(
        self, target_system: int, name: str, value: float, target_component: int = 1
    ) -> None:
        """PARAM_SET (answered by PARAM_VALUE with the value now in force)."""
        self._mav.param_set_send(
            target_system,
            target_component,
            name.encode("ascii")[:16],
            float(value),
            _MAV_PARAM_TYPE_REAL32,
        )

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
        self._mav.sys_status_send(
            s.present, s.enabled, s.health, 0, round(s.voltage_v * 1000.0), -1, -1, 0, 0, 0, 0, 0, 0
        )

    def send_ekf_status(self, e: msgs.EkfStatus) -> None:
        """EKF_STATUS_REPORT with the flags and small variances (a healthy solution)."""
        self._mav.ekf_status_report_send(int(e.flags), 0.1, 0.1, 0.1, 0.1, 0.0)

    def send_autopilot_version(self, v: msgs.AutopilotVersion) -> None:
        self._mav.autopilot_version_send(
            v.capabilities, v.flight_sw_version, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, 0
        )

    def send_param_value(self, p: msgs.ParamValue) -> None:
        self._mav.param_value_send(
            p.name.encode("ascii")[:16], float(p.value), _MAV_PARAM_TYPE_REAL32, p.count, p.index
        )

    def send_mission_count(self, target_system: int, count: int, mission_type: int = 0) -> None:
        self._mav.mission_count_send(target_system, 0, count, mission_type)

    def send_mission_request(
        self, target_system: int, seq: int, mission_type: int = 0, target_component: int = 0
    ) -> None:
        """MISSION_REQUEST_INT for item ``seq`` (the vehicle's side of an upload)."""
        self._mav.mission_request_int_send(target_system, target_component, seq, mission_type)

    def send_mission_item(self, item: msgs.MissionItem, target_system: int, as_int: bool) -> None:
        """MISSION_ITEM_INT (``as_int``), else the older MISSION_ITEM with float lat/lon."""
        common = (item.frame, item.command, item.current, item.autocontinue, *item.params)
        if as_int:
            self._mav.mission_item_int_send(
                target_system,
                0,
                item.seq,
                *common,
                round(item.lat_deg * 1e7),
                round(item.lon_deg * 1e7),
                item.alt_m,
                item.mission_type,
            )
        else:
            self._mav.mission_item_send(
                target_system,
                0,
                item.seq,
                *common,
                item.lat_deg,
                item.lon_deg,
                item.alt_m,
                item.mission_type,
            )

    def send_mission_ack(self, target_system: int, result: int, mission_type: int = 0) -> None:
        self._mav.mission_ack_send(target_system, 0, result, mission_type)

    def send_mission_current(self, seq: int) -> None:
        self._mav.mission_current_send(seq)

    def send_mission_item_reached(self, seq: int) -> None:
        self._mav.mission_item_reached_send(seq)

    def send_statustext(self, severity: int, text: str) -> None:
        self._mav.statustext_send(severity, text[:50].encode("ascii", "replace"))

    def send_command_ack(
        self, command: int, result: int, target_system: int = 0, target_component: int = 0
    ) -> None:
        self._mav.command_ack_send(int(command), int(result), 0, 0, target_system, target_component)
