"""Waypoint following with poles on the way (the reference study's Figure 4.14, "beyond").

A *course* is a polyline of waypoints W0 → W1 → … → WK with one pole on each leg. The boat
starts at W0 heading at the first pole (as in the pole task); its goal is W1, and each time it
comes within the goal radius (10 m) of its goal, the goal switches to the next waypoint. It
succeeds when it reaches WK, having reached every waypoint in order, without ever coming closer
than the safety distance (10 m) to any pole.

Course geometry (:func:`draw_course`), NED [x_N, y_E], angles clockwise from north::

    χ0 ~ U[0, 2π),  χ_{k+1} = χ_k ± U[turn range]               leg courses (sign random)
    W_{k+1} = W_k + L_k (cos χ_k, sin χ_k),  L_k ~ U[leg range]
    P_k = W_k + u_k L_k (cos χ_k, sin χ_k) + o_k (−sin χ_k, cos χ_k)
          u_k ~ U[pole fraction range], o_k ~ U[pole offset range]     the pole of leg k

A drawn course is rejected (and drawn again from the same generator) when a pole lies within
``clearance_m`` of a waypoint other than at the ends of its leg, or of another pole: each
waypoint must be reachable with the safety distance kept, and the nearest pole must be the one
that matters.

How the pole-task machinery is reused
-------------------------------------
* The plant, navigation filter, sensors and noise streams are those of
  :class:`usvsim.task.batch.PoleAvoidanceBatch`: one batch of N boats, one course each, built
  with a :class:`usvsim.task.scenario.Scenario` whose ``poles_ne`` lists every pole of every course.
  The start is an ordinary :class:`usvsim.task.scenario.EpisodeSpec` (the course's first pole, the
  start's distance and bearing from it, heading at it), so resets and noise seeding are the
  batch's own.
* The observation is the task's own (:func:`usvsim.task.observations.build_observation`, positional
  or radar, from the navigation estimate), with the *active waypoint* as the goal and the pole
  *nearest to the estimated position* as the pole — what a radar would pick out. A helmsman
  written for the pole task runs unchanged; it notices a new goal only through its observation.
  Radar clutter is not supported here (the image is rendered without a noise source).
* Each decision the batch's pole and goal arrays are set to that pole and waypoint, so the
  batch's reward terms stay meaningful; its own termination flags (single pole, single goal)
  are ignored. Goal switches, collisions with any pole, the closest approach to any pole, the
  course's time limit and success are judged here from the true trajectory the batch returns
  (every 0.1 s plant step).
* :func:`evaluate_waypoints` mirrors :func:`usvsim.evaluation.episodes.evaluate`: all courses in
  one batch, one :class:`WaypointRecord` each, with the metric names of
  :class:`usvsim.evaluation.episodes.EpisodeRecord` (``success``, ``min_pole_distance_m``,
  ``time_to_goal_s``, ``path_length_m``, ``smoothness_rad``), so the same summaries apply.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from usvsim.common.splits import check_test_draw
from usvsim.task.scenario import Scenario

__all__ = [
    "WAYPOINT_HELDOUT_SEED",
    "WAYPOINT_VALIDATION_SEED",
    "WaypointCourse",
    "WaypointScenario",
    "draw_course",
    "heldout_courses",
    "validation_courses",
]

WAYPOINT_VALIDATION_SEED = 20190414  # Figure 4.14
WAYPOINT_HELDOUT_SEED = 20190415
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class WaypointScenario:
    """Parameters of the waypoint course; goal radius, safety distance, speed, periods: ``base``."""

    n_legs: int = 3  # -, legs per course (waypoints after the start)
    leg_length_range_m: tuple[float, float] = (160.0, 220.0)  # m, L_k; the pole task's 220 m
    turn_range_rad: tuple[float, float] = (math.radians(30.0), math.radians(100.0))
    # rad, |χ_{k+1} − χ_k| at each waypoint (usvsim's choice)
    pole_fraction_range: tuple[float, float] = (0.3, 0.6)
    # -, u_k: the pole's place along its leg; 0.3 · 160 m = 48 m, near the pole task's 50-100 m
    pole_offset_range_m: tuple[float, float] = (-5.0, 5.0)  # m, o_k, across the leg
    clearance_m: float = 40.0  # m, least pole–waypoint and pole–pole distance (rejection)
    time_factor: float = 2.0  # -, time limit = factor × course length / speed (pole task: ~2)
    base: Scenario = field(default_factory=Scenario)  # goal radius, safety distance, speed, ...

    def __post_init__(self) -> None:
        if self.n_legs < 1:
            raise ValueError(f"n_legs must be ≥ 1, got {self.n_legs}")
        for name in ("leg_length_range_m", "turn_range_rad", "pole_fraction_range"):
            lo, hi = getattr(self, name)
            if not 0 <= lo <= hi:
                raise ValueError(f"{name} must satisfy 0 ≤ lo ≤ hi, got {lo, hi}")
        if not (0 < self.pole_fraction_range[0] and self.pole_fraction_range[1] < 1):
            raise ValueError("pole_fraction_range must lie inside (0, 1)")
        if self.leg_length_range_m[0] <= 2 * self.clearance_m:
            raise ValueError("legs must be longer than twice clearance_m")
        if self.time_factor <= 1:
            raise ValueError(f"time_factor must be > 1, got {self.time_factor}")


@dataclass(frozen=True)
class WaypointCourse:
    """One course: ``waypoints_ne`` (K + 1, 2) m with the start first, ``poles_ne`` (K, 2) m."""

    waypoints_ne: FloatArray
    poles_ne: FloatArray
    noise_seed: int

    @property
    def length_m(self) -> float:
        """Length of the polyline W0 → … → WK (m)."""
        return float(np.sum(np.hypot(*np.diff(self.waypoints_ne, axis=0).T)))


def _course_ok(way: FloatArray, poles: FloatArray, clearance_m: float) -> bool:
    d_wp = np.hypot(*np.moveaxis(poles[:, None] - way[None], -1, 0))  # (K, K + 1)
    d_wp[np.arange(len(poles)), np.arange(len(poles))] = np.inf  # its own leg's start ...
    d_wp[np.arange(len(poles)), np.arange(1, len(poles) + 1)] = np.inf  # ... and end
    d_pp = np.hypot(*np.moveaxis(poles[:, None] - poles[None], -1, 0))
    np.fill_diagonal(d_pp, np.inf)
    return bool(d_wp.min() >= clearance_m and d_pp.min() >= clearance_m)


def draw_course(rng: np.random.Generator, ws: WaypointScenario) -> WaypointCourse:
    """Draw one course (module docstring); rejected draws are repeated from the same ``rng``."""
    while True:
        chi = float(rng.uniform(0.0, 2.0 * math.pi))
        way, poles = [np.zeros(2)], []
        for k in range(ws.n_legs):
            if k > 0:
                chi += float(rng.choice([-1.0, 1.0]) * rng.uniform(*ws.turn_range_rad))
            length = float(rng.uniform(*ws.leg_length_range_m))
            u = np.array([math.cos(chi), math.sin(chi)])
            normal = np.array([-u[1], u[0]])
            poles.append(
                way[-1]
                + float(rng.uniform(*ws.pole_fraction_range)) * length * u
                + float(rng.uniform(*ws.pole_offset_range_m)) * normal
            )
            way.append(way[-1] + length * u)
        seed = int(rng.integers(2**63))
        if _course_ok(np.array(way), np.array(poles), ws.clearance_m):
            return WaypointCourse(np.array(way), np.array(poles), seed)


def validation_courses(
    ws: WaypointScenario | None = None, n: int = 15
) -> tuple[WaypointCourse, ...]:
    """``n`` fixed courses from ``WAYPOINT_VALIDATION_SEED``."""
    rng = np.random.default_rng(WAYPOINT_VALIDATION_SEED)
    return tuple(draw_course(rng, ws or WaypointScenario()) for _ in range(n))


def heldout_courses(ws: WaypointScenario | None = None, n: int = 200) -> tuple[WaypointCourse, ...]:
    """``n`` held-out courses from ``WAYPOINT_HELDOUT_SEED`` (a separate stream): a test split,
    refused inside :func:`usvsim.common.splits.selection_mode`."""
    check_test_draw("waypoint held-out")
    rng = np.random.default_rng(WAYPOINT_HELDOUT_SEED)
    return tuple(draw_course(rng, ws or WaypointScenario()) for _ in range(n))
