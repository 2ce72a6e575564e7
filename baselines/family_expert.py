"""The human-like expert on the open-water family: the ``vo`` helmsman's decisions, steered by a
person with the imperfections of :mod:`baselines.expert`.

The study's expert (:mod:`baselines.expert`) knows one pole straight ahead. On the family (many,
large and moving obstacles, goals anywhere; :mod:`usvsim.task.openwater`) a person still looks
out, picks a course that clears what is around and heads for the goal; here that judgement is the
velocity-obstacle rule of :mod:`baselines.velocity_obstacle` (Kuwata et al. 2014), and the hand
on the wheel is the study expert's:

=======================  =====================================================================
what                     model (traits drawn per run, :class:`FamilyExpertTraits`)
=======================  =====================================================================
what the helmsman sees   the TRUE scene as it was ``reaction_delay_s`` ago (delay drawn per run
                         from :attr:`ExpertParams.reaction_delay_range_s`): own pose, velocity
                         over ground (from the last tick's motion), goal, every obstacle and
                         vessel; bearings with :attr:`ExpertParams.bearing_noise_rad` noise
caution                  ``caution_m`` more clear water wanted from every obstacle (drawn from
                         :attr:`FamilyExpertParams.caution_range_m`, added to vo's margins):
                         wider or closer passes
decision                 the ``vo`` course θ* (:func:`baselines.velocity_obstacle.vo_course`)
                         on that perceived ``scene`` observation, every tick (0.2 s), with its
                         hysteresis, and where every course is blocked the one that passes
                         widest; the heading to steer is ψ + ssa(θ* − β), β the crab angle
hand                     an Ornstein-Uhlenbeck wobble on the heading to steer, swung at most
                         :attr:`ExpertParams.max_turn_rate_radps` (the study expert's hand)
=======================  =====================================================================

The judgement is a part of its own (:class:`Judgement`): :class:`VOJudgement` is the family
expert's; :mod:`baselines.sbmpc_expert` puts ``sb-mpc``'s in its place, with the same eyes and hand.

:func:`run_family_expert` drives N family episodes in one simulator batch
(:class:`usvsim.task.openwater_batch.OpenWaterBatch` with the heading reference updated every
``tick_s`` instead of every 2 s: plant, autopilot, navigation filter, currents and sensor faults
of each episode). A run ends as the task's episodes do: at the goal (10 m), at a collision, out
of the area or at the time limit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from baselines.expert import ExpertParams
from baselines.velocity_obstacle import VOConfig, vo_course
from usvsim.common.angles import ssa
from usvsim.task.observations import scene_observation
from usvsim.task.openwater import OpenWaterEpisode
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.scenario import Scenario

__all__ = [
    "FamilyExpertParams",
    "FamilyExpertRun",
    "FamilyExpertTraits",
    "Judgement",
    "VOJudgement",
    "draw_family_traits",
    "run_family_expert",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FamilyExpertParams:
    """The family expert: the study expert's hand and eyes (``human``), the ``vo`` judgement
    (``vo``) and how cautious a run is (usvsim's model; no study gives one)."""

    human: ExpertParams = field(default_factory=ExpertParams)
    # vo's judgement, graded where every course is blocked: a cautious helmsman who starts 30 m
    # from a pole cannot keep his margin and turns hard to pass widest (measured, stress sets
    # from the expert's own seed 1: start-short 95 % yes/no cone, 99 % graded)
    vo: VOConfig = field(default_factory=lambda: VOConfig(w_shortfall=5.0))
    # m, added to every obstacle's margin in vo's cone as the helmsman judges it (not to the
    # turn's own clearance). 0-8 m: from vo's own passes to wider ones
    caution_range_m: tuple[float, float] = (0.0, 8.0)

    def __post_init__(self) -> None:
        lo, hi = self.caution_range_m
        if not (0.0 <= lo <= hi):
            raise ValueError(
                f"caution_range_m must be 0 <= low <= high m, got {self.caution_range_m}"
            )


@dataclass(frozen=True)
class FamilyExpertTraits:
    """One batch's draws, (N,) arrays: reaction delay (s) and caution (m)."""

    reaction_delay_s: FloatArray
    caution_m: FloatArray

    def row(self, i: int) -> dict[str, float]:
        """Run ``i``'s traits as plain numbers (for metadata files)."""
        return {f.name: float(getattr(self, f.name)[i]) for f in dataclasses.fields(self)}


def draw_family_traits(
    rng: np.random.Generator, n: int, p: FamilyExpertParams
) -> FamilyExpertTraits:
    """Draw the traits of ``n`` runs (module table)."""
    return FamilyExpertTraits(
        reaction_delay_s=rng.uniform(*p.human.reaction_delay_range_s, n),
        caution_m=rng.uniform(*p.caution_range_m, n),
    )


@dataclass(frozen=True)
class FamilyExpertRun:
    """One run: true path ``trajectory`` (K, 4) = [t_s, x_N, y_E, ψ] every plant step (0.1 s)
    from t = 0, the episode, the run's traits, and how it ended."""

    episode: OpenWaterEpisode
    trajectory: FloatArray
    traits: dict[str, float]
    success: bool  # at the goal, never closer than the safety distance to any obstacle
    collision: bool
    min_distance_m: float  # pole-equivalent closest approach over the run (m)


class _Eyes:
    """What each helmsman perceives: the true pose ``lag`` ticks ago (per boat)."""

    def __init__(self, lag_ticks: NDArray[np.int64]) -> None:
        self.lag = lag_ticks
        self.history: list[FloatArray] = []  # [x_N, y_E, ψ] (N, 3) per tick, oldest first

    def look(self, eta: FloatArray) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
        """Perceived pose (N, 3), the pose one tick before it (N, 3), and the lag (N,) ticks."""
        self.history.append(eta.copy())
        h = np.stack(self.history)  # (L, N, 3)
        rows = np.arange(eta.shape[0])
        lag = np.minimum(self.lag, h.shape[0] - 1)
        seen = h[h.shape[0] - 1 - lag, rows]
        before = h[np.maximum(h.shape[0] - 2 - lag, 0), rows]
        del self.history[: -2 - int(self.lag.max())]  # keep what a delay can reach
        return seen, before, lag


class Judgement(Protocol):
    """The helmsman's choice of course over ground, from what it perceives (module table)."""

    def reset(self, n_boats: int) -> None:
        """Forget every earlier choice; ``n_boats`` runs follow."""

    def course(self, observation: FloatArray, caution_m: FloatArray, tick: int) -> FloatArray:
        """Course over ground θ* (N,) rad relative to the heading, from the perceived ``scene``
        observations (N, 4 + 6 k) of tick ``tick`` (every ``ExpertParams.tick_s``) and each
        run's ``caution_m`` (N,) m."""
        ...


@dataclass
class VOJudgement:
    """The family expert's judgement: ``vo``'s course every tick, with its hysteresis (the
    previous choice kept relative to the goal's bearing while avoiding)."""

    config: VOConfig

    def reset(self, n_boats: int) -> None:
        self._from_goal = np.full(n_boats, np.nan)  # rad, last choice − goal bearing (NaN: none)

    def course(self, observation: FloatArray, caution_m: FloatArray, tick: int) -> FloatArray:
        goal = observation[:, 1]
        previous = np.where(np.isnan(self._from_goal), np.nan, ssa(self._from_goal + goal))
        course, avoiding = vo_course(self.config, observation, previous, caution_m)
        self._from_goal = np.where(avoiding, ssa(course - goal), np.nan)
        return course


def run_family_expert(
    episodes: Sequence[OpenWaterEpisode],
    *,
    seed: int,
    params: FamilyExpertParams | None = None,
    judgement: Judgement | None = None,
) -> list[FamilyExpertRun]:
    """Run the family expert on every episode in one batch (module docstring).

    ``judgement`` chooses the course (default: :class:`VOJudgement` with ``params.vo``). The
    traits, perception noise and wobble come from ``numpy.random.default_rng(seed)``; each
    episode's sensor noise and disturbances from the episode itself. Returns one
    :class:`FamilyExpertRun` per episode, cut at the end of its episode.
    """
    p = params or FamilyExpertParams()
    h = p.human
    judge = judgement if judgement is not None else VOJudgement(p.vo)
    rng = np.random.default_rng(seed)
    n = len(episodes)
    judge.reset(n)
    fine = Scenario(decision_period_s=h.tick_s, max_heading_change_rad=h.max_change_per_tick_rad)
    sim = OpenWaterBatch(n, observation="scene", action="gaussian", scenario=fine)
    sim.reset(None, list(episodes))
    traits = draw_family_traits(rng, n, p)
    eyes = _Eyes(np.round(traits.reaction_delay_s / h.tick_s).astype(np.int64))
    wobble = rng.normal(0.0, h.wobble_sigma_rad, n)
    a = math.exp(-h.tick_s / h.wobble_tau_s)
    hand = h.max_turn_rate_radps * h.tick_s  # rad per tick, the most the hand swings
    cmd = sim.inner.state.eta[:, 2].copy()
    steps = fine.steps_per_decision
    ticks = math.ceil(max(e.time_limit_s for e in episodes) / h.tick_s - 1e-9)
    path = np.empty((n, ticks * steps + 1, 3))  # [x_N, y_E, ψ] every plant step, all boats
    path[:, 0] = sim.inner.state.eta
    n_steps = np.full(n, ticks * steps)  # plant steps of each run (cut at its end)
    active = np.ones(n, dtype=bool)
    last: dict[str, NDArray[np.generic]] = {}
    for k in range(ticks):
        seen, before, lag = eyes.look(sim.inner.state.eta)
        vel = (seen[:, :2] - before[:, :2]) / h.tick_s
        t_seen = np.maximum(k - lag, 0) * h.tick_s
        centres, radii, velocity, ok = sim.scene_at(t_seen)
        obs = scene_observation(
            seen[:, :2], seen[:, 2], vel, sim.goal_ne, centres, radii, velocity, ok,
        ).astype(np.float64)  # fmt: skip
        slots = obs[:, 4:].reshape(n, -1, 6)
        obs[:, 1] += rng.normal(0.0, h.bearing_noise_rad, n)
        slots[..., 1] += rng.normal(0.0, h.bearing_noise_rad, slots.shape[:2]) * slots[..., 5]
        course = judge.course(obs, traits.caution_m, k)
        crab = np.where(np.hypot(obs[:, 2], obs[:, 3]) > 0.3, np.arctan2(obs[:, 3], obs[:, 2]), 0.0)
        wobble = a * wobble + math.sqrt(1 - a * a) * rng.normal(0.0, h.wobble_sigma_rad, n)
        target = seen[:, 2] + ssa(course - crab) + wobble
        cmd = np.asarray(ssa(cmd + np.clip(ssa(target - cmd), -hand, hand)))
        _, psi_hat = sim.inner.estimate
        dpsi = np.clip(ssa(cmd - psi_hat), -h.max_change_per_tick_rad, h.max_change_per_tick_rad)
        res = sim.step((dpsi / h.max_change_per_tick_rad)[:, None].astype(np.float32))
        path[:, 1 + k * steps : 1 + (k + 1) * steps] = res.trajectory[:, :, 0:3]
        ended = active & (res.terminated | res.truncated)
        n_steps[ended] = k * steps + res.end_step[ended]
        for name in ("is_success", "collision", "min_distance_m"):
            value = getattr(res, name)
            last[name] = np.where(active, value, last.get(name, value))
        active &= ~ended
        if not active.any():
            break
    t = np.arange(path.shape[1]) * fine.dt_s
    return [
        FamilyExpertRun(
            episode=episodes[i],
            trajectory=np.column_stack([t, path[i]])[: n_steps[i] + 1],
            traits=traits.row(i),
            success=bool(last["is_success"][i]),
            collision=bool(last["collision"][i]),
            min_distance_m=float(last["min_distance_m"][i]),
        )
        for i in range(n)
    ]
