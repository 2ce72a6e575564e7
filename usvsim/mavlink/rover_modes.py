"""Position modes of ``usvsim sitl``: hold a position (LOITER), follow a mission (AUTO), RTL.

Each gives the heading and speed references of the plant's autopilot, or ``None`` for motors
off, from the true position and heading (the plant's autopilot, too, stands for an inner loop
with its own sensors):

* :class:`HoldPosition` (LOITER; GUIDED after its target timeout; the end of AUTO and RTL): a
  boat has no brakes, so while it moves faster than 0.05 m/s the hold point follows it; once it
  has come to rest (through the water; braking astern where the hull has a reversing bucket,
  :meth:`usvsim.mavlink.sitl.RoverSitl.step`), drifting outside the radius (LOIT_RADIUS) brings
  it back (:meth:`HoldPosition.references`). Rover's LOITER for boats likewise drives back to
  the loiter point once outside LOIT_RADIUS (Rover ``mode_loiter.cpp``); this is its simplest
  form. In a current it is a limit cycle, not station keeping: with the plant's idle thrust
  (5 %) the waterjet hull cannot hover (0.3 m/s across the bow: 35 m from the point within
  2 min, measured); the tests hold it to still water.
* :class:`MissionFollower` (AUTO, RTL): usvsim's LOS guidance (:class:`guidance.los.LOSGuidance`,
  proportional LOS, lookahead 20 m, no observer; Fossen 2021, §12.4.2) along
  [where the mode started, waypoint 1, ..., waypoint K] at WP_SPEED, switching at WP_RADIUS;
  towards the last waypoint the speed falls as ``0.2 m/s + 0.1 1/s · d`` (Rover's waypoint
  navigation likewise slows to stop at the destination; a boat without brakes must coast to
  it), then :class:`HoldPosition` takes over.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from guidance.los import LOSConfig, LOSGuidance
from guidance.waypoints import WaypointPath

__all__ = ["HoldPosition", "MissionFollower"]

SETTLED_SPEED_MPS = 0.05  # m/s, below this the boat counts as at rest (hold point fixed)
RETURN_SPEED_MPS = 1.0  # m/s, at most this fast back to the hold point (ASSUMED)
RETURN_GAIN = 0.2  # 1/s, return speed per metre from the hold point (ASSUMED)
LOOKAHEAD_M = 20.0  # m, LOS lookahead Δ (the los helmsman's, baselines/los.py)
APPROACH_GAIN = 0.1  # 1/s, speed per metre to the last waypoint (ASSUMED: coasts ~10 m from 1 m/s)
APPROACH_SPEED_MIN_MPS = 0.2  # m/s, the approach speed at the waypoint


class HoldPosition:
    """Stop, then stay within ``radius_m`` of where the boat came to rest (module docstring)."""

    def __init__(self, pos_ne: NDArray[np.float64]) -> None:
        self.restart(pos_ne)

    def restart(self, pos_ne: NDArray[np.float64]) -> None:
        self.point = np.asarray(pos_ne, dtype=float).copy()
        self.settled = False

    def references(
        self,
        pos_ne: NDArray[np.float64],
        psi_rad: float,
        speed_through_water_mps: float,
        radius_m: float,
    ) -> tuple[float, float] | None:
        """Heading (rad) and speed (m/s) back to the hold point, or ``None`` (motors off).

        At rest is judged through the water (a boat in a current is "at rest" while it drifts
        with it). Outside the radius the boat heads for the hold point at ``0.2 1/s · d`` (at
        most :data:`RETURN_SPEED_MPS`) when it lies within 60° of the bow, astern (speed < 0,
        heading kept) within 60° of the stern, and not at all abeam: a single waterjet turning
        at idle thrust circles ~20 m (measured) instead of returning; inside the radius the
        motors stop.
        """
        if speed_through_water_mps > SETTLED_SPEED_MPS and not self.settled:
            self.point = np.asarray(pos_ne, dtype=float).copy()
            return None
        self.settled = True
        d = self.point - pos_ne
        dist = float(np.hypot(d[0], d[1]))
        if dist <= radius_m:
            return None
        bearing = math.atan2(d[1], d[0])
        speed = min(RETURN_SPEED_MPS, RETURN_GAIN * dist)
        off_bow = math.cos(bearing - psi_rad)
        if off_bow > 0.5:  # within 60° of the bow: steer for it
            return bearing, speed
        if off_bow < -0.5:  # within 60° of the stern: back up along the bow axis (astern)
            return psi_rad, -speed
        return None  # abeam: a waterjet cannot crab; let it drift until ahead or astern


class MissionFollower:
    """LOS guidance from ``start_ne`` through ``waypoints_ne`` (K, 2) m (module docstring).

    Waypoints closer than ``switch_radius_m`` to the previous point are skipped (a segment must
    be longer than the circle of acceptance). :attr:`reached` counts the waypoints passed.

    Raises
    ------
    ValueError
        If no waypoint is farther than ``switch_radius_m`` from the start.
    """

    def __init__(
        self,
        start_ne: NDArray[np.float64],
        waypoints_ne: NDArray[np.float64],
        switch_radius_m: float,
    ) -> None:
        points = [np.asarray(start_ne, dtype=float)]
        self.index_of: list[int] = []  # waypoint number (1-based) of each kept point
        for k, wp in enumerate(np.asarray(waypoints_ne, dtype=float).reshape(-1, 2)):
            if float(np.hypot(*(wp - points[-1]))) > switch_radius_m:
                points.append(wp)
                self.index_of.append(k + 1)
        if len(points) < 2:
            raise ValueError(f"no waypoint farther than WP_RADIUS {switch_radius_m:g} m")
        config = LOSConfig(
            law="los",
            lookahead_m=LOOKAHEAD_M,
            switch_radius_m=switch_radius_m,
            observer_omega_radps=None,
        )
        self.guidance = LOSGuidance(WaypointPath.from_lists([np.array(points)]), config)
        self.last_ne = points[-1]
        self.reached = 0
        self.finished = False

    def heading(self, pos_ne: NDArray[np.float64], psi_rad: float, dt_s: float) -> float | None:
        """Heading reference (rad); ``None`` once the last waypoint is reached."""
        if self.finished:
            return None
        out = self.guidance.update(np.asarray(pos_ne)[None], np.array([psi_rad]), dt_s)
        self.reached = int(out.segment[0])
        if bool(out.finished[0]):
            self.finished = True
            self.reached = len(self.index_of)
            return None
        return float(out.psi_ref_rad[0])

    def speed(self, pos_ne: NDArray[np.float64], wp_speed_mps: float) -> float:
        """Speed reference (m/s): WP_SPEED, slowing down towards the last waypoint."""
        d = float(np.hypot(*(self.last_ne - pos_ne)))
        return min(wp_speed_mps, APPROACH_SPEED_MIN_MPS + APPROACH_GAIN * d)

    @property
    def current_waypoint(self) -> int:
        """Mission sequence number of the waypoint being steered to (1-based)."""
        return self.index_of[min(self.reached, len(self.index_of) - 1)]
