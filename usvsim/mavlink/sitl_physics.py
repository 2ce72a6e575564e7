"""``usvsim sitl-physics``: the usvsim vessel model as a JSON physics backend for ArduPilot SITL.

ArduPilot's SITL ``JSON`` model (``libraries/SITL/SIM_JSON.cpp``) runs the autopilot and sends
the servo outputs of every physics frame over UDP; the backend integrates its physics for one
frame and answers with the vehicle state as JSON. ArduPilot's own controllers (Rover steering
and throttle, AR_AttitudeControl, L1/S-curve navigation) then steer the Fossen model.

Servo frame (little endian), ``struct servo_packet``::

    uint16 magic        18458 (16 channels) or 29569 (32 channels)
    uint16 frame_rate   physics rate (Hz): one frame advances the physics by 1/frame_rate s
    uint32 frame_count  +1 per frame; a repeat is a re-send, a decrease a SITL restart
    uint16 pwm[16|32]   µs

Reply: one JSON object per frame between newlines, ``timestamp`` (s, physics time),
``imu.gyro`` (rad/s, body FRD), ``imu.accel_body`` (m/s², body FRD, specific force, so
[0, 0, -9.81] at rest), ``position`` and ``velocity`` (m, m/s, NED from the start point),
``attitude`` ([roll, pitch, yaw], rad).

The reply is *compact* JSON (``separators=(",", ":")``, no NaN): SIM_JSON.cpp's parser is no
JSON parser. For each key of its table it finds the section (``imu``) and then the key with
``strstr``, skips ``strlen(key) + 2`` characters (the closing quote and the colon) and reads a
number with ``atof`` or a vector with ``sscanf(p, "[%f, %f, %f]")``, so a space after the colon
(Python's default ``": "``) makes every vector fail ("Failed to parse Vector3f for imu/gyro")
and the SITL clock never advances. ``tests/usvsim/mavlink/test_sitl_physics.py`` re-implements
that scanning and checks every reply with it.

Actuator mapping (Rover ``motorboat`` defaults, :class:`ServoMapping`): SERVO1 = GroundSteering
(function 26), SERVO3 = Throttle (function 70), both SERVOn_MIN..MAX = 1000-2000 µs around a
SERVOn_TRIM of 1500 µs (ArduPilot's ``Tools/autotest/default_params/rover.parm`` and the shipped
``usvsim/mavlink/params/*.parm``); other ranges and channels by options. Steering +1 (MAX)
turns to starboard: nozzle angle ``δ = s · δ_max``; throttle ``t ∈ [-1, 1]`` (above trim
scaled by MAX − TRIM, below by TRIM − MIN, as ArduPilot's angle-type outputs) gives thrust
``t · T_max`` for t ≥ 0 and ``|t| · T_astern`` below trim where the vessel has a reversing
bucket (none otherwise). For ``forces`` vessels: ``F_x = t · F_x,max`` (``t · |F_x,min|``
astern), ``F_y = s · F_y,max``.

Start ArduPilot against it (ArduPilot source tree, Rover), with the Rover parameters derived for
the vessel (:mod:`usvsim.mavlink.rover_params`)::

    usvsim sitl-physics --write-params usv105.parm     # writes the file and exits
    usvsim sitl-physics --port 9002 &
    sim_vehicle.py -v Rover -f motorboat --model JSON:127.0.0.1 \
        --add-param-file=usv105.parm --console --map
    usvsim bridge --connect tcp:127.0.0.1:5760 --mission m.json --arm
"""

from __future__ import annotations

import json
import math
import socket
import struct
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.common.options import bounds
from usvsim.evaluation.manoeuvre import TrialWeather
from usvsim.vessel.model import NX, build_dynamics, build_rk4_step
from usvsim.vessel.vessels import Actuation, VesselParams
from usvsim.vessel.weather.waves import WaveResponse, wave_motion_init
from usvsim.vessel.weather.wind import GustParams
from usvsim.vessel.weather_open_loop import OpenLoopWeather
from usvsim.vessel.weather_plant import NWS, sensed_offsets, weather_inputs

__all__ = [
    "JsonPhysics",
    "ServoFrame",
    "ServoMapping",
    "SitlPhysicsArgs",
    "actuator_command",
    "compact_json",
    "parse_servo_frame",
]

MAGIC_16 = 18458
MAGIC_32 = 29569
GRAVITY_MPS2 = 9.80665  # m/s², standard gravity
_HEADER = struct.Struct("<HHI")


def check_sea_state(code: object) -> None:
    """``--sea-state`` must be a WMO code 0-8 (one line, :class:`UserError`), as for
    ``usvsim manoeuvre`` (``usvsim sitl`` and ``sitl-physics``)."""
    if isinstance(code, bool) or not isinstance(code, int) or not 0 <= code <= 8:
        raise UserError(f"--sea-state must be an integer code 0-8, got {code!r}")


@dataclass(frozen=True)
class SitlPhysicsArgs:
    """Serve the usvsim vessel model to ArduPilot SITL (--model JSON)."""

    bind: str = "127.0.0.1"  # address to listen on for ArduPilot's servo frames
    port: int = field(default=9002, metadata=bounds(ge=0, le=65535))  # UDP port (ArduPilot: 9002)
    vessel: str = "default"  # vessel preset (see usvsim demo)
    heading_deg: float = field(default=0.0, metadata=bounds(ge=-360, le=360))  # start, deg
    steering_channel: int = field(default=1, metadata=bounds(ge=1, le=16))  # servo (Rover SERVO1)
    throttle_channel: int = field(default=3, metadata=bounds(ge=1, le=16))  # servo (Rover SERVO3)
    # µs, SERVOn_MIN / TRIM / MAX of the steering and throttle outputs (the shipped .parm's)
    steering_pwm_min: int = field(default=1000, metadata=bounds(ge=500, le=2500))  # µs, full port
    steering_pwm_trim: int = field(default=1500, metadata=bounds(ge=500, le=2500))  # µs, centre
    steering_pwm_max: int = field(default=2000, metadata=bounds(ge=500, le=2500))  # µs, starboard
    throttle_pwm_min: int = field(default=1000, metadata=bounds(ge=500, le=2500))  # µs, astern
    throttle_pwm_trim: int = field(default=1500, metadata=bounds(ge=500, le=2500))  # µs, none
    throttle_pwm_max: int = field(default=2000, metadata=bounds(ge=500, le=2500))  # µs, full
    duration_s: float = field(default=0.0, metadata=bounds(ge=0))  # physics s; 0: until Ctrl-C
    write_params: str = ""  # write the vessel's Rover .parm file here and exit ('' = serve)
    # mean wind speed, m/s (gusts 10 %); 0: none. Weather uses usv105's windage and waterline
    wind: float = field(default=0.0, metadata=bounds(ge=0.0, le=40.0))
    # direction the wind blows from, deg clockwise from north; 90: from the east
    wind_dir: float = field(default=90.0, metadata=bounds(ge=0.0, lt=360.0))
    # WMO sea state code 0-8 (Bales 1983 H_s, T_p); waves come from the wind's direction
    sea_state: int = field(default=0, metadata=bounds(ge=0, le=8))
    seed: int = field(default=0, metadata=bounds(ge=0))  # gusts and wave motion

    def weather(self) -> TrialWeather:
        """The wind and sea (as ``usvsim manoeuvre``'s; ``calm`` without either)."""
        return TrialWeather(self.wind, self.wind_dir, self.sea_state, seed=self.seed)

    def check(self) -> None:
        """Rules beyond the ranges (:func:`usvsim.cli.args.check_options` calls it)."""
        check_sea_state(self.sea_state)
        if self.steering_channel == self.throttle_channel:
            raise UserError(
                f"--steering-channel and --throttle-channel must differ, both are "
                f"{self.steering_channel}"
            )
        for name in ("steering", "throttle"):
            lo, mid, hi = (getattr(self, f"{name}_pwm_{k}") for k in ("min", "trim", "max"))
            if not lo < mid < hi:
                raise UserError(
                    f"--{name}-pwm-min < --{name}-pwm-trim < --{name}-pwm-max is required, "
                    f"got {lo} / {mid} / {hi} µs"
                )

    def mapping(self) -> ServoMapping:
        """The servo channels and PWM ranges these options give."""
        return ServoMapping(
            self.steering_channel,
            self.throttle_channel,
            (self.steering_pwm_min, self.steering_pwm_trim, self.steering_pwm_max),
            (self.throttle_pwm_min, self.throttle_pwm_trim, self.throttle_pwm_max),
        )


@dataclass(frozen=True)
class ServoMapping:
    """Which servo outputs steer and throttle, and their PWM ranges (µs, min / trim / max).

    Defaults: Rover's SERVO1 (GroundSteering) and SERVO3 (Throttle) at 1000 / 1500 / 2000 µs,
    as ``rover.parm`` and the shipped parameter files set them.
    """

    steering_channel: int = 1  # 1-based servo output
    throttle_channel: int = 3  # 1-based servo output
    steering_pwm_us: tuple[int, int, int] = (1000, 1500, 2000)  # µs, SERVO1_MIN/TRIM/MAX
    throttle_pwm_us: tuple[int, int, int] = (1000, 1500, 2000)  # µs, SERVO3_MIN/TRIM/MAX


@dataclass(frozen=True)
class ServoFrame:
    """One decoded servo packet."""

    frame_rate_hz: int
    frame_count: int
    pwm_us: tuple[int, ...]  # 16 or 32 channels


def parse_servo_frame(data: bytes) -> ServoFrame:
    """Decode ``struct servo_packet`` (16 or 32 channels).

    Raises
    ------
    ValueError
        On a wrong magic, a size that does not match it, or a zero frame rate.
    """
    if len(data) < _HEADER.size:
        raise ValueError(f"servo frame too short: {len(data)} bytes")
    magic, rate, count = _HEADER.unpack_from(data)
    channels = {MAGIC_16: 16, MAGIC_32: 32}.get(magic)
    if channels is None:
        raise ValueError(f"bad servo frame magic {magic} (want {MAGIC_16} or {MAGIC_32})")
    if len(data) != _HEADER.size + 2 * channels:
        raise ValueError(
            f"servo frame with magic {magic} must be {_HEADER.size + 2 * channels} "
            f"bytes, got {len(data)}"
        )
    if rate == 0:
        raise ValueError("servo frame rate is 0 Hz")
    pwm = struct.unpack_from(f"<{channels}H", data, _HEADER.size)
    return ServoFrame(rate, count, tuple(pwm))


def pack_servo_frame(frame: ServoFrame) -> bytes:
    """Encode a servo packet (what ArduPilot sends; used by tests and tools)."""
    magic = MAGIC_16 if len(frame.pwm_us) == 16 else MAGIC_32
    n = len(frame.pwm_us)
    return _HEADER.pack(magic, frame.frame_rate_hz, frame.frame_count) + struct.pack(
        f"<{n}H", *frame.pwm_us
    )


def _normalized(pwm_us: int, pwm_range: tuple[int, int, int]) -> float:
    """PWM (µs) → [-1, 1]: (pwm − trim) / (max − trim) above trim, / (trim − min) below.

    ArduPilot's angle-type outputs (steering, boat throttle) map ±1 to MAX / MIN around TRIM
    (``SRV_Channel::pwm_from_angle``). 0 µs (channel not driven) is neutral.
    """
    if pwm_us == 0:
        return 0.0
    lo, trim, hi = pwm_range
    span = (hi - trim) if pwm_us >= trim else (trim - lo)
    return max(-1.0, min(1.0, (pwm_us - trim) / span))


def actuator_command(
    steering_pwm: int, throttle_pwm: int, act: Actuation, mapping: ServoMapping | None = None
) -> tuple[float, float]:
    """Actuator command ``a_cmd = [a1, a2]`` of the vessel model from steering/throttle PWM."""
    mapping = mapping or ServoMapping()
    s = _normalized(steering_pwm, mapping.steering_pwm_us)
    t = _normalized(throttle_pwm, mapping.throttle_pwm_us)
    # below neutral: astern thrust where the vessel has it (a waterjet's reversing bucket), else 0
    a1 = t * act.a1_max if t >= 0 else -t * act.a1_min
    return a1, s * act.a2_max


class JsonPhysics:
    """The vessel model stepped frame by frame from servo frames (no sockets: see :func:`run`).

    State ``x`` (8,) as in :mod:`usvsim.vessel.model`; physics time ``time_s``. In ``weather``
    (not calm) each frame is a step of :class:`usvsim.vessel.weather_open_loop.OpenLoopWeather`
    (wind and wave drift loads, gusts and wave motion at the frame's rate, seeded by the
    weather's seed) and the reply's position, heading and yaw rate carry the first-order wave
    motion (what ArduPilot's GPS, compass and gyro would see; the velocity does not, as in the
    simulator's sensors); weather states ``m`` (8,) as the weather plant's.
    """

    def __init__(
        self,
        vessel: VesselParams,
        heading_rad: float = 0.0,
        mapping: ServoMapping | None = None,
        weather: TrialWeather | None = None,
    ) -> None:
        self.vessel = vessel
        self.mapping = mapping or ServoMapping()
        self._f = build_dynamics(vessel)
        self._steps: dict[int, ca.Function] = {}
        self._ch = (self.mapping.steering_channel - 1, self.mapping.throttle_channel - 1)
        self._heading0 = heading_rad
        self.weather = None if weather is None or weather.calm else weather
        if self.weather is not None:
            self._rng = np.random.default_rng(self.weather.seed)
            self._weather_steps: dict[
                int, tuple[OpenLoopWeather, NDArray[np.float64], WaveResponse]
            ] = {}
        self.reset()

    def reset(self) -> None:
        """Back to rest at the start pose, time 0 (a SITL restart)."""
        self.x: NDArray[np.float64] = np.zeros(NX)
        self.x[2] = self._heading0
        self.time_s = 0.0
        self.last_count: int | None = None
        self._last_reply = ""
        self._xdot = np.zeros(NX)
        self.m: NDArray[np.float64] = np.zeros(NWS)
        if self.weather is not None:  # gusts and wave motion from their stationary laws
            _, inputs, resp = self._weather_inputs(10)
            sigma = self.weather.gust_intensity * self.weather.wind_speed_mps
            self.m[0] = sigma * self._rng.standard_normal()
            self.m[1:3] = wave_motion_init(self._rng, resp)[0]
            self.m[5] = self._heading0 + sensed_offsets(self.x, self.m, inputs[0])[2]

    def _weather_inputs(
        self, rate_hz: int
    ) -> tuple[OpenLoopWeather, NDArray[np.float64], WaveResponse]:
        """The open-loop step at ``rate_hz``, the weather inputs (1, 33) for its step (the
        wave motion at the sea's peak frequency: the boat starts at rest) and the wave
        response; built once per frame rate."""
        assert self.weather is not None
        if rate_hz not in self._weather_steps:
            dt = 1.0 / rate_hz
            cond = self.weather.conditions(1)
            zero, heading = np.zeros(1), np.full(1, self._heading0)
            inputs, resp = weather_inputs(cond, zero, heading, dt, GustParams(), None, (1.0, 0.0))
            self._weather_steps[rate_hz] = (OpenLoopWeather(self.vessel, dt), inputs, resp)
        return self._weather_steps[rate_hz]

    def _step_function(self, rate_hz: int) -> ca.Function:
        if rate_hz not in self._steps:
            self._steps[rate_hz] = build_rk4_step(self._f, 1.0 / rate_hz)
        return self._steps[rate_hz]

    def handle(self, frame: ServoFrame) -> str:
        """Advance one frame (unless it repeats the last count) and return the JSON reply."""
        if self.last_count is not None and frame.frame_count == self.last_count:
            return self._last_reply  # a re-send of the same frame: same answer
        if self.last_count is not None and frame.frame_count < self.last_count:
            self.reset()  # SITL restarted
        steer, throttle = (frame.pwm_us[i] if i < len(frame.pwm_us) else 0 for i in self._ch)
        a_cmd = actuator_command(steer, throttle, self.vessel.actuation, self.mapping)
        if self.weather is None:
            p = [0.0, 0.0]
            step = self._step_function(frame.frame_rate_hz)
            x_next = np.asarray(step(self.x, a_cmd, p)).ravel()
        else:
            open_loop, inputs, _ = self._weather_inputs(frame.frame_rate_hz)
            xs, ms = open_loop.step(
                self.x[None], np.array([a_cmd]), (0.0, 0.0), self.m[None], inputs, self._rng
            )
            x_next, self.m = xs[0], ms[0]
        self._xdot = (x_next - self.x) * frame.frame_rate_hz  # mean rate over the frame
        x_next[2] = float(ssa(x_next[2]))
        self.x = x_next
        self.time_s += 1.0 / frame.frame_rate_hz
        self.last_count = frame.frame_count
        self._last_reply = "\n" + compact_json(self.state_dict()) + "\n"
        return self._last_reply

    def state_dict(self) -> dict[str, object]:
        """The JSON reply fields (see the module docstring)."""
        x_n, y_e, psi, u, v, r = (float(a) for a in self.x[:6])
        u_dot, v_dot = float(self._xdot[3]), float(self._xdot[4])
        c, s = math.cos(psi), math.sin(psi)
        # body acceleration of a rotating frame: a = ν̇ + r × ν (Fossen 2021, §3.1)
        ax, ay = u_dot - r * v, v_dot + r * u
        if self.weather is not None:  # the first-order wave motion the sensors see
            inputs = next(iter(self._weather_steps.values()))[1][0]
            dn, de, dpsi, dr = (float(a) for a in sensed_offsets(self.x, self.m, inputs))
            x_n, y_e, psi, r = x_n + dn, y_e + de, float(ssa(psi + dpsi)), r + dr
        return {
            "timestamp": self.time_s,
            "imu": {"gyro": [0.0, 0.0, r], "accel_body": [ax, ay, -GRAVITY_MPS2]},
            "position": [x_n, y_e, 0.0],
            "velocity": [c * u - s * v, s * u + c * v, 0.0],
            "attitude": [0.0, 0.0, psi],
        }


def compact_json(state: dict[str, object]) -> str:
    """``state`` as the compact JSON SIM_JSON.cpp can scan: no spaces, no NaN (module docstring).

    Raises
    ------
    ValueError
        If a value is NaN or infinite (SIM_JSON would read garbage).
    """
    return json.dumps(state, separators=(",", ":"), allow_nan=False)


def serve(
    physics: JsonPhysics, sock: socket.socket, duration_s: float = 0.0, should_stop: object = None
) -> int:
    """Answer servo frames on ``sock`` until ``duration_s`` physics time or ``should_stop``.

    Returns the number of frames handled; malformed datagrams are skipped.
    """
    handled = 0
    sock.settimeout(0.2)
    while True:
        if should_stop is not None and should_stop.is_set():  # type: ignore[attr-defined]
            return handled
        if duration_s > 0 and physics.time_s >= duration_s:
            return handled
        try:
            data, addr = sock.recvfrom(512)
        except TimeoutError:
            continue
        try:
            frame = parse_servo_frame(data)
        except ValueError:
            continue
        sock.sendto(physics.handle(frame).encode("ascii"), addr)
        handled += 1
