"""Typed MAVLink 2 messages and constants: the vocabulary of :mod:`usvsim.mavlink.link`.

Plain frozen dataclasses in SI units (angles in rad, speeds in m/s, positions in deg), one per
message type this project uses, and the enum values it needs from MAVLink ``common.xml`` and
ArduPilot Rover (``Rover/mode.h``). Pure Python: the bridge, the SITL and the demonstration
importer build and read these without pymavlink; :class:`usvsim.mavlink.link.MavlinkLink`
encodes and decodes them.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

__all__ = [
    "ATTITUDE_MASK_YAW_THRUST",
    "EKF",
    "EKF_NEEDED_FOR_ARMING",
    "MAV_AUTOPILOT_ARDUPILOTMEGA",
    "MAV_AUTOPILOT_INVALID",
    "MAV_CMD_NAV_WAYPOINT",
    "MAV_FRAME_GLOBAL_RELATIVE_ALT_INT",
    "MAV_FRAME_LOCAL_NED",
    "MAV_MISSION_ACCEPTED",
    "MAV_MISSION_ERROR",
    "MAV_MODE_FLAG_CUSTOM_MODE_ENABLED",
    "MAV_MODE_FLAG_GUIDED_ENABLED",
    "MAV_MODE_FLAG_SAFETY_ARMED",
    "MAV_RESULT_ACCEPTED",
    "MAV_RESULT_DENIED",
    "MAV_RESULT_FAILED",
    "MAV_RESULT_UNSUPPORTED",
    "MAV_SEVERITY_INFO",
    "MAV_SEVERITY_WARNING",
    "MAV_STATE_ACTIVE",
    "MAV_STATE_STANDBY",
    "MAV_TYPE_GCS",
    "MAV_TYPE_GROUND_ROVER",
    "MAV_TYPE_SURFACE_BOAT",
    "TYPE_MASK_VELOCITY_YAW",
    "Attitude",
    "AutopilotVersion",
    "CommandAck",
    "CommandLong",
    "EkfStatus",
    "GlobalPosition",
    "GpsRaw",
    "Heartbeat",
    "MavCommand",
    "Message",
    "MissionAck",
    "MissionClearAll",
    "MissionCount",
    "MissionCurrent",
    "MissionItem",
    "MissionRequest",
    "MissionRequestList",
    "ParamRequestList",
    "ParamRequestRead",
    "ParamSet",
    "ParamValue",
    "Received",
    "RoverMode",
    "SetAttitudeTarget",
    "SetMode",
    "SetPositionTarget",
    "StatusText",
    "SysStatus",
    "SysStatusSensor",
    "VfrHud",
]

# POSITION_TARGET_TYPEMASK bits (MAVLink common.xml): 1 x, 2 y, 4 z, 8 vx, 16 vy, 32 vz,
# 64 ax, 128 ay, 256 az, 512 force, 1024 yaw, 2048 yaw rate.
_POS_IGNORE = 1 | 2 | 4
_VZ_IGNORE = 32
_ACC_IGNORE = 64 | 128 | 256
_YAW_IGNORE = 1024
_YAW_RATE_IGNORE = 2048
TYPE_MASK_VELOCITY_YAW = _POS_IGNORE | _VZ_IGNORE | _ACC_IGNORE | _YAW_RATE_IGNORE  # 2535
# ATTITUDE_TARGET_TYPEMASK bits: 1 roll rate, 2 pitch rate, 4 yaw rate, 64 throttle, 128 attitude
ATTITUDE_MASK_YAW_THRUST = 1 | 2 | 4

# Enum values of MAVLink common.xml (tests/test_mavlink_link.py checks them against pymavlink).
MAV_TYPE_GCS = 6
MAV_TYPE_GROUND_ROVER = 10
MAV_TYPE_SURFACE_BOAT = 11
MAV_AUTOPILOT_ARDUPILOTMEGA = 3
MAV_AUTOPILOT_INVALID = 8
MAV_STATE_STANDBY = 3
MAV_STATE_ACTIVE = 4
MAV_RESULT_ACCEPTED = 0
MAV_RESULT_DENIED = 2
MAV_RESULT_UNSUPPORTED = 3
MAV_RESULT_FAILED = 4
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
MAV_MODE_FLAG_GUIDED_ENABLED = 8
MAV_MODE_FLAG_SAFETY_ARMED = 128
MAV_FRAME_LOCAL_NED = 1
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT = 6
MAV_SEVERITY_WARNING = 4
MAV_SEVERITY_INFO = 6
MAV_CMD_NAV_WAYPOINT = 16  # a mission item's command, not a COMMAND_LONG
MAV_MISSION_ACCEPTED = 0
MAV_MISSION_ERROR = 1
MAV_MISSION_TYPE_MISSION = 0


class SysStatusSensor(enum.IntFlag):
    """MAV_SYS_STATUS_SENSOR bits of SYS_STATUS ``onboard_control_sensors_*`` (common.xml)."""

    GYRO = 0x01
    ACCEL = 0x02
    MAG = 0x04
    GPS = 0x20
    MOTOR_OUTPUTS = 0x8000
    GEOFENCE = 0x100000
    AHRS = 0x200000
    PREARM_CHECK = 0x10000000


class EKF(enum.IntFlag):
    """EKF_STATUS_FLAGS of EKF_STATUS_REPORT (ardupilotmega.xml)."""

    ATTITUDE = 1
    VELOCITY_HORIZ = 2
    VELOCITY_VERT = 4
    POS_HORIZ_REL = 8
    POS_HORIZ_ABS = 16
    POS_VERT_ABS = 32
    PRED_POS_HORIZ_REL = 256
    PRED_POS_HORIZ_ABS = 512


# what a boat needs before it may arm in GUIDED: attitude, horizontal velocity and an absolute
# horizontal position (Rover refuses to arm without a position estimate)
EKF_NEEDED_FOR_ARMING = EKF.ATTITUDE | EKF.VELOCITY_HORIZ | EKF.POS_HORIZ_ABS


class RoverMode(enum.IntEnum):
    """ArduPilot Rover custom modes (``Rover/mode.h``)."""

    MANUAL = 0
    ACRO = 1
    STEERING = 3
    HOLD = 4
    LOITER = 5
    FOLLOW = 6
    SIMPLE = 7
    AUTO = 10
    RTL = 11
    SMART_RTL = 12
    GUIDED = 15
    INITIALISING = 16


class MavCommand(enum.IntEnum):
    """The MAV_CMD values used here (MAVLink common.xml)."""

    DO_SET_MODE = 176
    COMPONENT_ARM_DISARM = 400
    SET_MESSAGE_INTERVAL = 511
    REQUEST_MESSAGE = 512
    REQUEST_AUTOPILOT_CAPABILITIES = 520
    SET_MODE_MESSAGE = 11  # the SET_MODE message id: ArduPilot acks SET_MODE with it


@dataclass(frozen=True)
class Heartbeat:
    """HEARTBEAT: vehicle type, autopilot, modes and status."""

    type: int
    autopilot: int
    base_mode: int
    custom_mode: int
    system_status: int

    @property
    def armed(self) -> bool:
        return bool(self.base_mode & MAV_MODE_FLAG_SAFETY_ARMED)

    @property
    def is_boat_or_rover(self) -> bool:
        return self.type in (MAV_TYPE_SURFACE_BOAT, MAV_TYPE_GROUND_ROVER)


@dataclass(frozen=True)
class GlobalPosition:
    """GLOBAL_POSITION_INT: fused position (deg), NED ground velocity (m/s), heading (rad)."""

    time_boot_ms: int
    lat_deg: float
    lon_deg: float
    vn_mps: float
    ve_mps: float
    heading_rad: float  # NaN when the vehicle reports it unknown (UINT16_MAX)


@dataclass(frozen=True)
class Attitude:
    """ATTITUDE: Euler angles (rad) and rates (rad/s)."""

    time_boot_ms: int
    roll_rad: float
    pitch_rad: float
    yaw_rad: float
    yaw_rate_radps: float


@dataclass(frozen=True)
class VfrHud:
    groundspeed_mps: float
    heading_deg: int
    throttle_pct: int


@dataclass(frozen=True)
class GpsRaw:
    time_usec: int
    fix_type: int
    lat_deg: float
    lon_deg: float
    satellites: int


@dataclass(frozen=True)
class SysStatus:
    """SYS_STATUS: battery voltage and the MAV_SYS_STATUS_SENSOR bit sets."""

    voltage_v: float
    present: int = 0
    enabled: int = 0
    health: int = 0

    @property
    def prearm_ok(self) -> bool | None:
        """The pre-arm bit's health; ``None`` when the vehicle does not report it."""
        if not self.present & SysStatusSensor.PREARM_CHECK:
            return None
        return bool(self.health & SysStatusSensor.PREARM_CHECK)


@dataclass(frozen=True)
class EkfStatus:
    """EKF_STATUS_REPORT: the estimator's solution flags (:class:`EKF`)."""

    flags: int

    @property
    def ready_to_arm(self) -> bool:
        return self.flags & EKF_NEEDED_FOR_ARMING == EKF_NEEDED_FOR_ARMING


@dataclass(frozen=True)
class StatusText:
    severity: int
    text: str


@dataclass(frozen=True)
class CommandAck:
    command: int
    result: int
    target_system: int = 0
    target_component: int = 0


@dataclass(frozen=True)
class AutopilotVersion:
    """AUTOPILOT_VERSION: capability bits and the firmware version (``0xMMmmpptt``)."""

    capabilities: int
    flight_sw_version: int


@dataclass(frozen=True)
class ParamValue:
    """PARAM_VALUE: one parameter (name ≤ 16 characters, value as float32)."""

    name: str
    value: float
    index: int
    count: int


@dataclass(frozen=True)
class ParamRequestList:
    target_system: int


@dataclass(frozen=True)
class ParamRequestRead:
    """PARAM_REQUEST_READ: by ``name``, or by ``index`` when it is >= 0."""

    target_system: int
    name: str
    index: int


@dataclass(frozen=True)
class ParamSet:
    target_system: int
    name: str
    value: float


@dataclass(frozen=True)
class MissionCount:
    target_system: int
    count: int
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionRequestList:
    target_system: int
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionRequest:
    """MISSION_REQUEST_INT (``is_int``) or the older MISSION_REQUEST for item ``seq``."""

    target_system: int
    seq: int
    is_int: bool = True
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionItem:
    """MISSION_ITEM_INT (or MISSION_ITEM): one mission item; position in deg and m."""

    target_system: int
    seq: int
    command: int
    lat_deg: float
    lon_deg: float
    alt_m: float = 0.0
    frame: int = MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    params: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    current: int = 0
    autocontinue: int = 1
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionAck:
    target_system: int
    result: int
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionClearAll:
    target_system: int
    mission_type: int = MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionCurrent:
    seq: int


@dataclass(frozen=True)
class CommandLong:
    target_system: int
    target_component: int
    command: int
    params: tuple[float, float, float, float, float, float, float]


@dataclass(frozen=True)
class SetMode:
    target_system: int
    base_mode: int
    custom_mode: int


@dataclass(frozen=True)
class SetPositionTarget:
    """SET_POSITION_TARGET_LOCAL_NED or _GLOBAL_INT (``frame`` tells which); SI units."""

    target_system: int
    frame: int
    type_mask: int
    vx_mps: float
    vy_mps: float
    yaw_rad: float
    yaw_rate_radps: float
    is_global: bool

    @property
    def uses_velocity_and_yaw(self) -> bool:
        """Position and yaw rate ignored, velocity and yaw used (Rover: heading + speed)."""
        m = self.type_mask
        return bool(
            m & _POS_IGNORE == _POS_IGNORE
            and not m & (8 | 16)
            and m & _ACC_IGNORE == _ACC_IGNORE
            and not m & _YAW_IGNORE
            and m & _YAW_RATE_IGNORE
        )


@dataclass(frozen=True)
class SetAttitudeTarget:
    target_system: int
    type_mask: int
    q: tuple[float, float, float, float]
    thrust: float
    body_yaw_rate_radps: float

    @property
    def yaw_rad(self) -> float:
        """Yaw of the quaternion [w, x, y, z] (ZYX Euler)."""
        w, x, y, z = self.q
        return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


Message = (
    Heartbeat
    | GlobalPosition
    | Attitude
    | VfrHud
    | GpsRaw
    | SysStatus
    | EkfStatus
    | StatusText
    | CommandAck
    | CommandLong
    | SetMode
    | SetPositionTarget
    | SetAttitudeTarget
    | AutopilotVersion
    | ParamValue
    | ParamRequestList
    | ParamRequestRead
    | ParamSet
    | MissionCount
    | MissionRequestList
    | MissionRequest
    | MissionItem
    | MissionAck
    | MissionClearAll
    | MissionCurrent
)


@dataclass(frozen=True)
class Received:
    """One decoded packet and who sent it."""

    src_system: int
    src_component: int
    message: Message
