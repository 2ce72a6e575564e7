"""``usvsim sitl``: the usvsim plant behind a MAVLink endpoint that behaves like ArduPilot Rover.

One boat (vessel model + heading autopilot + sensors + navigation filter, as in the simulator)
answers the subset of Rover's MAVLink interface the bridge uses, so the same bridge that drives a
real ArduPilot boat can be tested against it, and MAVProxy or QGroundControl can watch it:

* HEARTBEAT (1 Hz): ``MAV_TYPE_SURFACE_BOAT``, ``MAV_AUTOPILOT_ARDUPILOTMEGA``, Rover custom
  modes MANUAL 0, HOLD 4, LOITER 5, GUIDED 15; armed flag.
* COMMAND_LONG ``COMPONENT_ARM_DISARM``, ``DO_SET_MODE``, ``SET_MESSAGE_INTERVAL`` and the
  SET_MODE message, each answered by COMMAND_ACK (SET_MODE with command id 11, like ArduPilot).
* Telemetry from the navigation *estimate* (what an autopilot's EKF reports): GLOBAL_POSITION_INT,
  ATTITUDE, VFR_HUD; GPS_RAW_INT from a raw GNSS draw; SYS_STATUS; STATUSTEXT on events.
* GUIDED setpoints, ignored outside GUIDED and never acknowledged (as Rover):
  SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT with velocity (+ yaw) and SET_ATTITUDE_TARGET
  (yaw quaternion + thrust · WP_SPEED). Rover's semantics: speed ``|(vx, vy)|`` signed by vx,
  heading from yaw (or from the velocity direction if yaw is ignored).
* Rover's guided timeout: no new target for 3 s → stop and hold position (the mode stays GUIDED).

Modes: MANUAL without an RC transmitter = neutral controls; HOLD = motors stop; LOITER = stop,
then stay within ``loiter_radius_m`` of where the boat came to rest. Disarmed: motors stop
whatever the mode. "Motors stop" integrates the vessel model
(:func:`usvsim.vessel.model.build_dynamics`) with zero thrust and a centred nozzle: the boat coasts
to rest (the plant's autopilot would keep the waterjet at idle thrust).

The simulation steps at the plant's 0.1 s; the vehicle clock (``time_boot_ms``) is simulated
time, paced at ``speedup`` × wall-clock time. Everything runs in one thread.

ArduPilot equivalents for the same bridge::

    sim_vehicle.py -v Rover -f motorboat --console --map        # ArduPilot's own boat model
    usvsim bridge --connect tcp:127.0.0.1:5760 --mission m.json --arm
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from usvsim.common.angles import ssa
from usvsim.common.options import bounds, check_bounds
from usvsim.mavlink.link import MavlinkLink, load_signing_key, message_id
from usvsim.mavlink.messages import (
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_DENIED,
    MAV_RESULT_FAILED,
    MAV_RESULT_UNSUPPORTED,
    Attitude,
    CommandLong,
    GlobalPosition,
    GpsRaw,
    MavCommand,
    RoverMode,
    SetAttitudeTarget,
    SetMode,
    SetPositionTarget,
    SysStatus,
    VfrHud,
)
from usvsim.nav.filter import Navigator
from usvsim.nav.geo import GeoOrigin, geodetic_from_ned
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import sample_gps
from usvsim.task.scenario import BoatNoise
from usvsim.vessel.autopilot import AutopilotConfig, initial_controller_state
from usvsim.vessel.model import build_dynamics, build_rk4_step
from usvsim.vessel.plant import Plant, PlantState

__all__ = ["RoverSitl", "SitlArgs"]

_SUPPORTED_MODES = (RoverMode.MANUAL, RoverMode.HOLD, RoverMode.LOITER, RoverMode.GUIDED)
_STREAMS = ("HEARTBEAT", "GLOBAL_POSITION_INT", "ATTITUDE", "VFR_HUD", "GPS_RAW_INT", "SYS_STATUS")
# default intervals (ms) before any SET_MESSAGE_INTERVAL; ArduPilot's SRx defaults are similar
_DEFAULT_INTERVAL_MS = {
    "HEARTBEAT": 1000,
    "GLOBAL_POSITION_INT": 250,
    "ATTITUDE": 250,
    "VFR_HUD": 250,
    "GPS_RAW_INT": 1000,
    "SYS_STATUS": 1000,
}
_SEVERITY_INFO, _SEVERITY_WARNING = 6, 4


@dataclass(frozen=True)
class SitlArgs:
    """Run the usvsim plant as a MAVLink vehicle (ArduPilot Rover boat subset)."""

    listen: str = "tcpin:127.0.0.1:5760"  # MAVLink endpoint (tcpin:, udpin:, udpout:)
    lat: float = field(default=63.4305, metadata=bounds(ge=-90, le=90))  # start, deg; origin
    lon: float = field(default=10.3951, metadata=bounds(ge=-180, le=180))  # start longitude, deg
    heading_deg: float = field(default=0.0, metadata=bounds(ge=-360, le=360))  # start, deg
    speed_mps: float = field(default=0.0, metadata=bounds(ge=0, le=30))  # start surge speed, m/s
    vessel: str = "default"  # vessel preset (see usvsim demo)
    autopilot: str = "pid"  # heading autopilot: pid | rover | rover-tuned
    speedup: float = field(default=1.0, metadata=bounds(gt=0, le=1000))  # sim s per wall s
    wp_speed_mps: float = field(default=3.0, metadata=bounds(gt=0, le=30))  # WP_SPEED, m/s
    guided_timeout_s: float = field(default=3.0, metadata=bounds(gt=0, le=600))  # target drop, s
    loiter_radius_m: float = field(default=2.0, metadata=bounds(gt=0, le=1000))  # LOIT_RADIUS, m
    seed: int = field(default=0, metadata=bounds(ge=0))  # sensor-noise seed
    system_id: int = field(default=1, metadata=bounds(ge=1, le=255))  # our MAVLink system id
    signing_key: str = ""  # file with a 32-byte MAVLink2 signing key ('' = unsigned)
    wait_for_target: bool = False  # freeze the physics until the first guided target
    duration_s: float = field(default=0.0, metadata=bounds(ge=0))  # sim s; 0: until Ctrl-C
    mute_telemetry_after_s: float = field(default=0.0, metadata=bounds(ge=0))  # faults; 0: never

    def __post_init__(self) -> None:
        # the ranges above (usvsim.common.options), for library callers too
        check_bounds(self)


def _autopilot(name: str) -> AutopilotConfig:
    return AutopilotConfig.from_name(name)


@dataclass
class _Guided:
    """GUIDED controller state: the last heading/speed target and when it arrived (sim ms)."""

    heading_rad: float = 0.0
    speed_mps: float = 0.0
    received_ms: int = -1  # -1: no target yet
    timed_out: bool = False


@dataclass
class SitlRecord:
    """What happened on the endpoint (for tests and plots): times in simulated seconds."""

    times_s: list[float] = field(default_factory=list)
    states: list[np.ndarray] = field(default_factory=list)  # true x (8,) after each step
    plant_steps: list[int] = field(default_factory=list)  # plant steps taken (0 while frozen)
    modes: list[tuple[float, RoverMode]] = field(default_factory=list)  # mode changes
    guided_timeouts_s: list[float] = field(default_factory=list)
    targets: list[tuple[float, float, float]] = field(default_factory=list)  # t, ψ, U


class RoverSitl:
    """One simulated boat behind a :class:`MavlinkLink` (see the module docstring).

    ``link`` may be given (tests); otherwise one is opened on ``args.listen``.
    """

    def __init__(
        self,
        args: SitlArgs,
        link: MavlinkLink | None = None,
        start_eta: np.ndarray | None = None,
        noise_seed: int | None = None,
    ) -> None:
        self.args = args
        key = load_signing_key(args.signing_key) if args.signing_key else None
        self.link = link or MavlinkLink(
            args.listen, system_id=args.system_id, component_id=1, signing_key=key
        )
        self.origin = GeoOrigin(args.lat, args.lon)
        self.plant = Plant(args.vessel, _autopilot(args.autopilot))
        self.dt_ms = round(self.plant.dt_s * 1000)
        self._coast = build_rk4_step(build_dynamics(self.plant.vessel), self.plant.dt_s)
        eta = (
            np.array([[0.0, 0.0, math.radians(args.heading_deg)]])
            if start_eta is None
            else np.asarray(start_eta, dtype=float).reshape(1, 3)
        )
        self.state = self.plant.initial_state(eta, np.array([args.speed_mps]))
        self.nav = Navigator(NavConfig(dt_s=self.plant.dt_s), 1)
        self._noise = BoatNoise(1)  # the simulator's per-episode stream: same seed, same noise
        self._noise.seed(np.array([0]), [args.seed if noise_seed is None else noise_seed])
        # BoatNoise serves the Generator.normal interface the navigator draws from
        self._noise_stream = cast(np.random.Generator, self._noise)
        self.nav.reset(self.state.eta, self.state.nu, self._noise_stream)
        self._gps_rng = np.random.default_rng(args.seed + 1)
        self.time_ms = 0
        self.step_index = 0
        self.mode = RoverMode.MANUAL
        self.armed = False
        self.frozen = args.wait_for_target
        self.guided = _Guided()
        self._hold_point = self.state.x[0, 0:2].copy()
        self._hold_settled = False
        self._interval_ms = dict(_DEFAULT_INTERVAL_MS)
        self._next_due_ms = dict.fromkeys(_STREAMS, 0)
        self._thrust_pct = 0
        self.record = SitlRecord()
        self.record.modes.append((0.0, self.mode))

    # --- command handling ------------------------------------------------------------------

    def _for_us(self, target_system: int) -> bool:
        return target_system in (0, self.args.system_id)

    def _set_mode(self, mode: int) -> int:
        if mode not in [int(m) for m in _SUPPORTED_MODES]:
            return MAV_RESULT_DENIED
        new = RoverMode(mode)
        if new != self.mode:
            self.mode = new
            self._hold_point = self.state.x[0, 0:2].copy()
            self._hold_settled = False
            self.guided = _Guided()
            self.record.modes.append((self.time_ms / 1000.0, new))
            self.link.send_statustext(_SEVERITY_INFO, f"Mode {new.name}")
        return MAV_RESULT_ACCEPTED

    def _command(self, c: CommandLong) -> None:
        if not self._for_us(c.target_system):
            return
        result = MAV_RESULT_UNSUPPORTED
        if c.command == MavCommand.COMPONENT_ARM_DISARM:
            self.armed = c.params[0] > 0.5
            self.link.send_statustext(_SEVERITY_INFO, "Armed" if self.armed else "Disarmed")
            result = MAV_RESULT_ACCEPTED
        elif c.command == MavCommand.DO_SET_MODE:
            result = self._set_mode(int(c.params[1]))
        elif c.command == MavCommand.SET_MESSAGE_INTERVAL:
            result = self._set_interval(int(c.params[0]), c.params[1])
        self.link.send_command_ack(c.command, result)

    def _set_interval(self, msg_id: int, interval_us: float) -> int:
        names = [n for n in _STREAMS if message_id(n) == msg_id]
        if not names:
            return MAV_RESULT_FAILED
        name = names[0]
        if interval_us < 0:
            self._interval_ms[name] = 0  # disabled
        elif interval_us == 0:
            self._interval_ms[name] = _DEFAULT_INTERVAL_MS[name]
        else:
            self._interval_ms[name] = max(self.dt_ms, round(interval_us / 1000.0))
        self._next_due_ms[name] = self.time_ms
        return MAV_RESULT_ACCEPTED

    def _target(self, heading_rad: float, speed_mps: float) -> None:
        if self.mode != RoverMode.GUIDED:
            return  # Rover ignores guided setpoints outside GUIDED, silently
        if not (math.isfinite(heading_rad) and math.isfinite(speed_mps)):
            return
        speed = min(max(speed_mps, 0.0), self.args.wp_speed_mps)  # waterjet: no astern
        self.guided = _Guided(float(ssa(heading_rad)), speed, self.time_ms, False)
        self.record.targets.append((self.time_ms / 1000.0, self.guided.heading_rad, speed))
        self.frozen = False

    def _position_target(self, p: SetPositionTarget) -> None:
        if not self._for_us(p.target_system):
            return
        m = p.type_mask
        vel_used = not m & (8 | 16)
        yaw_used = not m & 1024
        if not vel_used or m & 7 != 7 or not m & 2048:
            return  # position / yaw-rate / heading-only targets: not part of this subset
        speed = math.hypot(p.vx_mps, p.vy_mps) * (-1.0 if yaw_used and p.vx_mps < 0 else 1.0)
        heading = p.yaw_rad if yaw_used else math.atan2(p.vy_mps, p.vx_mps)
        if p.frame in (8, 9):  # MAV_FRAME_BODY_NED / BODY_OFFSET_NED: relative to our heading
            heading += float(self.state.x[0, 2])
        self._target(heading, speed)

    def _attitude_target(self, a: SetAttitudeTarget) -> None:
        if not self._for_us(a.target_system) or a.type_mask & 64 or not a.type_mask & 4:
            return  # thrust ignored or yaw rate used: not part of this subset
        self._target(a.yaw_rad, max(-1.0, min(1.0, a.thrust)) * self.args.wp_speed_mps)

    def handle_incoming(self, timeout_s: float) -> None:
        """Read and act on everything that arrives within ``timeout_s`` (wall clock)."""
        for r in self.link.poll(timeout_s):
            msg = r.message
            if isinstance(msg, CommandLong):
                self._command(msg)
            elif isinstance(msg, SetMode) and self._for_us(msg.target_system):
                self.link.send_command_ack(
                    MavCommand.SET_MODE_MESSAGE, self._set_mode(msg.custom_mode)
                )
            elif isinstance(msg, SetPositionTarget):
                self._position_target(msg)
            elif isinstance(msg, SetAttitudeTarget):
                self._attitude_target(msg)

    # --- simulation ------------------------------------------------------------------------

    def _references(self) -> tuple[float, float] | None:
        """Heading (rad) and speed (m/s) references for the autopilot; ``None``: motors off."""
        x = self.state.x[0]
        if not self.armed or self.mode in (RoverMode.HOLD, RoverMode.MANUAL):
            return None
        if self.mode == RoverMode.GUIDED:
            g = self.guided
            if g.received_ms < 0:
                return None
            if not g.timed_out and self.time_ms - g.received_ms > self.args.guided_timeout_s * 1e3:
                g.timed_out = True
                self._hold_point = x[0:2].copy()
                self._hold_settled = False
                self.record.guided_timeouts_s.append(self.time_ms / 1000.0)
                self.link.send_statustext(_SEVERITY_WARNING, "Guided target timeout: holding")
            if not g.timed_out:
                return g.heading_rad, g.speed_mps
        return self._hold_position(x)

    def _hold_position(self, x: np.ndarray) -> tuple[float, float] | None:
        """LOITER and guided timeout: stop, then keep within the radius of where it stopped.

        While the boat still moves faster than 0.2 m/s the hold point follows it (a boat cannot
        brake, it coasts to a stop); afterwards, drifting outside ``loiter_radius_m`` brings a
        slow return (gain 0.2 1/s, at most 0.5 m/s).
        """
        if float(np.hypot(x[3], x[4])) > 0.2 and not self._hold_settled:
            self._hold_point = x[0:2].copy()
            return None
        self._hold_settled = True
        d = self._hold_point - x[0:2]
        dist = float(np.hypot(d[0], d[1]))
        if dist <= self.args.loiter_radius_m:
            return None
        speed = min(0.5, 0.2 * (dist - self.args.loiter_radius_m))
        return math.atan2(d[1], d[0]), speed

    def step(self) -> None:
        """Advance the vehicle clock by one plant step, the physics unless frozen."""
        refs = self._references()
        if not self.frozen:
            if refs is None:  # motors off: the vessel model with zero actuator commands
                x = np.asarray(self._coast(self.state.x[0], [0.0, 0.0], self.plant.current))
                x = x.reshape(1, -1)
                x[0, 2] = float(ssa(x[0, 2]))
                c = initial_controller_state(self.plant.kind, x[:, 2], x[:, 5])
                self.state = PlantState(x=x, c=c)
            else:
                self.state, _ = self.plant.step(self.state, [refs[0]], [refs[1]])
            self.step_index += 1
            self.nav.step(self.step_index, self.state.eta, self.state.nu, self._noise_stream)
        a_max = self.plant.vessel.actuation.a1_max
        self._thrust_pct = round(100.0 * float(self.state.x[0, 6]) / a_max)
        self.time_ms += self.dt_ms
        self.record.times_s.append(self.time_ms / 1000.0)
        self.record.states.append(self.state.x[0].copy())
        self.record.plant_steps.append(self.step_index)

    def send_telemetry(self) -> None:
        """Send every stream that is due at the current vehicle time."""
        mute = self.args.mute_telemetry_after_s
        if mute > 0 and self.time_ms > mute * 1000.0:
            return
        due = [
            n for n in _STREAMS if self._interval_ms[n] > 0 and self.time_ms >= self._next_due_ms[n]
        ]
        for name in due:
            self._next_due_ms[name] += self._interval_ms[name] * max(
                1, (self.time_ms - self._next_due_ms[name]) // self._interval_ms[name] + 1
            )
        est = self.nav.estimate
        pos, vel = est.pos_ne[0], est.vel_ne[0]
        psi, rate = float(est.psi[0]), float(est.yaw_rate[0])
        t = self.time_ms
        if "HEARTBEAT" in due:
            self.link.send_vehicle_heartbeat(self.mode, self.armed)
        if "ATTITUDE" in due:
            self.link.send_attitude(Attitude(t, 0.0, 0.0, psi, rate))
        if "GLOBAL_POSITION_INT" in due:
            lat, lon = geodetic_from_ned(pos[0], pos[1], self.origin)
            self.link.send_global_position(
                GlobalPosition(t, float(lat), float(lon), float(vel[0]), float(vel[1]), psi)
            )
        if "VFR_HUD" in due:
            sog = float(np.hypot(vel[0], vel[1]))
            self.link.send_vfr_hud(VfrHud(sog, round(math.degrees(psi)) % 360, self._thrust_pct))
        if "GPS_RAW_INT" in due:
            raw = sample_gps(self.state.x[:, 0:2], self._gps_rng, self.nav.cfg.sensors)[0]
            lat, lon = geodetic_from_ned(raw[0], raw[1], self.origin)
            self.link.send_gps_raw(
                GpsRaw(t * 1000, 3, float(lat), float(lon), 12),
                float(np.hypot(vel[0], vel[1])),
                math.atan2(vel[1], vel[0]),
            )
        if "SYS_STATUS" in due:
            self.link.send_sys_status(SysStatus(12.6))

    @contextlib.contextmanager
    def serving_in_background(self, max_wall_s: float = 60.0) -> Iterator[RoverSitl]:
        """Run :meth:`serve` in a daemon thread for the ``with`` block, then stop and close."""
        stop = threading.Event()
        thread = threading.Thread(target=self.serve, args=(stop, max_wall_s), daemon=True)
        thread.start()
        try:
            yield self
        finally:
            stop.set()
            thread.join(5.0)
            self.link.close()

    def serve(self, should_stop: object = None, max_wall_s: float = math.inf) -> None:
        """Run the loop (incoming → step → telemetry), paced at ``speedup``.

        ``should_stop``: an object with ``is_set()`` (a :class:`threading.Event`) checked every
        step; the loop also ends after ``duration_s`` simulated or ``max_wall_s`` wall seconds.
        """
        start = time.monotonic()
        t0_ms = self.time_ms
        self.send_telemetry()
        while True:
            if should_stop is not None and should_stop.is_set():  # type: ignore[attr-defined]
                return
            if self.args.duration_s > 0 and self.time_ms >= self.args.duration_s * 1000.0:
                return
            if time.monotonic() - start > max_wall_s:
                return
            wall_due = start + (self.time_ms + self.dt_ms - t0_ms) / 1000.0 / self.args.speedup
            while (left := wall_due - time.monotonic()) > 0:
                self.handle_incoming(left)
            self.handle_incoming(0.0)
            self.step()
            self.send_telemetry()
