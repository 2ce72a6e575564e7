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
  :class:`usvsim.vector_env.PoleAvoidanceBatch`: one batch of N boats, one course each, built
  with a :class:`usvsim.scenario.Scenario` whose ``poles_ne`` lists every pole of every course.
  The start is an ordinary :class:`usvsim.scenario.EpisodeSpec` (the course's first pole, the
  start's distance and bearing from it, heading at it), so resets and noise seeding are the
  batch's own.
* The observation is the task's own (:func:`usvsim.observations.build_observation`, positional
  or radar, from the navigation estimate), with the *active waypoint* as the goal and the pole
  *nearest to the estimated position* as the pole — what a radar would pick out. A helmsman
  written for the pole task runs unchanged; it notices a new goal only through its observation.
  Radar clutter is not supported here (the image is rendered without a noise source).
* Each decision the batch's pole and goal arrays are set to that pole and waypoint, so the
  batch's reward terms stay meaningful; its own termination flags (single pole, single goal)
  are ignored. Goal switches, collisions with any pole, the closest approach to any pole, the
  course's time limit and success are judged here from the true trajectory the batch returns
  (every 0.1 s plant step).
* :func:`evaluate_waypoints` mirrors :func:`usvsim.evaluate.evaluate`: all courses in one batch,
  one :class:`WaypointRecord` each, with the metric names of
  :class:`usvsim.evaluate.EpisodeRecord` (``success``, ``min_pole_distance_m``,
  ``time_to_goal_s``, ``path_length_m``, ``smoothness_rad``), so the same summaries apply.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.evaluate import Helmsman
from usvsim.observations import build_observation
from usvsim.scenario import EpisodeSpec, Scenario
from usvsim.vector_env import PoleAvoidanceBatch

__all__ = [
    "WAYPOINT_HELDOUT_SEED",
    "WAYPOINT_VALIDATION_SEED",
    "WaypointCourse",
    "WaypointRecord",
    "WaypointScenario",
    "draw_course",
    "evaluate_waypoints",
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
    """``n`` held-out courses from ``WAYPOINT_HELDOUT_SEED`` (a separate stream)."""
    rng = np.random.default_rng(WAYPOINT_HELDOUT_SEED)
    return tuple(draw_course(rng, ws or WaypointScenario()) for _ in range(n))


@dataclass(frozen=True)
class WaypointRecord:
    """Outcome and trace of one course (true state unless named ``est``).

    ``goal_index`` (D,): the waypoint index that was the goal at each decision (1..K);
    ``reach_time_s`` (K,): when waypoint 1..K was first within the goal radius (NaN: never);
    ``trajectory`` (S + 1, 3): true [x_N, y_E, ψ] from the start to the course's end.
    """

    course: WaypointCourse
    success: bool
    collision: bool
    time_limit: bool
    waypoints_reached: int
    min_pole_distance_m: float  # over every pole and every plant step
    time_to_goal_s: float  # reaching the last waypoint; NaN if not reached
    path_length_m: float
    smoothness_rad: float  # Σ |Δψ_k − Δψ_{k−1}|, as in EpisodeRecord
    duration_s: float
    goal_index: NDArray[np.int64]
    reach_time_s: FloatArray
    trajectory: FloatArray
    actions_rad: FloatArray

    @property
    def outcome(self) -> str:
        """One word: success, collision, goal-unsafe (finished too close to a pole), time-limit."""
        if self.success:
            return "success"
        if self.collision:
            return "collision"
        if self.waypoints_reached == len(self.course.poles_ne):
            return "goal-unsafe"
        return "time-limit"


def _batch_setup(
    courses: Sequence[WaypointCourse], ws: WaypointScenario
) -> tuple[Scenario, list[EpisodeSpec]]:
    """The batch's scenario (every pole of every course) and one start spec per course."""
    k = ws.n_legs
    poles = np.concatenate([c.poles_ne for c in courses])
    longest = max(c.length_m for c in courses)
    base = ws.base
    limit = ws.time_factor * longest / base.speed_mps
    scenario = replace(
        base,
        poles_ne=tuple((float(x), float(y)) for x, y in poles),
        time_limit_s=base.decision_period_s * math.ceil(limit / base.decision_period_s),
        area_radius_m=1e9,  # the batch's single-pole area check is not used here
    )
    specs = []
    for i, c in enumerate(courses):
        d = c.waypoints_ne[0] - c.poles_ne[0]
        bearing = math.atan2(d[1], d[0]) % (2.0 * math.pi)
        specs.append(EpisodeSpec(i * k, float(np.hypot(*d)), bearing, 0.0, c.noise_seed))
    return scenario, specs


def evaluate_waypoints(
    helmsman: Helmsman,
    courses: Sequence[WaypointCourse],
    *,
    observation: str = "positional",
    action: str = "gaussian",
    scenario: WaypointScenario | None = None,
    **batch_kwargs: Any,
) -> list[WaypointRecord]:
    """Run ``helmsman`` on every course (all in one batch) and record each one.

    ``batch_kwargs`` go to :class:`usvsim.vector_env.PoleAvoidanceBatch` (radar, nav, plant,
    vessel, ...; not ``scenario``: the batch's scenario is built from the courses).
    """
    ws = scenario or WaypointScenario()
    n = len(courses)
    if n == 0:
        raise ValueError("evaluate_waypoints needs at least one course")
    if any(len(c.poles_ne) != ws.n_legs for c in courses):
        raise ValueError(f"every course must have {ws.n_legs} legs (WaypointScenario.n_legs)")
    sc, specs = _batch_setup(courses, ws)
    sim = PoleAvoidanceBatch(n, observation=observation, action=action, scenario=sc, **batch_kwargs)
    T, K, dt = sc.steps_per_decision, ws.n_legs, sc.dt_s
    way = np.stack([c.waypoints_ne for c in courses])  # (N, K + 1, 2)
    poles = np.stack([c.poles_ne for c in courses])  # (N, K, 2)
    limits = np.array([ws.time_factor * c.length_m / sc.speed_mps for c in courses])
    collide_m = sc.pole_radius_m + sim.plant.vessel.half_beam_m
    rows = np.arange(n)

    def observe(target: NDArray[np.int64]) -> Any:
        pos, psi = sim.estimate
        near = np.argmin(np.hypot(*np.moveaxis(poles - pos[:, None], -1, 0)), axis=1)
        sim.pole_ne[:], sim.goal_ne[:] = poles[rows, near], way[rows, target]
        return build_observation(
            observation, pos, psi, sim.pole_ne, sim.goal_ne, sc.pole_radius_m, sim.radar
        )

    sim.reset(None, specs)
    helmsman.reset(n)
    target = np.ones(n, dtype=np.int64)
    obs = observe(target)
    traj = [sim.state.eta[:, None].copy()]
    goal_hist, act_hist = [], []
    reach = np.full((n, K), np.nan)
    min_d = np.full(n, np.inf)
    end_step = np.full(n, -1, dtype=np.int64)  # plant steps up to the end; -1 while running
    collision = np.zeros(n, dtype=bool)
    for k in range(sc.max_decisions):
        running = end_step < 0
        goal_hist.append(target.copy())
        res = sim.step(helmsman.act(obs))
        act_hist.append(res.heading_change_rad)
        traj.append(res.trajectory[:, :, 0:3])
        pos = res.trajectory[:, :, 0:2]  # (N, T, 2), true
        d_pole = np.hypot(*np.moveaxis(pos[:, :, None] - poles[:, None], -1, 0)).min(axis=2)
        goal = way[rows, target]
        in_goal = np.hypot(*np.moveaxis(pos - goal[:, None], -1, 0)) <= sc.goal_radius_m
        hit = d_pole < collide_m
        first_hit = np.where(hit.any(1), np.argmax(hit, 1), T)
        first_goal = np.where(in_goal.any(1), np.argmax(in_goal, 1), T)
        reached = running & (first_goal < first_hit)
        reach[rows[reached], target[reached] - 1] = (k * T + first_goal[reached] + 1) * dt
        finished = reached & (target == K)
        crashed = running & (first_hit < T) & ~finished
        stop = np.where(finished, first_goal, np.where(crashed, first_hit, T - 1))
        upto = np.arange(T)[None] <= stop[:, None]
        min_d = np.where(running, np.minimum(min_d, np.where(upto, d_pole, np.inf).min(1)), min_d)
        collision |= crashed
        out_of_time = running & ((k + 1) * sc.decision_period_s >= limits - 1e-9)
        ended = finished | crashed | out_of_time
        end_step[ended] = k * T + stop[ended] + 1
        target = np.where(reached & (target < K), target + 1, target)
        if (end_step >= 0).all():
            break
        obs = observe(target)
    trajectory = np.concatenate(traj, axis=1)
    goals, acts = np.stack(goal_hist, axis=1), np.stack(act_hist, axis=1)
    return [
        _record(
            courses[i],
            trajectory[i, : end_step[i] + 1],
            goals[i, : math.ceil(end_step[i] / T)],
            acts[i, : math.ceil(end_step[i] / T)],
            reach[i],
            float(min_d[i]),
            bool(collision[i]),
            sc,
        )
        for i in range(n)
    ]


def _record(
    course: WaypointCourse,
    traj: FloatArray,
    goals: NDArray[np.int64],
    acts: FloatArray,
    reach: FloatArray,
    min_d: float,
    collision: bool,
    sc: Scenario,
) -> WaypointRecord:
    n_reached = int(np.sum(np.isfinite(reach)))
    done = n_reached == len(reach)
    return WaypointRecord(
        course=course,
        success=done and not collision and min_d >= sc.safety_distance_m,
        collision=collision,
        time_limit=not done and not collision,
        waypoints_reached=n_reached,
        min_pole_distance_m=min_d,
        time_to_goal_s=float(reach[-1]) if done else math.nan,
        path_length_m=float(np.sum(np.hypot(*np.diff(traj[:, :2], axis=0).T))),
        smoothness_rad=float(np.sum(np.abs(np.diff(acts)))),
        duration_s=(len(traj) - 1) * sc.dt_s,
        goal_index=goals.astype(np.int64),
        reach_time_s=reach.copy(),
        trajectory=traj.copy(),
        actions_rad=acts.copy(),
    )
