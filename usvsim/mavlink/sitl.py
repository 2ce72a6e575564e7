"""``usvsim sitl``: the usvsim plant behind a MAVLink endpoint that behaves like ArduPilot Rover.

One boat (vessel model + heading autopilot + sensors + navigation filter, as in the simulator)
answers the subset of Rover's MAVLink interface the bridge uses, so the same bridge that drives a
real ArduPilot boat can be tested against it, and MAVProxy or QGroundControl can watch it.

Why this module is long: it is one vehicle's whole MAVLink face (commands, arming readiness,
streams, GUIDED targets, mode switching, fault injection), each part small and tied to the same
state; the parameter and mission protocols and the position modes are already their own modules.

What it answers:

* HEARTBEAT (1 Hz): ``MAV_TYPE_SURFACE_BOAT``, ``MAV_AUTOPILOT_ARDUPILOTMEGA``, Rover custom
  modes MANUAL 0, HOLD 4, LOITER 5, AUTO 10, RTL 11, GUIDED 15; armed flag.
* COMMAND_LONG ``COMPONENT_ARM_DISARM``, ``DO_SET_MODE``, ``SET_MESSAGE_INTERVAL``,
  ``REQUEST_MESSAGE`` (any stream, and AUTOPILOT_VERSION), ``REQUEST_AUTOPILOT_CAPABILITIES`` and
  the SET_MODE message, each answered by COMMAND_ACK addressed to the sender's system and
  component (SET_MODE with command id 11, like ArduPilot).
* Arming, as real ArduPilot showed it (Rover 4.7.0-dev SITL): refused (``MAV_RESULT_FAILED`` and
  a STATUSTEXT reason) until the simulated EKF has an absolute position, ``ekf_delay_s`` after
  boot; the SYS_STATUS pre-arm bit is healthy from half that delay on (ArduPilot set it at
  ~23 s and accepted arming only at ~42 s), so a bridge that trusts the bit alone must retry.
  EKF_STATUS_REPORT carries the EKF flags (``ekf_status_report=False`` mutes it, as an SRx
  rate of 0 would).
* The parameter and mission protocols (:mod:`usvsim.mavlink.rover_protocol`) for the
  parameters it models (:func:`usvsim.mavlink.rover_protocol.sitl_parameters`); AUTO follows
  the uploaded mission with usvsim's LOS guidance, RTL returns to home
  (:mod:`usvsim.mavlink.rover_modes`).
* Telemetry from the navigation *estimate* (what an autopilot's EKF reports): GLOBAL_POSITION_INT,
  ATTITUDE, VFR_HUD; GPS_RAW_INT from a raw GNSS draw; SYS_STATUS with the sensor bits
  (present / enabled / healthy: gyro, accel, mag, GPS, motor outputs, AHRS, pre-arm; no
  geofence, so MAVProxy reports no fence breach); EKF_STATUS_REPORT; MISSION_CURRENT;
  STATUSTEXT on events.
* GUIDED setpoints, ignored outside GUIDED and never acknowledged (as Rover):
  SET_POSITION_TARGET_LOCAL_NED / _GLOBAL_INT with velocity (+ yaw) and SET_ATTITUDE_TARGET
  (yaw quaternion + thrust · WP_SPEED). Rover's semantics: speed ``|(vx, vy)|`` signed by vx,
  heading from yaw (or from the velocity direction if yaw is ignored).
* Rover's guided timeout: no new target for 3 s → stop and hold position (the mode stays GUIDED).

Modes: MANUAL without an RC transmitter = neutral controls; HOLD = motors stop (the boat drifts
with the current); LOITER = stop, then stay within LOIT_RADIUS of where the boat came to rest
(:class:`usvsim.mavlink.rover_modes.HoldPosition`; braking astern while it stops, as Rover's
ATC_BRAKE). Disarmed: motors stop whatever the mode. "Motors stop" integrates the vessel model
(:func:`usvsim.vessel.model.build_dynamics`) with zero thrust and a centred nozzle: the boat
coasts to rest (the plant's autopilot would keep the waterjet at idle thrust).

The simulation steps at the plant's 0.1 s; the vehicle clock (``time_boot_ms``) is simulated
time, paced at ``speedup`` × wall-clock time. Everything runs in one thread.

Fault injection (tests): ``freeze_at_s`` stops the whole vehicle for ``freeze_for_s`` wall
seconds (no physics, no reading, no telemetry: a stopped process; what arrives meanwhile is
read after it resumes), ``drop_client_at_s`` closes the TCP client's connection and listens
for the next (a radio or router glitch), ``drop_link_at_s`` closes the link and ends the
vehicle (a crash: the TCP peer sees EOF, then refused connections), ``mute_telemetry_after_s``
stops telemetry only.
An ocean current (``current_mps`` towards ``current_dir_deg``) makes HOLD drift (LOITER in a
current: see :mod:`usvsim.mavlink.rover_modes`). Wind and waves (``wind`` m/s from ``wind_dir``
deg, gusts 10 %, WMO ``sea_state``, as ``usvsim manoeuvre``'s; seeded by ``seed``): the boat
steps in :class:`usvsim.vessel.weather_plant.WeatherPlant` (the autopilot with its wave filter)
and, motors off, in :class:`usvsim.vessel.weather_open_loop.OpenLoopWeather`; the navigation
filter and GPS_RAW_INT see the first-order wave motion (so does the reported estimate).

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
from dataclasses import dataclass, field, replace
from typing import Any, cast

import numpy as np

from usvsim.common.angles import ssa
from usvsim.common.options import bounds, check_bounds
from usvsim.evaluation.manoeuvre import TrialWeather
from usvsim.mavlink.link import LinkLostError, MavlinkLink, load_signing_key, message_id
from usvsim.mavlink.messages import (
    EKF,
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_DENIED,
    MAV_RESULT_FAILED,
    MAV_RESULT_UNSUPPORTED,
    MAV_SEVERITY_INFO,
    MAV_SEVERITY_WARNING,
    Attitude,
    AutopilotVersion,
    CommandLong,
    EkfStatus,
    GlobalPosition,
    GpsRaw,
    MavCommand,
    Received,
    RoverMode,
    SetAttitudeTarget,
    SetMode,
    SetPositionTarget,
    SysStatus,
    SysStatusSensor,
    VfrHud,
)
from usvsim.mavlink.rover_modes import (
    RETURN_SPEED_MPS,
    SETTLED_SPEED_MPS,
    HoldPosition,
    MissionFollower,
)
from usvsim.mavlink.rover_protocol import ATC_FIELDS, MissionStore, RoverParameters, sitl_parameters
from usvsim.mavlink.sitl_physics import check_sea_state
from usvsim.nav.filter import Navigator
from usvsim.nav.geo import GeoOrigin, geodetic_from_ned, ned_from_geodetic
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import sample_gps
from usvsim.task.scenario import BoatNoise
from usvsim.vessel.autopilot import AutopilotConfig, initial_controller_state
from usvsim.vessel.model import build_dynamics, build_rk4_step
from usvsim.vessel.plant import Plant, PlantState
from usvsim.vessel.weather_open_loop import OpenLoopWeather
from usvsim.vessel.weather_plant import WeatherPlant, WeatherPlantState, sensed_offsets

__all__ = ["FIRMWARE_VERSION", "RoverSitl", "SitlArgs"]

_SUPPORTED_MODES = (
    RoverMode.MANUAL,
    RoverMode.HOLD,
    RoverMode.LOITER,
    RoverMode.AUTO,
    RoverMode.RTL,
    RoverMode.GUIDED,
)
_STREAMS = (
    "HEARTBEAT",
    "GLOBAL_POSITION_INT",
    "ATTITUDE",
    "VFR_HUD",
    "GPS_RAW_INT",
    "SYS_STATUS",
    "EKF_STATUS_REPORT",
    "MISSION_CURRENT",
)
# default intervals (ms) before any SET_MESSAGE_INTERVAL; ArduPilot's SRx defaults are similar
_DEFAULT_INTERVAL_MS = {
    "HEARTBEAT": 1000,
    "GLOBAL_POSITION_INT": 250,
    "ATTITUDE": 250,
    "VFR_HUD": 250,
    "GPS_RAW_INT": 1000,
    "SYS_STATUS": 1000,
    "EKF_STATUS_REPORT": 1000,
    "MISSION_CURRENT": 1000,
}
_SEVERITY_INFO, _SEVERITY_WARNING = MAV_SEVERITY_INFO, MAV_SEVERITY_WARNING
FIRMWARE_VERSION = (4 << 24) | (7 << 16)  # 4.7.0-dev, the Rover it stands in for
# MAV_PROTOCOL_CAPABILITY: MISSION_FLOAT 1, PARAM_FLOAT 2, MISSION_INT 4, SET_ATTITUDE_TARGET
# 128, SET_POSITION_TARGET_LOCAL_NED 256, MAVLINK2 8192
_CAPABILITIES = 1 | 2 | 4 | 128 | 256 | 8192
_SENSORS = (
    SysStatusSensor.GYRO
    | SysStatusSensor.ACCEL
    | SysStatusSensor.MAG
    | SysStatusSensor.GPS
    | SysStatusSensor.MOTOR_OUTPUTS
    | SysStatusSensor.AHRS
    | SysStatusSensor.PREARM_CHECK
)
_EKF_ALWAYS = EKF.ATTITUDE | EKF.VELOCITY_HORIZ | EKF.VELOCITY_VERT | EKF.POS_VERT_ABS
_EKF_WITH_GPS = EKF.POS_HORIZ_REL | EKF.POS_HORIZ_ABS | EKF.PRED_POS_HORIZ_REL
_EKF_WITH_GPS |= EKF.PRED_POS_HORIZ_ABS
NOT_READY_TEXT = "PreArm: EKF has no absolute position yet"  # ours; Rover's text differs


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
    ekf_delay_s: float = field(default=10.0, metadata=bounds(ge=0, le=600))  # arming from, sim s
    ekf_status_report: bool = True  # stream EKF_STATUS_REPORT (off: only the pre-arm bit tells)
    wp_radius_m: float = field(default=5.0, metadata=bounds(gt=0, le=1000))  # WP_RADIUS, m
    current_mps: float = field(default=0.0, metadata=bounds(ge=0, le=5))  # ocean current, m/s
    current_dir_deg: float = field(default=0.0, metadata=bounds(ge=-360, le=360))  # flows to, deg
    mute_telemetry_after_s: float = field(default=0.0, metadata=bounds(ge=0))  # faults; 0: never
    freeze_at_s: float = field(default=0.0, metadata=bounds(ge=0))  # faults: stop at sim s; 0 never
    freeze_for_s: float = field(default=3.0, metadata=bounds(gt=0, le=600))  # ... for wall s
    drop_link_at_s: float = field(default=0.0, metadata=bounds(ge=0))  # faults: crash at sim s
    drop_client_at_s: float = field(default=0.0, metadata=bounds(ge=0))  # faults: tcpin, sim s
    # mean wind speed, m/s (gusts 10 %); 0: none. Weather uses usv105's windage and waterline
    wind: float = field(default=0.0, metadata=bounds(ge=0.0, le=40.0))
    # direction the wind blows from, deg clockwise from north; 90: from the east
    wind_dir: float = field(default=90.0, metadata=bounds(ge=0.0, lt=360.0))
    # WMO sea state code 0-8 (Bales 1983 H_s, T_p); waves come from the wind's direction
    sea_state: int = field(default=0, metadata=bounds(ge=0, le=8))

    def __post_init__(self) -> None:
        # the ranges above (usvsim.common.options), for library callers too
        check_bounds(self)
        check_sea_state(self.sea_state)

    def weather(self) -> TrialWeather:
        """The vehicle's wind and sea (as ``usvsim manoeuvre``'s; ``calm`` without either)."""
        return TrialWeather(self.wind, self.wind_dir, self.sea_state, seed=self.seed)


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
    frozen_wall_s: tuple[float, float] | None = None  # (monotonic start, duration) of a freeze
    dropped_at_s: float | None = None  # sim time the link was dropped
    client_dropped_at_s: float | None = None  # sim time the TCP client was cut off
    position_reports: int = 0  # GLOBAL_POSITION_INT messages sent


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
        self.autopilot = _autopilot(args.autopilot)
        current = (args.current_mps, math.radians(args.current_dir_deg))
        self.plant = Plant(args.vessel, self.autopilot, current=current)
        self.dt_ms = round(self.plant.dt_s * 1000)
        self._coast = build_rk4_step(build_dynamics(self.plant.vessel), self.plant.dt_s)
        eta = (
            np.array([[0.0, 0.0, math.radians(args.heading_deg)]])
            if start_eta is None
            else np.asarray(start_eta, dtype=float).reshape(1, 3)
        )
        self.state = self.plant.initial_state(eta, np.array([args.speed_mps]))
        self._start_weather(eta)
        self.nav = Navigator(NavConfig(dt_s=self.plant.dt_s), 1)
        self._noise = BoatNoise(1)  # the simulator's per-episode stream: same seed, same noise
        self._noise.seed(np.array([0]), [args.seed if noise_seed is None else noise_seed])
        # BoatNoise serves the Generator.normal interface the navigator draws from
        self._noise_stream = cast(np.random.Generator, self._noise)
        self.nav.reset(*self._sensed(), self._noise_stream)
        self._gps_rng = np.random.default_rng(args.seed + 1)
        self.time_ms = 0
        self.step_index = 0
        self.mode = RoverMode.MANUAL
        self.armed = False
        self.frozen = args.wait_for_target
        self.guided = _Guided()
        self.home_ne = self.state.x[0, 0:2].copy()
        self.hold = HoldPosition(self.home_ne)
        self.follower: MissionFollower | None = None
        self.params = RoverParameters(
            sitl_parameters(
                args.system_id,
                args.wp_speed_mps,
                args.wp_radius_m,
                args.loiter_radius_m,
                args.speedup,
                self.autopilot,
            ),
            self._param_changed,
        )
        home = geodetic_from_ned(self.home_ne[0], self.home_ne[1], self.origin)
        self.mission = MissionStore(float(home[0]), float(home[1]))
        self._interval_ms = dict(_DEFAULT_INTERVAL_MS)
        if not args.ekf_status_report:
            self._interval_ms["EKF_STATUS_REPORT"] = 0
        self._next_due_ms = dict.fromkeys(_STREAMS, 0)
        self._thrust_pct = 0
        self._astern_mps = 0.0  # LOITER's astern return speed this step (0: none)
        self._last_reached = 0
        self.record = SitlRecord()
        self.record.modes.append((0.0, self.mode))

    # --- weather ---------------------------------------------------------------------------

    def _start_weather(self, eta: np.ndarray) -> None:
        """Wind and waves (``--wind``, ``--sea-state``): the closed loop steps in the weather
        plant, motors off in :class:`OpenLoopWeather`; the sensors (navigation filter, GPS) see
        the first-order wave motion. Calm: neither is built, every number as without."""
        weather = self.args.weather()
        self.weather: WeatherPlant | None = None
        if weather.calm:
            return
        self.weather = WeatherPlant(self.plant, seed=self.args.seed)
        speed = np.array([self.args.speed_mps])
        self._weather_state = self.weather.initial_state(
            eta, weather.conditions(1), speed, calm=self.state
        )
        self._open_loop = OpenLoopWeather(self.plant.vessel, self.plant.dt_s)
        self._open_loop_rng = np.random.default_rng([self.args.seed, 38])  # motors-off draws

    def _sensed(self) -> tuple[np.ndarray, np.ndarray]:
        """(η, ν) as the sensors see them: plus the first-order wave motion in waves."""
        if self.weather is None:
            return self.state.eta, self.state.nu
        ws = self._weather_state
        d = sensed_offsets(ws.x, ws.m, ws.inputs)
        nu = self.state.nu.copy()
        nu[:, 2] += d[:, 3]
        return self.state.eta + d[:, 0:3], nu

    def _step_in_weather(self, refs: tuple[float, float] | None, a_cmd: list[float]) -> None:
        """One plant step in the weather: the weather plant's closed loop on ``refs``, or the
        open loop on ``a_cmd`` where the motors are off (``refs`` None)."""
        assert self.weather is not None
        ws = self._weather_state
        if refs is None:
            x, m = self._open_loop.step(
                ws.x, np.array([a_cmd]), self.plant.current, ws.m, ws.inputs, self._open_loop_rng
            )
            x[0, 2] = float(ssa(x[0, 2]))
            c = initial_controller_state(self.plant.kind, x[:, 2], x[:, 5])
            self._weather_state = WeatherPlantState(x, c, m, ws.inputs)
        else:
            self._weather_state, _ = self.weather.step(ws, [refs[0]], [refs[1]])
        self.state = self._weather_state.plant

    # --- readiness -------------------------------------------------------------------------

    @property
    def ekf_ready(self) -> bool:
        """The simulated EKF has an absolute position (``ekf_delay_s`` of vehicle time)."""
        return self.time_ms >= self.args.ekf_delay_s * 1000.0

    @property
    def prearm_bit(self) -> bool:
        """The SYS_STATUS pre-arm bit: healthy from half the EKF delay (module docstring)."""
        return self.time_ms >= self.args.ekf_delay_s * 500.0

    def _param_changed(self, name: str, value: float) -> None:
        if name in ATC_FIELDS:
            field_name, scale = ATC_FIELDS[name]
            changes: dict[str, Any] = {field_name: value * scale}
            self.autopilot = replace(self.autopilot, **changes)
            if self.autopilot.kind == "rover":  # the rover cascade runs on these gains
                self.plant = Plant(self.plant.vessel, self.autopilot, current=self.plant.current)
                if self.weather is not None:
                    self.weather = WeatherPlant(self.plant, seed=self.args.seed)

    # --- command handling ------------------------------------------------------------------

    def _for_us(self, target_system: int) -> bool:
        return target_system in (0, self.args.system_id)

    def _set_mode(self, mode: int) -> int:
        if mode not in [int(m) for m in _SUPPORTED_MODES]:
            return MAV_RESULT_DENIED
        new = RoverMode(mode)
        if new == self.mode:
            return MAV_RESULT_ACCEPTED
        pos = self.state.x[0, 0:2]
        if new in (RoverMode.AUTO, RoverMode.RTL):
            targets = self._mission_ne() if new == RoverMode.AUTO else self.home_ne[None]
            try:
                self.follower = MissionFollower(pos, targets, self.params["WP_RADIUS"])
            except ValueError as err:
                if new == RoverMode.AUTO:
                    self.link.send_statustext(_SEVERITY_WARNING, f"AUTO refused: {err}")
                    return MAV_RESULT_FAILED
                self.follower = None  # RTL from within WP_RADIUS of home: hold there
        self.mode = new
        self.hold.restart(pos)
        self.guided = _Guided()
        self._last_reached = 0
        self.record.modes.append((self.time_ms / 1000.0, new))
        self.link.send_statustext(_SEVERITY_INFO, f"Mode {new.name}")
        return MAV_RESULT_ACCEPTED

    def _mission_ne(self) -> np.ndarray:
        wps = self.mission.waypoints()
        if not wps:
            return np.zeros((0, 2))
        lat, lon = zip(*wps, strict=True)
        return np.asarray(ned_from_geodetic(list(lat), list(lon), self.origin)).reshape(-1, 2)

    def _arm(self, arm: bool) -> int:
        if arm and not self.armed and not self.ekf_ready:
            self.link.send_statustext(_SEVERITY_WARNING, NOT_READY_TEXT)
            return MAV_RESULT_FAILED
        self.armed = arm
        self.link.send_statustext(_SEVERITY_INFO, "Armed" if arm else "Disarmed")
        return MAV_RESULT_ACCEPTED

    def _request_message(self, msg_id: int) -> int:
        if msg_id == message_id("AUTOPILOT_VERSION"):
            self.link.send_autopilot_version(AutopilotVersion(_CAPABILITIES, FIRMWARE_VERSION))
            return MAV_RESULT_ACCEPTED
        names = [n for n in _STREAMS if message_id(n) == msg_id]
        if not names:
            return MAV_RESULT_FAILED
        self._send_streams(names)
        return MAV_RESULT_ACCEPTED

    def _command(self, c: CommandLong, src: Received) -> None:
        if not self._for_us(c.target_system):
            return
        result = MAV_RESULT_UNSUPPORTED
        if c.command == MavCommand.COMPONENT_ARM_DISARM:
            result = self._arm(c.params[0] > 0.5)
        elif c.command == MavCommand.DO_SET_MODE:
            result = self._set_mode(int(c.params[1]))
        elif c.command == MavCommand.SET_MESSAGE_INTERVAL:
            result = self._set_interval(int(c.params[0]), c.params[1])
        elif c.command == MavCommand.REQUEST_MESSAGE:
            result = self._request_message(int(c.params[0]))
        elif c.command == MavCommand.REQUEST_AUTOPILOT_CAPABILITIES:
            result = self._request_message(message_id("AUTOPILOT_VERSION"))
        self.link.send_command_ack(c.command, result, src.src_system, src.src_component)

    def _set_interval(self, msg_id: int, interval_us: float) -> int:
        names = [n for n in _STREAMS if message_id(n) == msg_id]
        if not names or (names[0] == "EKF_STATUS_REPORT" and not self.args.ekf_status_report):
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
        speed = min(max(speed_mps, 0.0), self.params["WP_SPEED"])  # waterjet: no astern
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
        self._target(a.yaw_rad, max(-1.0, min(1.0, a.thrust)) * self.params["WP_SPEED"])

    def handle_incoming(self, timeout_s: float) -> None:
        """Read and act on everything that arrives within ``timeout_s`` (wall clock).

        A TCP client that goes away is forgotten (the endpoint listens for the next one).
        """
        try:
            for r in self.link.poll(timeout_s):
                self._dispatch(r)  # its replies may find the client gone too
        except LinkLostError:
            return

    def _dispatch(self, r: Received) -> None:
        msg = r.message
        if isinstance(msg, CommandLong):
            self._command(msg, r)
        elif isinstance(msg, SetMode) and self._for_us(msg.target_system):
            self.link.send_command_ack(
                MavCommand.SET_MODE_MESSAGE,
                self._set_mode(msg.custom_mode),
                r.src_system,
                r.src_component,
            )
        elif isinstance(msg, SetPositionTarget):
            self._position_target(msg)
        elif isinstance(msg, SetAttitudeTarget):
            self._attitude_target(msg)
        elif self._for_us(getattr(msg, "target_system", 0)):
            if not self.params.handle(msg, self.link):
                self.mission.handle(msg, r.src_system, self.link)

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
                self.hold.restart(x[0:2])
                self.record.guided_timeouts_s.append(self.time_ms / 1000.0)
                self.link.send_statustext(_SEVERITY_WARNING, "Guided target timeout: holding")
            if not g.timed_out:
                return g.heading_rad, g.speed_mps
        if self.mode in (RoverMode.AUTO, RoverMode.RTL) and self.follower is not None:
            psi_ref = self.follower.heading(x[0:2], float(x[2]), self.plant.dt_s)
            if self.follower.reached > self._last_reached and self.mode == RoverMode.AUTO:
                self._last_reached = self.follower.reached
                self.link.send_mission_item_reached(self.follower.index_of[self._last_reached - 1])
            if psi_ref is not None:
                return psi_ref, self.follower.speed(x[0:2], self.params["WP_SPEED"])
            # mission complete or home reached: hold where the boat comes to rest
        radius = self.params["LOIT_RADIUS"]
        refs = self.hold.references(x[0:2], float(x[2]), self._water_speed(x), radius)
        if refs is not None and refs[1] < 0.0:  # astern: direct thrust (see _astern_thrust)
            self._astern_mps = -refs[1]
            return None
        return refs

    def _brake_thrust(self) -> float:
        """Astern thrust (N) that stops a boat coming to a hold, where it has a reversing bucket.

        Rover brakes with reverse throttle (ATC_BRAKE = 1); here ``a1_min · min(1, u / 1 m/s)``
        while the surge speed through the water u > 0.05 m/s and the position modes wait for
        the boat to come to rest (LOITER, guided timeout, end of AUTO/RTL); HOLD and disarmed:
        none (it drifts). LOITER's astern return (:class:`HoldPosition`) uses it too.
        """
        act = self.plant.vessel.actuation
        if self._astern_mps > 0.0 and act.a1_min < 0:  # LOITER backing up to its point
            return act.a1_min * min(1.0, self._astern_mps / RETURN_SPEED_MPS)
        x = self.state.x[0]
        speed, direction = self.plant.current
        u = float(x[3]) - speed * math.cos(direction - float(x[2]))  # surge through the water
        holding = self.armed and self.mode not in (RoverMode.HOLD, RoverMode.MANUAL)
        if not holding or self.hold.settled or act.a1_min >= 0 or u <= SETTLED_SPEED_MPS:
            return 0.0
        return act.a1_min * min(1.0, u / 1.0)

    def _water_speed(self, x: np.ndarray) -> float:
        """Speed through the water |ν − ν_c| (m/s): ν is over ground (Fossen 2021, §10.3)."""
        speed, direction = self.plant.current
        rel = direction - float(x[2])
        return float(np.hypot(x[3] - speed * math.cos(rel), x[4] - speed * math.sin(rel)))

    def step(self) -> None:
        """Advance the vehicle clock by one plant step, the physics unless frozen."""
        self._astern_mps = 0.0
        refs = self._references()
        if not self.frozen and self.weather is not None:
            self._step_in_weather(refs, [self._brake_thrust(), 0.0] if refs is None else [])
            self.step_index += 1
            self.nav.step(self.step_index, *self._sensed(), self._noise_stream)
        elif not self.frozen:
            if refs is None:  # motors off (or braking): the vessel model, actuators direct
                a_cmd = [self._brake_thrust(), 0.0]
                x = np.asarray(self._coast(self.state.x[0], a_cmd, self.plant.current))
                x = x.reshape(1, -1)
                x[0, 2] = float(ssa(x[0, 2]))
                c = initial_controller_state(self.plant.kind, x[:, 2], x[:, 5])
                self.state = PlantState(x=x, c=c)
            else:
                self.state, _ = self.plant.step(self.state, [refs[0]], [refs[1]])
            self.step_index += 1
            self.nav.step(self.step_index, self.state.eta, self.state.nu, self._noise_stream)
        a_max = self.plant.vessel.actuation.a1_max
        # VFR_HUD throttle is unsigned: astern (braking) thrust reads as its magnitude
        self._thrust_pct = min(100, round(100.0 * abs(float(self.state.x[0, 6])) / a_max))
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
        try:
            self._send_streams(due)
        except LinkLostError:
            return  # the client went away: the endpoint listens for the next one

    def _send_streams(self, names: list[str]) -> None:
        est = self.nav.estimate
        pos, vel = est.pos_ne[0], est.vel_ne[0]
        psi, rate = float(est.psi[0]), float(est.yaw_rate[0])
        t = self.time_ms
        if "HEARTBEAT" in names:
            self.link.send_vehicle_heartbeat(self.mode, self.armed)
        if "ATTITUDE" in names:
            self.link.send_attitude(Attitude(t, 0.0, 0.0, psi, rate))
        if "GLOBAL_POSITION_INT" in names:
            self.record.position_reports += 1
            lat, lon = geodetic_from_ned(pos[0], pos[1], self.origin)
            self.link.send_global_position(
                GlobalPosition(t, float(lat), float(lon), float(vel[0]), float(vel[1]), psi)
            )
        if "VFR_HUD" in names:
            sog = float(np.hypot(vel[0], vel[1]))
            self.link.send_vfr_hud(VfrHud(sog, round(math.degrees(psi)) % 360, self._thrust_pct))
        if "GPS_RAW_INT" in names:
            raw = sample_gps(self._sensed()[0][:, 0:2], self._gps_rng, self.nav.cfg.sensors)[0]
            lat, lon = geodetic_from_ned(raw[0], raw[1], self.origin)
            self.link.send_gps_raw(
                GpsRaw(t * 1000, 3, float(lat), float(lon), 12),
                float(np.hypot(vel[0], vel[1])),
                math.atan2(vel[1], vel[0]),
            )
        if "SYS_STATUS" in names:
            self.link.send_sys_status(self.sys_status())
        if "EKF_STATUS_REPORT" in names:
            flags = _EKF_ALWAYS | (_EKF_WITH_GPS if self.ekf_ready else 0)
            self.link.send_ekf_status(EkfStatus(int(flags)))
        if "MISSION_CURRENT" in names:
            seq = self.follower.current_waypoint if self.follower is not None else 0
            self.link.send_mission_current(seq if self.mode == RoverMode.AUTO else 0)

    def sys_status(self) -> SysStatus:
        """SYS_STATUS: sensors present and enabled; AHRS healthy with the EKF, pre-arm bit."""
        health = _SENSORS & ~(SysStatusSensor.AHRS | SysStatusSensor.PREARM_CHECK)
        if self.ekf_ready:
            health |= SysStatusSensor.AHRS
        if self.prearm_bit:
            health |= SysStatusSensor.PREARM_CHECK
        return SysStatus(12.6, int(_SENSORS), int(_SENSORS), int(health))

    @contextlib.contextmanager
    def serving_in_background(
        self, max_wall_s: float = 60.0, lockstep_s: float = 0.0
    ) -> Iterator[RoverSitl]:
        """Run :meth:`serve` in a daemon thread for the ``with`` block, then stop and close."""
        stop = threading.Event()
        thread = threading.Thread(
            target=self.serve, args=(stop, max_wall_s, lockstep_s), daemon=True
        )
        thread.start()
        try:
            yield self
        finally:
            stop.set()
            thread.join(5.0)
            self.link.close()

    def serve(
        self, should_stop: object = None, max_wall_s: float = math.inf, lockstep_s: float = 0.0
    ) -> None:
        """Run the loop (incoming → step → telemetry), paced at ``speedup``.

        ``should_stop``: an object with ``is_set()`` (a :class:`threading.Event`) checked every
        step; the loop also ends after ``duration_s`` simulated or ``max_wall_s`` wall seconds,
        and at ``drop_link_at_s`` (the link is closed: a crashed vehicle).

        ``lockstep_s`` > 0 (tests; not a CLI option): lockstep with a GCS that answers every
        GLOBAL_POSITION_INT with one GUIDED target, as the bridge does at its default rates.
        In GUIDED and armed (and until a guided timeout), the vehicle takes no step after a
        GLOBAL_POSITION_INT until a new target has arrived, the mode or arming has changed, or
        ``lockstep_s`` wall seconds have passed (a GCS that stopped answering). Each decision
        then acts from the plant step after the telemetry it was made on, whatever the load
        of the machine; paced, a decision lands ``latency · speedup`` of vehicle time later.
        """
        start = time.monotonic()
        t0_ms = self.time_ms
        frozen_once = False
        self.send_telemetry()
        while True:
            if should_stop is not None and should_stop.is_set():  # type: ignore[attr-defined]
                return
            if self.args.duration_s > 0 and self.time_ms >= self.args.duration_s * 1000.0:
                return
            if time.monotonic() - start > max_wall_s:
                return
            drop = self.args.drop_link_at_s
            if drop > 0 and self.time_ms >= drop * 1000.0:
                self.record.dropped_at_s = self.time_ms / 1000.0
                self.link.close()
                return
            cut = self.args.drop_client_at_s
            if cut > 0 and self.record.client_dropped_at_s is None and self.time_ms >= cut * 1e3:
                if self.link.drop_client():
                    self.record.client_dropped_at_s = self.time_ms / 1000.0
            freeze = self.args.freeze_at_s
            if freeze > 0 and not frozen_once and self.time_ms >= freeze * 1000.0:
                frozen_once = True
                self.record.frozen_wall_s = (time.monotonic(), self.args.freeze_for_s)
                threading.Event().wait(self.args.freeze_for_s)  # a stopped process
                start, t0_ms = time.monotonic(), self.time_ms  # resume at the same pace
            wall_due = start + (self.time_ms + self.dt_ms - t0_ms) / 1000.0 / self.args.speedup
            while (left := wall_due - time.monotonic()) > 0:
                self.handle_incoming(left)
            self.handle_incoming(0.0)
            self.step()
            sent = self.record.position_reports
            self.send_telemetry()
            if lockstep_s > 0 and self.record.position_reports > sent:
                self._await_answer(lockstep_s)

    def _await_answer(self, limit_s: float) -> None:
        """Lockstep (:meth:`serve`): wait for the target that answers the last position."""
        if self.mode != RoverMode.GUIDED or not self.armed or self.guided.timed_out:
            return
        n_targets = len(self.record.targets)
        deadline = time.monotonic() + limit_s
        while len(self.record.targets) == n_targets and self.mode == RoverMode.GUIDED:
            left = deadline - time.monotonic()
            if left <= 0 or not self.armed:
                return
            self.handle_incoming(min(left, 0.05))
