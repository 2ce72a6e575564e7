"""Judging helmsmen on waypoint courses: :func:`evaluate_waypoints` and :class:`WaypointRecord`.

The courses and their geometry are :mod:`usvsim.task.waypoints`; this module runs every course of
a set in one batch and mirrors :func:`usvsim.evaluation.episodes.evaluate` (see the task module's
docstring, "How the pole-task machinery is reused").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.helm.protocol import Helmsman
from usvsim.task.batch import ActionKind, PoleAvoidanceBatch
from usvsim.task.observations import ObservationKind, build_observation
from usvsim.task.scenario import EpisodeSpec, Scenario
from usvsim.task.waypoints import WaypointCourse, WaypointScenario

__all__ = ["WaypointRecord", "evaluate_waypoints"]

FloatArray = NDArray[np.float64]


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
    observation: ObservationKind = "positional",
    action: ActionKind = "gaussian",
    scenario: WaypointScenario | None = None,
    **batch_kwargs: Any,
) -> list[WaypointRecord]:
    """Run ``helmsman`` on every course (all in one batch) and record each one.

    ``batch_kwargs`` go to :class:`usvsim.task.batch.PoleAvoidanceBatch` (radar, nav, plant,
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
            observation, pos, psi, sim.pole_ne, sim.goal_ne, sc.pole_radius_m, sim.radar,
            velocity_ne=sim.estimated_velocity,
        )  # fmt: skip

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
