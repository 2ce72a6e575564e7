"""``usvsim bridge``: a helmsman steers an external autopilot (ArduPilot Rover, boat) over MAVLink.

Sequence: wait for the vehicle's HEARTBEAT (must be a surface boat or rover), request
GLOBAL_POSITION_INT and ATTITUDE at ``telemetry_rate_hz`` (SET_MESSAGE_INTERVAL), switch to
GUIDED, arm only with ``--arm``; then on every telemetry tick:

1. convert GLOBAL_POSITION_INT to NED around the mission origin (:mod:`usvsim.nav.geo`) and run the
   simulator's Kalman filter models (:class:`TelemetryEstimator`);
2. every ``decision_period_s`` of *vehicle* time, build the observation with the simulator's
   builder (:func:`usvsim.task.observations.build_observation`), ask the helmsman
   (:class:`usvsim.helm.protocol.Helmsman`), map the action to a heading change exactly as the
   environment does (:func:`usvsim.task.batch.heading_change_rad`), and command
   ``ψ_ref = ssa(ψ̂ + Δψ)`` at the mission's cruise speed;
3. re-send the setpoint at ``setpoint_rate_hz`` (Rover drops GUIDED targets after ~3 s and
   acknowledges none), and a GCS HEARTBEAT every vehicle second.

Timing follows the vehicle clock (``time_boot_ms``), so a faster-than-real-time SITL gets the
same 2 s decisions. ``--arm`` waits for the vehicle to be ready and retries refusals with the
vehicle's reasons (:func:`usvsim.mavlink.safety.arm_when_ready`); ``--attitude-target`` reads
WP_SPEED from the vehicle (PARAM_REQUEST_READ) unless ``--wp-speed-mps`` is given.

Safety: the bridge stops streaming and commands the ``--failsafe`` mode (LOITER by default:
a boat in HOLD drifts; see :mod:`usvsim.mavlink.safety` for the actions against ArduPilot's
FS_ACTION) when telemetry is older than ``stale_s`` of vehicle time *and* ``stale_wall_min_s``
of wall clock (see :meth:`Bridge.telemetry_age_s`), when the link is lost (TCP EOF, reset), when
the helmsman raises or returns an invalid action (NaN, out of range), at ``max_duration_s``,
when the goal is reached, and on Ctrl-C (then exit). The command is repeated until the vehicle
acknowledges it or ``failsafe_deadline_s`` has passed (a lost link is reconnected at most
``reconnect_attempts`` times meanwhile); an unacknowledged failsafe is reported loudly: a line
on stderr, an ``unacknowledged`` CSV row and exit status 3 (:attr:`BridgeResult.exit_status`).
Every decision and failsafe goes to a CSV log; the link is recorded as a tlog.

Shapes inside: one boat, arrays of shape (1, ...), as the simulator's batched builders expect.

Why this module is long: one session's whole sequence (connect, the vehicle-clock loop, the
decision, the stop) reads top to bottom here; the readiness, arming and failsafe-delivery
machinery is already its own module (:mod:`usvsim.mavlink.safety`).
"""

from __future__ import annotations

import csv
import math
import statistics
import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import IO, Any, Literal

import numpy as np

from usvsim.common.angles import ssa
from usvsim.common.options import bounds
from usvsim.helm.protocol import Helmsman
from usvsim.helm.registry import helmsman_kinds
from usvsim.mavlink.connection import LinkLostError, VehicleError
from usvsim.mavlink.link import MavlinkLink, load_signing_key
from usvsim.mavlink.messages import (
    MAV_RESULT_ACCEPTED,
    Attitude,
    GlobalPosition,
    Heartbeat,
    MavCommand,
    ParamValue,
    Received,
    RoverMode,
)
from usvsim.mavlink.mission import Mission
from usvsim.mavlink.safety import (
    FAILSAFE_MODES,
    Delivery,
    VehicleWatch,
    arm_when_ready,
    deliver_mode,
    wait_ack,
)
from usvsim.nav.geo import ned_from_geodetic
from usvsim.nav.telemetry import TelemetryEstimator
from usvsim.task.batch import ActionKind, heading_change_rad
from usvsim.task.observations import ObservationKind, build_observation
from usvsim.task.radar import RadarConfig

__all__ = ["Bridge", "BridgeArgs", "BridgeResult"]

# MAV_RESULT of MAVLink common.xml, for messages (the module's constants name the ones it sends)
_MAV_RESULTS = ("ACCEPTED", "TEMPORARILY_REJECTED", "DENIED", "UNSUPPORTED", "FAILED",
                "IN_PROGRESS", "CANCELLED")  # fmt: skip


def _result_name(result: int) -> str:
    """``DENIED (2)`` for a COMMAND_ACK result; the bare number for one MAVLink does not list."""
    name = _MAV_RESULTS[result] if 0 <= result < len(_MAV_RESULTS) else "unknown"
    return f"{name} ({result})"


_CSV_FIELDS = (
    "wall_s",
    "vehicle_s",
    "event",
    "x_n_m",
    "y_e_m",
    "psi_deg",
    "action",
    "psi_ref_deg",
    "speed_mps",
    "latency_ms",
    "detail",
)


@dataclass(frozen=True)
class BridgeArgs:
    """Let a helmsman steer an ArduPilot Rover boat (or usvsim sitl) over MAVLink."""

    connect: str = "tcp:127.0.0.1:5760"  # MAVLink URL: tcp:, udp:, udpin:, udpout:, serial dev
    mission: str = ""  # mission file (JSON, or YAML with PyYAML): poles and goal as lat/lon
    helmsman: str = "straight"  # any name of usvsim.helm.registry, or a checkpoint path
    observation: ObservationKind | Literal["auto"] = "auto"  # auto: the helmsman's (positional)
    action: ActionKind | Literal["auto"] = "auto"  # auto: the helmsman's (else gaussian)
    arm: bool = False  # arm the vehicle when it is ready (otherwise it must be armed already)
    arm_timeout_s: float = field(default=120.0, metadata=bounds(gt=0, le=3600))  # wall s
    arm_retry_s: float = field(default=2.0, metadata=bounds(gt=0, le=60))  # wall s between tries
    failsafe: Literal["loiter", "hold", "rtl"] = "loiter"  # mode when the bridge stops steering
    failsafe_deadline_s: float = field(default=10.0, metadata=bounds(gt=0, le=600))  # wall s
    failsafe_repeat_s: float = field(default=0.5, metadata=bounds(gt=0, le=10))  # re-send, s
    reconnect_attempts: int = field(default=3, metadata=bounds(ge=0, le=20))  # after link loss
    attitude_target: bool = False  # command SET_ATTITUDE_TARGET instead of position target
    wp_speed_mps: float = field(default=0.0, metadata=bounds(ge=0, le=30))  # 0: vehicle's WP_SPEED
    decision_period_s: float = field(default=2.0, metadata=bounds(ge=0.1, le=60))  # vehicle s
    max_heading_change_deg: float = field(default=30.0, metadata=bounds(gt=0, le=180))  # deg
    setpoint_rate_hz: float = field(default=10.0, metadata=bounds(ge=0.5, le=100))  # re-send, Hz
    telemetry_rate_hz: float = field(default=10.0, metadata=bounds(ge=0.5, le=100))  # Hz
    stale_s: float = field(default=1.5, metadata=bounds(gt=0, le=60))  # vehicle s: failsafe
    stale_wall_min_s: float = field(default=0.3, metadata=bounds(gt=0, le=60))  # ... and wall s
    heartbeat_timeout_s: float = field(default=30.0, metadata=bounds(gt=0, le=3600))  # wall s
    command_timeout_s: float = field(default=3.0, metadata=bounds(gt=0, le=600))  # COMMAND_ACK, s
    max_duration_s: float = field(default=0.0, metadata=bounds(ge=0))  # HOLD after; 0: no limit
    target_system: int = field(default=0, metadata=bounds(ge=0, le=255))  # 0: first boat heard
    system_id: int = field(default=255, metadata=bounds(ge=1, le=255))  # our system id (GCS)
    signing_key: str = ""  # file with a 32-byte MAVLink2 signing key ('' = unsigned)
    log_csv: str = "usvsim-results/bridge/decisions.csv"  # decisions and failsafes
    tlog: str = "usvsim-results/bridge/link.tlog"  # link recording ('' = none)


@dataclass
class BridgeResult:
    """How a bridge run ended and what it measured (latencies in wall-clock seconds)."""

    reason: str = ""
    decisions: int = 0
    path_ne: list[tuple[float, float, float]] = field(default_factory=list)  # t_s, x_N, y_E
    latencies_s: list[float] = field(default_factory=list)  # telemetry in -> setpoint out
    telemetry_ticks: int = 0
    telemetry_wall_s: float = 0.0
    failsafe: Delivery | None = None  # the final mode command and whether it was acknowledged
    arm_attempts: int = 0
    wp_speed_mps: float = math.nan  # the WP_SPEED used for --attitude-target

    @property
    def failsafe_acknowledged(self) -> bool:
        return self.failsafe is not None and self.failsafe.acknowledged

    @property
    def exit_status(self) -> int:
        """0 goal reached (mode acknowledged), 1 another stop, acknowledged, 3 unacknowledged."""
        if not self.failsafe_acknowledged:
            return 3
        return 0 if self.reason == "goal reached" else 1

    def latency_summary(self) -> tuple[float, float]:
        """Median and 99th percentile of the decision latency (s)."""
        lat = sorted(self.latencies_s)
        if not lat:
            return math.nan, math.nan
        return statistics.median(lat), float(np.percentile(lat, 99))


class FailsafeError(Exception):
    """Internal: a condition that ends the run with the failsafe mode (the message says which)."""


class Bridge:
    """One bridge session (see the module docstring); :meth:`run` does everything.

    ``link`` and ``clock`` may be injected (tests); ``helmsman`` is any
    :class:`usvsim.helm.protocol.Helmsman`.
    """

    def __init__(
        self,
        args: BridgeArgs,
        mission: Mission,
        helmsman: Helmsman,
        link: MavlinkLink | None = None,
        clock: Callable[[], float] = time.perf_counter,
    ) -> None:
        declared_observation, declared_action = helmsman_kinds(helmsman)
        # "auto" (the default): the kinds the helmsman declares (usvsim.cli.mavlink refuses
        # explicit kinds that contradict them before a Bridge is built)
        self.observation: ObservationKind = (
            declared_observation if args.observation == "auto" else args.observation
        )
        self.action: ActionKind = declared_action if args.action == "auto" else args.action
        args = replace(args, observation=self.observation, action=self.action)
        self.args = args
        self.mission = mission
        self.helmsman = helmsman
        self._clock = clock
        if link is None:
            key = load_signing_key(args.signing_key) if args.signing_key else None
            tlog = args.tlog or None
            if tlog:
                Path(tlog).parent.mkdir(parents=True, exist_ok=True)
            link = MavlinkLink(
                args.connect, system_id=args.system_id, signing_key=key, tlog_path=tlog
            )
        self.link = link
        self.poles_ne = mission.poles_ne
        self.goal_ne = mission.goal_ne
        self.estimator = TelemetryEstimator()
        self.radar = RadarConfig()
        self._rng = np.random.default_rng(0)  # radar speckle for radar observations
        self.target = args.target_system
        self.watch = VehicleWatch(self.target)
        self.wp_speed_mps = args.wp_speed_mps
        self.result = BridgeResult()
        self._attitude: Attitude | None = None
        self._last_rx_wall: float | None = None
        self._rate_window: deque[tuple[float, int]] = deque()  # (wall s, vehicle ms)
        self.clock_rate = 1.0  # vehicle seconds per wall second, estimated
        self._setpoint: tuple[float, float] | None = None  # ψ_ref (rad), speed (m/s)
        self._next = {"decision": 0, "setpoint": 0, "heartbeat": 0}
        self._start_ms: int | None = None
        self._log_file: IO[str] | None = None
        self._log: Any = None
        if args.log_csv:
            Path(args.log_csv).parent.mkdir(parents=True, exist_ok=True)
            self._log_file = open(args.log_csv, "w", newline="")
            self._log = csv.DictWriter(self._log_file, fieldnames=_CSV_FIELDS)
            self._log.writeheader()

    # --- logging ---------------------------------------------------------------------------

    def _write(self, event: str, detail: str = "", **values: float | str) -> None:
        if self._log is None:
            return
        row: dict[str, Any] = dict.fromkeys(_CSV_FIELDS, "")
        row.update(wall_s=f"{self._clock():.6f}", event=event, detail=detail)
        if self.estimator.last_ms is not None:
            row["vehicle_s"] = f"{self.estimator.last_ms / 1000.0:.3f}"
        row.update({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in values.items()})
        self._log.writerow(row)
        assert self._log_file is not None
        self._log_file.flush()

    # --- connection ------------------------------------------------------------------------

    def _accept(self, r: Received) -> bool:
        """Only the target vehicle's autopilot counts; other systems are ignored."""
        return r.src_system == self.target and r.src_component == 1

    def _say(self, text: str) -> None:
        print(f"usvsim bridge: {text}", flush=True)
        self._write("info", text)

    def _read_param(self, name: str, timeout_s: float) -> float | None:
        """A parameter's value (PARAM_REQUEST_READ → PARAM_VALUE), None if unanswered."""
        self.link.request_param(self.target, name)
        deadline = time.monotonic() + timeout_s
        while (left := deadline - time.monotonic()) > 0:
            for r in self.link.poll(min(left, 0.05)):
                self.watch.update(r)
                if self._accept(r) and isinstance(r.message, ParamValue):
                    if r.message.name == name:
                        return float(r.message.value)
        return None

    def connect(self) -> None:
        """Heartbeat, type check, telemetry rates, WP_SPEED, GUIDED, arming when ready.

        Raises
        ------
        VehicleError
            (a :class:`RuntimeError` and a one-line user error) If the vehicle is not a
            boat/rover, refuses GUIDED or does not acknowledge it within
            ``command_timeout_s``, or does not arm within ``arm_timeout_s`` (its mode is then
            set back to what it was).
        HeartbeatTimeoutError
            If no heartbeat arrives within ``heartbeat_timeout_s``.
        """
        want = self.args.target_system

        def is_vehicle(r: Received) -> bool:
            hb = r.message
            return (
                isinstance(hb, Heartbeat)
                and hb.type != 6
                and r.src_component == 1
                and (want == 0 or r.src_system == want)
            )

        first = self.link.wait_heartbeat(self.args.heartbeat_timeout_s, is_vehicle)
        hb = first.message
        assert isinstance(hb, Heartbeat)
        if not hb.is_boat_or_rover:
            raise VehicleError(
                f"vehicle {first.src_system} is MAV_TYPE {hb.type}, not a surface "
                "boat (11) or ground rover (10)"
            )
        self.target = first.src_system
        self.watch = VehicleWatch(self.target)
        self._write("info", f"vehicle {self.target} type {hb.type} mode {hb.custom_mode}")
        timeout = self.args.command_timeout_s
        streams = (
            ("GLOBAL_POSITION_INT", self.args.telemetry_rate_hz),
            ("ATTITUDE", self.args.telemetry_rate_hz),
            ("SYS_STATUS", 1.0),
            ("EKF_STATUS_REPORT", 1.0),
        )
        for name, rate in streams:  # a vehicle that refuses one still works; readiness knows
            self.link.request_message_interval(self.target, name, rate)
            ack = wait_ack(self.link, self.watch, MavCommand.SET_MESSAGE_INTERVAL, timeout)
            if name == "EKF_STATUS_REPORT":
                self.watch.ekf_expected = ack is not None and ack.result == MAV_RESULT_ACCEPTED
        if self.args.attitude_target and self.wp_speed_mps <= 0:
            value = self._read_param("WP_SPEED", timeout)
            if value is None or not value > 0:
                raise VehicleError(
                    f"vehicle {self.target} did not report WP_SPEED within {timeout:g} s "
                    "(--attitude-target scales thrust by it); give --wp-speed-mps"
                )
            self.wp_speed_mps = value
            self._say(f"WP_SPEED {value:g} m/s (read from the vehicle)")
        if self.args.attitude_target and self.mission.cruise_speed_mps > self.wp_speed_mps:
            self._say(
                f"the mission's {self.mission.cruise_speed_mps:g} m/s exceeds WP_SPEED "
                f"{self.wp_speed_mps:g} m/s: thrust 1 gives WP_SPEED"
            )
        self.result.wp_speed_mps = self.wp_speed_mps
        self.link.set_mode(self.target, RoverMode.GUIDED)
        ack = wait_ack(self.link, self.watch, MavCommand.DO_SET_MODE, timeout)
        if ack is None:  # silence is not a refusal: a lost ACK, a busy or slow vehicle
            raise VehicleError(
                f"vehicle {self.target} did not acknowledge GUIDED mode within {timeout:g} s "
                "(no COMMAND_ACK; --command-timeout-s sets the wait)"
            )
        if ack.result != MAV_RESULT_ACCEPTED:
            raise VehicleError(
                f"vehicle {self.target} refused GUIDED mode (COMMAND_ACK result "
                f"{_result_name(ack.result)})"
            )
        if self.args.arm:
            try:
                self.result.arm_attempts = arm_when_ready(
                    self.link,
                    self.watch,
                    self.args.arm_timeout_s,
                    self.args.arm_retry_s,
                    timeout,
                    self._say,
                )
            except VehicleError:
                self.link.set_mode(self.target, RoverMode(hb.custom_mode))  # as it was
                wait_ack(self.link, self.watch, MavCommand.DO_SET_MODE, timeout)
                raise
        self._write("info", "GUIDED" + (", armed" if self.args.arm else ""))

    # --- the loop --------------------------------------------------------------------------

    def telemetry_age_s(self, now_wall: float) -> float:
        """Age of the last telemetry on the vehicle clock, extrapolated at the measured rate.

        ``(wall now − wall at receipt) · max(ρ, 1)`` with ρ the vehicle-clock rate (vehicle s
        per wall s) measured over the telemetry: the vehicle clock when it runs faster than
        real time, the wall clock otherwise (never later than real time).
        """
        if self._last_rx_wall is None:
            return 0.0
        return (now_wall - self._last_rx_wall) * max(self.clock_rate, 1.0)

    def telemetry_stale(self, now_wall: float) -> bool:
        """Older than ``stale_s`` of vehicle time and ``stale_wall_min_s`` of wall clock.

        The wall-clock floor keeps a fast SITL (30×: 1.5 vehicle s = 50 ms) from calling a
        thread-scheduling hiccup a telemetry loss.
        """
        if self._last_rx_wall is None:
            return False
        wall_age = now_wall - self._last_rx_wall
        return self.telemetry_age_s(now_wall) > self.args.stale_s and (
            wall_age > self.args.stale_wall_min_s
        )

    def _on_telemetry(self, r: Received, rx_wall: float) -> None:
        msg = r.message
        if isinstance(msg, Attitude):
            self._attitude = msg
            return
        if not isinstance(msg, GlobalPosition) or self._attitude is None:
            return
        t_ms = msg.time_boot_ms
        if self.estimator.last_ms is not None and t_ms <= self.estimator.last_ms:
            return  # old or repeated sample
        # vehicle-clock rate over the last ~1 s of wall clock (a sliding window, so a burst of
        # queued packets at the start does not bias it for long)
        self._rate_window.append((rx_wall, t_ms))
        while rx_wall - self._rate_window[0][0] > 1.0:
            self._rate_window.popleft()
        w0, m0 = self._rate_window[0]
        if rx_wall - w0 > 0.05:
            self.clock_rate = (t_ms - m0) / 1000.0 / (rx_wall - w0)
        self._last_rx_wall = rx_wall
        self.result.telemetry_ticks += 1
        pos = ned_from_geodetic(msg.lat_deg, msg.lon_deg, self.mission.origin)
        a = self._attitude
        self.estimator.update(
            t_ms, pos, np.array([msg.vn_mps, msg.ve_mps]), a.yaw_rad, a.yaw_rate_radps
        )
        if self._start_ms is None:
            self._start_ms = t_ms
            self._next = dict.fromkeys(self._next, t_ms)
        est = self.estimator.pos_ne
        self.result.path_ne.append((t_ms / 1000.0, float(est[0]), float(est[1])))
        self._tick(t_ms, rx_wall)

    def _tick(self, t_ms: int, rx_wall: float) -> None:
        """Decide, stream and heartbeat on the vehicle clock; raise FailsafeError to stop."""
        pos, psi = self.estimator.pos_ne, self.estimator.psi
        if float(np.hypot(*(pos - self.goal_ne))) <= self.mission.goal_radius_m:
            raise FailsafeError("goal reached")
        assert self._start_ms is not None
        if self.args.max_duration_s > 0 and t_ms - self._start_ms > self.args.max_duration_s * 1e3:
            raise FailsafeError("max duration")
        sent = False
        if t_ms >= self._next["decision"]:
            self._decide(pos, psi)
            self._next["decision"] += round(self.args.decision_period_s * 1000)
            self._send_setpoint()
            sent = True
            self.result.latencies_s.append(self._clock() - rx_wall)
            self._next["setpoint"] = t_ms
        if t_ms >= self._next["setpoint"]:
            if not sent:
                self._send_setpoint()
            self._next["setpoint"] += round(1000.0 / self.args.setpoint_rate_hz)
        if t_ms >= self._next["heartbeat"]:
            self.link.send_gcs_heartbeat()
            self._next["heartbeat"] += 1000

    def _decide(self, pos: np.ndarray, psi: float) -> None:
        poles = self.poles_ne
        pole = poles[np.argmin(np.hypot(*(poles - pos).T))]  # the nearest pole is "the" pole
        obs = build_observation(
            self.observation,
            pos[None],
            np.array([psi]),
            pole[None],
            self.goal_ne[None],
            self.mission.pole_radius_m,
            self.radar,
            self._rng,
        )
        try:
            actions = self.helmsman.act(obs)
        except Exception as err:  # any helmsman failure must end in HOLD, and is logged
            raise FailsafeError(f"helmsman error: {type(err).__name__}: {err}") from err
        try:
            dpsi = heading_change_rad(
                self.action, actions, 1, math.radians(self.args.max_heading_change_deg)
            )
        except ValueError as err:
            raise FailsafeError(f"invalid action: {err}") from err
        psi_ref = float(ssa(psi + dpsi[0]))
        self._setpoint = (psi_ref, self.mission.cruise_speed_mps)
        self.result.decisions += 1
        self._write(
            "decision",
            x_n_m=float(pos[0]),
            y_e_m=float(pos[1]),
            psi_deg=math.degrees(psi),
            action=str(np.asarray(actions).ravel().tolist()),
            psi_ref_deg=math.degrees(psi_ref),
            speed_mps=self.mission.cruise_speed_mps,
        )

    def _send_setpoint(self) -> None:
        if self._setpoint is None:
            return
        psi_ref, speed = self._setpoint
        if self.args.attitude_target:
            thrust = min(1.0, speed / self.wp_speed_mps)  # Rover: speed = thrust · WP_SPEED
            self.link.send_attitude_target(self.target, psi_ref, thrust)
        else:
            self.link.send_heading(self.target, psi_ref, speed)

    def stop(self, reason: str) -> None:
        """Stop streaming and command the failsafe mode until acknowledged (module docstring)."""
        self._setpoint = None
        mode = FAILSAFE_MODES[self.args.failsafe]
        self.result.reason = reason
        self._write("done" if reason == "goal reached" else "failsafe", reason)
        if reason != "goal reached":
            self._say(f"failsafe: {reason}; commanding {mode.name}")
        delivery = deliver_mode(
            self.link,
            self.watch,
            mode,
            self.args.failsafe_deadline_s,
            self.args.failsafe_repeat_s,
            self.args.reconnect_attempts,
            self._say,
        )
        self.result.failsafe = delivery
        detail = (
            f"{mode.name} {delivery.how} after {delivery.elapsed_s:.2f} s, "
            f"{delivery.commands} command(s)"
        )
        if delivery.acknowledged:
            self._write("ack", detail)
            return
        self._write("unacknowledged", detail)
        print(
            f"usvsim bridge: FAILSAFE NOT ACKNOWLEDGED: {mode.name} commanded "
            f"{delivery.commands} time(s) over {delivery.elapsed_s:.1f} s, {delivery.how}; "
            "the vehicle may still follow its last setpoint (Rover drops a GUIDED target "
            "after ~3 s)",
            file=sys.stderr,
            flush=True,
        )

    def loop(self, max_wall_s: float = math.inf) -> BridgeResult:
        """Run until a failsafe, the goal, Ctrl-C, or ``max_wall_s``; always ends in
        :meth:`stop` (the failsafe mode commanded until acknowledged or its deadline)."""
        start = self._clock()
        try:
            while True:
                now = self._clock()
                if now - start > max_wall_s:
                    raise FailsafeError("wall-clock limit")
                if self._last_rx_wall is None and now - start > self.args.heartbeat_timeout_s:
                    raise FailsafeError("no telemetry")
                for r in self.link.poll(0.01):
                    self.watch.update(r)
                    if self._accept(r):
                        self._on_telemetry(r, self._clock())
                # judged at `now`, after a poll that read everything waiting since: time the
                # bridge itself spent (a slow decision, a descheduled thread) while the vehicle
                # kept talking is not a telemetry loss
                if self.telemetry_stale(now):
                    raise FailsafeError(
                        f"stale telemetry ({self.telemetry_age_s(now):.2f} s vehicle clock)"
                    )
        except FailsafeError as failure:
            self.stop(str(failure))
        except LinkLostError as err:
            self.stop(f"link lost ({err})")
        except KeyboardInterrupt:
            self.stop("interrupted (Ctrl-C)")
            raise
        finally:
            self.result.telemetry_wall_s = self._clock() - start
        return self.result

    def close(self) -> None:
        self.link.close()
        if self._log_file is not None:
            self._log_file.close()
            self._log_file = None

    def run(self, max_wall_s: float = math.inf) -> BridgeResult:
        """connect, reset the helmsman, loop; the link and the log are closed at the end."""
        try:
            self.connect()
            self.helmsman.reset(1)
            return self.loop(max_wall_s)
        finally:
            self.close()
