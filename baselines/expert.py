"""A stochastic, human-like expert helmsman: the stand-in for the study's manual demonstrations.

The study's expert (Vedeler 2019, Sect. 3.5; ``shared/reference/table-4-1.md``) drove a 10.5 m
waterjet USV at a pole 46 times: *steer at the pole, make a decisive turn to the left or the
right, then go back to the original course*. No such recordings ship, so this module models
that person. Each run draws its own traits (:class:`ExpertTraits`), and the helmsman then acts
on what it perceives, late and imperfectly:

==================  ============================================================================
phase               commanded heading ψ_cmd (absolute, rad; NED, clockwise from north)
==================  ============================================================================
0 approach          the bearing to the pole (the study: "steer at the pole")
1 avoid             bearing to the pole + side · (asin(min(1, c / r)) + margin): the tangent
                    that passes the pole at the planned clearance c (a collision cone kept
                    clear), entered when the range r falls below the run's turn distance
2 return            line-of-sight guidance back onto the original start→goal line with a
                    lookahead Δ (Fossen 2021, Sect. 12.4), entered once the boat is the run's
                    "back-to-course" distance past the pole along the original course
==================  ============================================================================

Human imperfections (all drawn per run from :class:`ExpertParams`):

* reaction delay — the helmsman acts on the scene as it was ``reaction_delay_s`` ago;
* imperfect timing — turn distance, clearance, back-to-course point and lookahead vary;
* a side preference — starboard with probability ``p_starboard`` (COLREG habit), else port;
* an unsteady hand — an Ornstein-Uhlenbeck wobble (σ, τ) on the commanded heading, which the
  helmsman swings at most ``max_turn_rate_radps`` (a smooth hand on the wheel);
* perception noise — bearing noise on every look;
* occasional lapses — with probability ``p_late_turn`` the turn starts far too late (these runs
  pass close to the pole and the quality filter of :mod:`learning.imitation.demonstrations`
  rejects them).

The helmsman looks at the true pose (a person sees the pole and the water, not a filter
estimate); the run itself is the real simulator (:class:`usvsim.task.batch.PoleAvoidanceBatch`,
plant, autopilot and navigation filter) with the heading reference updated every
``tick_s`` = 0.2 s instead of every 2 s. :func:`run_expert` runs N such episodes in one batch.

A run ends when the boat is within ``finish_radius_m`` of the goal, when the goal falls abaft
the beam within ``goal_radius_m`` (missed, but there), or at the scenario's time limit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.batch import PoleAvoidanceBatch
from usvsim.task.scenario import EpisodeSpec, Scenario, episode_geometry

__all__ = [
    "ExpertParams",
    "ExpertRun",
    "ExpertTraits",
    "HumanExpert",
    "draw_traits",
    "run_expert",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ExpertParams:
    """Distributions of the expert's per-run traits (usvsim's model; the study gives none)."""

    tick_s: float = 0.2  # s, how often the helmsman adjusts the heading (5 Hz)
    reaction_delay_range_s: tuple[float, float] = (0.4, 1.0)
    # s, uniform; simple visual reaction time is ~0.2-0.3 s, steering decisions longer
    # m, range to pole at the turn. On the coupled default hull (usv105, which turns wider and
    # drifts) (35, 52) m took the careful expert within 10 m of the pole in 14 of the 200
    # held-out episodes; (45, 60) m: none, closest 14.1 m (median 19.9 m)
    turn_distance_range_m: tuple[float, float] = (45.0, 60.0)
    clearance_range_m: tuple[float, float] = (16.0, 24.0)  # m, planned passing distance
    margin_rad: float = math.radians(4.0)  # rad, extra angle off the tangent
    back_to_course_range_m: tuple[float, float] = (0.0, 12.0)
    # m, how far past the pole (along the original course) the helmsman heads back to it
    lookahead_range_m: tuple[float, float] = (25.0, 45.0)  # m, LOS lookahead Δ when returning
    p_starboard: float = 0.6  # probability of turning to starboard (COLREG habit)
    wobble_sigma_rad: float = math.radians(2.0)  # rad, stationary σ of the OU heading wobble
    wobble_tau_s: float = 4.0  # s, OU correlation time
    bearing_noise_rad: float = math.radians(1.5)  # rad, 1σ perception noise on bearings
    p_late_turn: float = 0.12  # probability of a lapse: turn far too late
    late_turn_distance_range_m: tuple[float, float] = (17.0, 22.0)  # m, a lapse's turn distance
    late_clearance_range_m: tuple[float, float] = (7.0, 10.0)  # m, a lapse's clearance
    finish_radius_m: float = 3.0  # m, the run ends this close to the goal
    # rad, how far ψ_ref may lead ψ̂. With 30° the boat, once behind its command, turned at the
    # autopilot's rate limit with overshoot (16.7 °/s, 33° in 2 s on usv105: more than the task's
    # action bound, so the quality filter rejected 43 of 46 runs); with 10°: 7 of 46
    max_change_per_tick_rad: float = math.radians(10.0)
    max_turn_rate_radps: float = math.radians(11.0)
    # rad/s, how fast the helmsman swings the commanded heading (a smooth hand on the wheel;
    # keeps every 2 s heading change inside the task's ±30° action bound)


@dataclass(frozen=True)
class ExpertTraits:
    """One run's draws (N,) arrays; ``side`` +1 starboard (clockwise), -1 port."""

    side: FloatArray
    reaction_delay_s: FloatArray
    turn_distance_m: FloatArray
    clearance_m: FloatArray
    back_to_course_m: FloatArray
    lookahead_m: FloatArray
    late_turn: NDArray[np.bool_]

    def row(self, i: int) -> dict[str, float | bool]:
        """Run ``i``'s traits as plain numbers (for metadata files)."""
        return {
            f.name: (bool if f.name == "late_turn" else float)(getattr(self, f.name)[i])
            for f in dataclasses.fields(self)
        }


def draw_traits(rng: np.random.Generator, n: int, p: ExpertParams) -> ExpertTraits:
    """Draw the traits of ``n`` runs (module docstring)."""
    late = rng.random(n) < p.p_late_turn
    turn = np.where(
        late,
        rng.uniform(*p.late_turn_distance_range_m, n),
        rng.uniform(*p.turn_distance_range_m, n),
    )
    clear = np.where(
        late, rng.uniform(*p.late_clearance_range_m, n), rng.uniform(*p.clearance_range_m, n)
    )
    return ExpertTraits(
        side=np.where(rng.random(n) < p.p_starboard, 1.0, -1.0),
        reaction_delay_s=rng.uniform(*p.reaction_delay_range_s, n),
        turn_distance_m=turn,
        clearance_m=clear,
        back_to_course_m=rng.uniform(*p.back_to_course_range_m, n),
        lookahead_m=rng.uniform(*p.lookahead_range_m, n),
        late_turn=late,
    )


class HumanExpert:
    """The expert's decision rule for N boats (phases and imperfections: module docstring).

    ``command(pos_ne, psi)`` is called every ``tick_s`` with the TRUE poses (N, 2), (N,) and
    returns the commanded absolute heading (N,) rad. Perception is delayed by whole ticks.
    """

    def __init__(
        self,
        traits: ExpertTraits,
        pole_ne: FloatArray,
        start_ne: FloatArray,
        goal_ne: FloatArray,
        params: ExpertParams,
        rng: np.random.Generator,
    ) -> None:
        self.traits, self.p, self.rng = traits, params, rng
        self.pole_ne, self.start_ne, self.goal_ne = pole_ne, start_ne, goal_ne
        n = pole_ne.shape[0]
        self.phase = np.zeros(n, dtype=np.int64)
        self._delay_ticks = np.maximum(0, np.round(traits.reaction_delay_s / params.tick_s)).astype(
            np.int64
        )
        self._history: list[FloatArray] = []  # perceived poses [x_N, y_E, ψ] (N, 3) per tick
        self._wobble = rng.normal(0.0, params.wobble_sigma_rad, n)
        self._cmd: FloatArray | None = None  # last commanded heading (N,) rad
        line = goal_ne - start_ne
        self._line_dir = line / np.linalg.norm(line, axis=1, keepdims=True)

    def _perceived(self, pos_ne: FloatArray, psi: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Pose as it was ``delay`` ticks ago (the first pose before enough history exists)."""
        self._history.append(np.column_stack([pos_ne, psi]))
        lag = np.minimum(self._delay_ticks, len(self._history) - 1)
        window = np.stack(self._history[-1 - int(lag.max()) :])  # (L, N, 3), oldest first
        seen = window[window.shape[0] - 1 - lag, np.arange(pos_ne.shape[0])]
        del self._history[: -1 - int(self._delay_ticks.max())]  # keep what a delay can reach
        return seen[:, :2], seen[:, 2]

    def command(self, pos_ne: FloatArray, psi: FloatArray) -> FloatArray:
        """Commanded absolute heading (N,) rad after one more tick (see the class docstring)."""
        p, tr = self.p, self.traits
        pos, _ = self._perceived(pos_ne, psi)
        n = pos.shape[0]
        d = self.pole_ne - pos
        r_pole = np.hypot(d[:, 0], d[:, 1])
        brg_pole = np.arctan2(d[:, 1], d[:, 0]) + self.rng.normal(0.0, p.bearing_noise_rad, n)
        self.phase = np.where((self.phase == 0) & (r_pole <= tr.turn_distance_m), 1, self.phase)
        # along-track distance past the pole on the original course (start→goal line)
        along = np.sum((pos - self.start_ne) * self._line_dir, axis=1)
        past_pole = along - np.sum((self.pole_ne - self.start_ne) * self._line_dir, axis=1)
        self.phase = np.where((self.phase == 1) & (past_pole >= tr.back_to_course_m), 2, self.phase)
        # tangent of the circle of radius c around the pole, on the run's side
        avoid = brg_pole + tr.side * (
            np.arcsin(np.minimum(1.0, tr.clearance_m / np.maximum(r_pole, 1e-6))) + p.margin_rad
        )
        # LOS onto the start→goal line: the point Δ ahead of the boat's projection on it
        target = self.start_ne + (along + tr.lookahead_m)[:, None] * self._line_dir
        los = np.arctan2(target[:, 1] - pos[:, 1], target[:, 0] - pos[:, 0])
        cmd = np.select([self.phase == 0, self.phase == 1], [brg_pole, avoid], los)
        # Ornstein-Uhlenbeck wobble, exact discretisation (Gillespie 1996)
        a = math.exp(-p.tick_s / p.wobble_tau_s)
        self._wobble = a * self._wobble + math.sqrt(1 - a * a) * self.rng.normal(
            0.0, p.wobble_sigma_rad, n
        )
        target = cmd + self._wobble
        if self._cmd is None:
            self._cmd = psi.copy()
        step = p.max_turn_rate_radps * p.tick_s
        self._cmd = np.asarray(ssa(self._cmd + np.clip(ssa(target - self._cmd), -step, step)))
        return self._cmd.copy()


@dataclass(frozen=True)
class ExpertRun:
    """One expert run: true path ``trajectory`` (K, 4) = [t_s, x_N, y_E, ψ] every 0.1 s, the
    episode's pole and goal (2,), its spec and traits, and whether it ended at the goal."""

    spec: EpisodeSpec
    trajectory: FloatArray
    pole_ne: FloatArray
    goal_ne: FloatArray
    traits: dict[str, float | bool]
    finished: bool

    @property
    def min_pole_distance_m(self) -> float:
        return float(np.min(np.hypot(*(self.trajectory[:, 1:3] - self.pole_ne).T)))


def run_expert(
    specs: Sequence[EpisodeSpec],
    *,
    seed: int,
    scenario: Scenario | None = None,
    params: ExpertParams | None = None,
) -> list[ExpertRun]:
    """Run the expert on every episode of ``specs`` in one simulator batch.

    The traits, perception noise and wobble come from ``numpy.random.default_rng(seed)``; the
    sensor noise of the simulator's navigation filter comes from each spec's ``noise_seed``.
    Returns one :class:`ExpertRun` per spec, cut at the run's end (module docstring).
    """
    scenario = scenario or Scenario()
    p = params or ExpertParams()
    rng = np.random.default_rng(seed)
    n = len(specs)
    fine = dataclasses.replace(
        scenario, decision_period_s=p.tick_s, max_heading_change_rad=p.max_change_per_tick_rad
    )
    sim = PoleAvoidanceBatch(n, observation="positional", action="gaussian", scenario=fine)
    sim.reset(None, list(specs))
    geo = episode_geometry(scenario, specs)
    traits = draw_traits(rng, n, p)
    expert = HumanExpert(traits, geo.pole_ne, geo.start_eta[:, :2], geo.goal_ne, p, rng)
    T = fine.steps_per_decision
    eta = sim.state.eta
    paths = [np.concatenate([[0.0], eta[i]])[None] for i in range(n)]
    chunks: list[list[FloatArray]] = [[row] for row in paths]
    active = np.ones(n, dtype=bool)
    finished = np.zeros(n, dtype=bool)
    for k in range(fine.max_decisions):
        eta = sim.state.eta
        cmd = expert.command(eta[:, :2], eta[:, 2])
        _, psi_hat = sim.estimate
        dpsi = np.clip(ssa(cmd - psi_hat), -p.max_change_per_tick_rad, p.max_change_per_tick_rad)
        res = sim.step((dpsi / p.max_change_per_tick_rad)[:, None].astype(np.float32))
        t = (k * T + np.arange(1, T + 1)) * fine.dt_s
        pos = res.trajectory[:, :, 0:2]
        to_goal = geo.goal_ne[:, None] - pos  # (N, T, 2)
        d_goal = np.hypot(to_goal[..., 0], to_goal[..., 1])
        rel_goal = ssa(np.arctan2(to_goal[..., 1], to_goal[..., 0]) - res.trajectory[:, :, 2])
        end = (d_goal <= p.finish_radius_m) | (
            (np.abs(rel_goal) > math.pi / 2) & (d_goal <= scenario.goal_radius_m)
        )
        for i in np.flatnonzero(active):
            stop = int(np.argmax(end[i])) + 1 if end[i].any() else T
            traj = res.trajectory[i, :stop, 0:3]
            chunks[i].append(np.column_stack([t[:stop], traj]))
            if end[i].any():
                active[i], finished[i] = False, True
        if not active.any():
            break
    return [
        ExpertRun(
            spec=specs[i],
            trajectory=np.concatenate(chunks[i]),
            pole_ne=geo.pole_ne[i].copy(),
            goal_ne=geo.goal_ne[i].copy(),
            traits=traits.row(i),
            finished=bool(finished[i]),
        )
        for i in range(n)
    ]
