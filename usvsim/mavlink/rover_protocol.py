"""The parameter and mission protocols of ``usvsim sitl``, as ArduPilot Rover answers them.

Both are small state machines that read typed messages (:mod:`usvsim.mavlink.messages`) and
answer through a :class:`usvsim.mavlink.link.MavlinkLink`; :class:`usvsim.mavlink.sitl.RoverSitl`
feeds them and reads their state.

Parameters (MAVLink parameter protocol; what MAVProxy's ``param fetch`` / ``param set`` do):
``PARAM_REQUEST_LIST`` → every parameter as ``PARAM_VALUE`` (index, count); ``PARAM_REQUEST_READ``
by name or index → one ``PARAM_VALUE``; ``PARAM_SET`` of a known name with a value in range →
the new value in ``PARAM_VALUE`` (out of range: the old value, as a refusal; unknown names are
ignored, as ArduPilot does). Values are float32 on the wire.

Missions (MAVLink mission protocol, ``mission_type`` 0; fence and rally lists are empty):
upload ``MISSION_COUNT`` → ``MISSION_REQUEST_INT`` 0..n−1 → ``MISSION_ITEM_INT`` each →
``MISSION_ACK``; download ``MISSION_REQUEST_LIST`` → ``MISSION_COUNT`` → ``MISSION_REQUEST(_INT)``
→ ``MISSION_ITEM(_INT)``; ``MISSION_CLEAR_ALL`` → ``MISSION_ACK``. As in ArduPilot, item 0 is
home (set to the start position at boot) and the navigation items follow.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import (
    MAV_CMD_NAV_WAYPOINT,
    MAV_MISSION_ACCEPTED,
    MAV_MISSION_ERROR,
    MissionAck,
    MissionClearAll,
    MissionCount,
    MissionItem,
    MissionRequest,
    MissionRequestList,
    ParamRequestList,
    ParamRequestRead,
    ParamSet,
    ParamValue,
)
from usvsim.vessel.autopilot import AutopilotConfig

__all__ = ["ATC_FIELDS", "MissionStore", "Parameter", "RoverParameters", "sitl_parameters"]


@dataclass(frozen=True)
class Parameter:
    """One modelled parameter: value and the range a PARAM_SET may give it."""

    name: str
    value: float
    low: float
    high: float
    doc: str  # unit and effect in usvsim sitl


def sitl_parameters(
    system_id: int,
    wp_speed_mps: float,
    wp_radius_m: float,
    loiter_radius_m: float,
    speedup: float,
    ap: AutopilotConfig,
) -> list[Parameter]:
    """The parameters ``usvsim sitl`` models (names and units as ArduPilot Rover's).

    The ATC_STR_* gains are the rover cascade's (:data:`ATC_FIELDS`); with the ``pid``
    autopilot they are stored but steer nothing.
    """
    deg = math.degrees
    return [
        Parameter("SYSID_THISMAV", system_id, system_id, system_id, "read only"),
        Parameter("FRAME_CLASS", 2, 2, 2, "2 = boat, read only"),
        Parameter("WP_SPEED", wp_speed_mps, 0.0, 30.0, "m/s, GUIDED/AUTO speed limit"),
        Parameter("CRUISE_SPEED", wp_speed_mps, 0.0, 30.0, "m/s, stored"),
        Parameter("WP_RADIUS", wp_radius_m, 0.1, 1000.0, "m, AUTO waypoint switch"),
        Parameter("LOIT_RADIUS", loiter_radius_m, 0.1, 1000.0, "m, LOITER radius"),
        Parameter("FS_ACTION", 2, 0, 6, "stored (Rover: 0 none, 1 RTL, 2 HOLD, ...)"),
        Parameter("ARMING_CHECK", 1, 0, 1, "stored"),
        Parameter("ATC_STR_ANG_P", ap.rover_ang_p, 1e-3, 10.0, "1/s, rover autopilot"),
        Parameter("ATC_STR_RAT_FF", ap.rover_rate_ff, 1e-3, 100.0, "s/rad, rover autopilot"),
        Parameter("ATC_STR_RAT_P", ap.rover_rate_p, 1e-3, 100.0, "s/rad, rover autopilot"),
        Parameter("ATC_STR_RAT_I", ap.rover_rate_i, 1e-3, 100.0, "1/rad, rover autopilot"),
        Parameter("ATC_STR_RAT_IMAX", ap.rover_rate_imax, 1e-3, 1.0, "-, rover autopilot"),
        Parameter("ATC_STR_RAT_MAX", deg(ap.rover_rate_max), 1.0, 1000.0, "deg/s, rover"),
        Parameter("ATC_STR_ACC_MAX", deg(ap.rover_acc_max), 1.0, 1000.0, "deg/s², rover"),
        Parameter("SIM_SPEEDUP", speedup, speedup, speedup, "read only"),
    ]


# parameters that change the rover cascade's gains (AutopilotConfig field, factor to SI)
ATC_FIELDS = {
    "ATC_STR_ANG_P": ("rover_ang_p", 1.0),
    "ATC_STR_RAT_FF": ("rover_rate_ff", 1.0),
    "ATC_STR_RAT_P": ("rover_rate_p", 1.0),
    "ATC_STR_RAT_I": ("rover_rate_i", 1.0),
    "ATC_STR_RAT_IMAX": ("rover_rate_imax", 1.0),
    "ATC_STR_RAT_MAX": ("rover_rate_max", math.pi / 180.0),
    "ATC_STR_ACC_MAX": ("rover_acc_max", math.pi / 180.0),
}


class RoverParameters:
    """The parameter table and its protocol (module docstring).

    ``on_change(name, value)`` is called after an accepted PARAM_SET.
    """

    def __init__(
        self, params: list[Parameter], on_change: Callable[[str, float], None] | None = None
    ) -> None:
        self._params = {p.name: p for p in params}
        self._order = [p.name for p in params]
        self._on_change = on_change

    def __getitem__(self, name: str) -> float:
        return self._params[name].value

    @property
    def names(self) -> list[str]:
        return list(self._order)

    def set(self, name: str, value: float) -> bool:
        """Set ``name`` if ``value`` is finite and in range; True when accepted."""
        p = self._params[name]
        if not (math.isfinite(value) and p.low <= value <= p.high):
            return False
        self._params[name] = replace(p, value=float(value))
        if self._on_change is not None:
            self._on_change(name, float(value))
        return True

    def _value(self, name: str) -> ParamValue:
        return ParamValue(name, self._params[name].value, self._order.index(name), len(self._order))

    def handle(self, msg: object, link: MavlinkLink) -> bool:
        """Answer a parameter message; False if ``msg`` is not one."""
        if isinstance(msg, ParamRequestList):
            for name in self._order:
                link.send_param_value(self._value(name))
        elif isinstance(msg, ParamRequestRead):
            if 0 <= msg.index < len(self._order):
                link.send_param_value(self._value(self._order[msg.index]))
            elif msg.name in self._params:
                link.send_param_value(self._value(msg.name))
        elif isinstance(msg, ParamSet):
            if msg.name in self._params:
                self.set(msg.name, msg.value)
                link.send_param_value(self._value(msg.name))
        else:
            return False
        return True


class MissionStore:
    """The vehicle's mission and its upload/download protocol (module docstring).

    ``home`` is item 0. :attr:`version` counts changes (upload or clear).
    """

    def __init__(self, home_lat_deg: float, home_lon_deg: float) -> None:
        self.home = MissionItem(0, 0, MAV_CMD_NAV_WAYPOINT, home_lat_deg, home_lon_deg, 0.0)
        self.items: list[MissionItem] = [self.home]
        self.version = 0
        self._incoming: list[MissionItem | None] | None = None  # an upload in progress
        self._upload_from = 0  # GCS system id of the upload

    def waypoints(self) -> list[tuple[float, float]]:
        """(lat, lon) in deg of the NAV_WAYPOINT items after home, in order."""
        return [
            (it.lat_deg, it.lon_deg) for it in self.items[1:] if it.command == MAV_CMD_NAV_WAYPOINT
        ]

    def handle(self, msg: object, src_system: int, link: MavlinkLink) -> bool:
        """Answer a mission message from ``src_system``; False if ``msg`` is not one."""
        if isinstance(msg, (MissionCount, MissionRequestList, MissionClearAll)) and (
            msg.mission_type != 0
        ):
            # fence (1) and rally (2) lists: always empty here
            if isinstance(msg, MissionRequestList):
                link.send_mission_count(src_system, 0, msg.mission_type)
            else:
                result = MAV_MISSION_ACCEPTED if isinstance(msg, MissionClearAll) else 1
                link.send_mission_ack(src_system, result, msg.mission_type)
            return True
        if isinstance(msg, MissionCount):
            self._upload_start(msg, src_system, link)
        elif isinstance(msg, MissionItem):
            self._upload_item(msg, src_system, link)
        elif isinstance(msg, MissionRequestList):
            link.send_mission_count(src_system, len(self.items))
        elif isinstance(msg, MissionRequest):
            if msg.mission_type == 0 and 0 <= msg.seq < len(self.items):
                item = replace(self.items[msg.seq], target_system=src_system, seq=msg.seq)
                link.send_mission_item(item, src_system, msg.is_int)
        elif isinstance(msg, MissionClearAll):
            self.items = [self.home]
            self.version += 1
            link.send_mission_ack(src_system, MAV_MISSION_ACCEPTED)
        elif isinstance(msg, MissionAck):
            pass  # the end of a download: nothing to do
        else:
            return False
        return True

    def _upload_start(self, msg: MissionCount, src: int, link: MavlinkLink) -> None:
        if msg.count == 0:
            self.items = [self.home]
            self.version += 1
            link.send_mission_ack(src, MAV_MISSION_ACCEPTED)
            return
        self._incoming = [None] * msg.count
        self._upload_from = src
        link.send_mission_request(src, 0)

    def _upload_item(self, item: MissionItem, src: int, link: MavlinkLink) -> None:
        incoming = self._incoming
        if incoming is None or src != self._upload_from or item.mission_type != 0:
            return
        if not 0 <= item.seq < len(incoming) or not (
            math.isfinite(item.lat_deg) and math.isfinite(item.lon_deg)
        ):
            self._incoming = None
            link.send_mission_ack(src, MAV_MISSION_ERROR)
            return
        incoming[item.seq] = item
        missing = [k for k, it in enumerate(incoming) if it is None]
        if missing:
            link.send_mission_request(src, missing[0])
            return
        uploaded = [it for it in incoming if it is not None]
        self.items = [self.home, *uploaded[1:]]  # item 0 is home; the vehicle keeps its own
        self.version += 1
        self._incoming = None
        link.send_mission_ack(src, MAV_MISSION_ACCEPTED)
