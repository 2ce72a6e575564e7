"""The open-water family as a native ``gymnasium.vector.VectorEnv`` for training
(``usvsim/OpenWater-v0``).

:class:`OpenWaterVectorEnv` wraps :class:`usvsim.task.openwater_batch.OpenWaterBatch` the way
:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv` wraps the pole task: autoreset
``SAME_STEP`` (``final_obs`` / ``final_info``), per-boat seeded generators, the reward horizon
of :mod:`usvsim.task.horizon`. Each new episode of a boat is drawn from a
:class:`ScenarioMixture` of :class:`usvsim.task.openwater.OpenWaterScenario` members (domain
randomisation over the family's ranges, :data:`OPEN_WATER_FAMILY`); its disturbances (cruise
speed, current, GNSS quality) and radar quality are the episode's own, as the family defines
them (:mod:`usvsim.task.openwater`).

Reward (the study's, :class:`usvsim.task.reward.GaussianReward`, on the scene): at the end of a
decision period (for an episode that terminated, at its first goal / collision plant step),
from the TRUE position,

    d_pole = min_j ( |p − c_j| − R_j + R_pole )     R_pole = 1 m, over every static disc and
                                                    every vessel at its position at that step
    d_goal = |p − g|
    r      = GaussianReward(d_pole, d_goal)

i.e. the pole term sees the nearest obstacle by its pole-equivalent distance, the quantity of
the family's success rule (≥ 10 m from every obstacle). With no obstacle d_pole = ∞ and the pole
term is 0. A study episode (one 1 m pole) gives d_pole = the pole's centre distance: the pole
task's reward exactly (tested against ``PoleAvoidanceVectorEnv``).

``reward_horizon="fixed"`` is :func:`usvsim.task.horizon.apply_reward_horizon` with each
episode's own number of decisions K_i (the family's time limits differ per episode): the
horizon is evaluated against one reference horizon K_ref with every boat's clock advanced by
K_ref − K_i decisions, so m = K_i − (t + 1) as in the pole task.

The loop over boats that remains is over *finished* boats only, as in the pole task's env:
drawing their next episodes (scalar, seeded code per episode) and the ``final_obs`` object
array; the reset itself is one batched call.

Why this module is long: the env's Gymnasium docstring (Description to Arguments, from which its
documentation page is generated) takes about 110 lines, and the family the env draws from (its
members, mixtures and the practice members mixed into training) defines the env's episodes, so
it is kept beside the env.
"""

from __future__ import annotations

import bisect
import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from usvsim.task.batch import ActionKind, Observation, observation_rows, write_observation_rows
from usvsim.task.colreg_reward import COLREG_TERMS, ColregReward, ColregRewardWeights
from usvsim.task.horizon import RewardHorizon, apply_reward_horizon
from usvsim.task.observations import OBSERVATION_KINDS, ObservationKind
from usvsim.task.openwater import (
    OpenWaterEpisode,
    OpenWaterScenario,
    draw_open_water,
    seeds63,
)
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.options import EnvOptions, normalized_observation, normalized_positional_space
from usvsim.task.radar import RadarConfig
from usvsim.task.reward import (
    GaussianReward,
    GoalAimReward,
    RewardFunction,
    SafetyMarginReward,
    SuccessReward,
)
from usvsim.task.vector_env import boat_generators, episodes_option
from usvsim.task.weather_draw import WEATHER_SETS, WeatherRanges
from usvsim.vessel.plant import Plant

__all__ = [
    "OPEN_WATER_FAMILY",
    "RADAR_RANGES",
    "OpenWaterVectorEnv",
    "ScenarioMixture",
    "crowded_family",
    "draw_family",
    "draw_family_episode",
    "goal_approach_family",
    "goal_islet_family",
    "harsh_radar_family",
    "mix_families",
    "weather_family",
]

FloatArray = NDArray[np.float64]
DEG = math.pi / 180.0
_HORIZON_REF_S = 20_000.0  # s, the reference horizon K_ref · 2 s (module docstring); > any limit


@dataclass(frozen=True)
class ScenarioMixture:
    """A training distribution over members of the family: each episode picks member j with
    probability ``weights[j]`` (normalised), then draws from it."""

    members: tuple[OpenWaterScenario, ...]
    weights: tuple[float, ...]
    names: tuple[str, ...] = ()  # one label per member, for reports

    def __post_init__(self) -> None:
        w = np.asarray(self.weights, dtype=float)
        if not self.members or len(self.weights) != len(self.members):
            raise ValueError("ScenarioMixture needs one weight per member (and a member)")
        if not (np.all(np.isfinite(w)) and np.all(w >= 0) and w.sum() > 0):
            raise ValueError(f"ScenarioMixture weights must be >= 0 with a positive sum: {w}")
        if self.names and len(self.names) != len(self.members):
            raise ValueError("ScenarioMixture needs one name per member (or none)")

    @property
    def probabilities(self) -> FloatArray:
        w = np.asarray(self.weights, dtype=float)
        return w / w.sum()

    @functools.cached_property
    def _cdf(self) -> list[float]:
        """The cumulative distribution as ``Generator.choice(p=probabilities)`` builds it."""
        cdf = self.probabilities.cumsum()
        cdf /= cdf[-1]
        values: list[float] = cdf.tolist()
        return values

    def pick(self, rng: np.random.Generator) -> OpenWaterScenario:
        """A member drawn from ``rng`` with probability ``probabilities``: the member and the
        draw of ``rng.choice(len(members), p=probabilities)`` (one ``random()`` draw, the
        first index whose cumulative probability exceeds it), without its checks per call."""
        return self.members[bisect.bisect_right(self._cdf, rng.random())]


# The family's ranges: every perturbation of the stress suite (usvsim.evaluation.stress) at up
# to its strongest level, each drawn from 0 (or the study's value) upward, so calm water and
# clean sensors stay in the distribution. usvsim's choice for training (issue 18), not tuned.
_RANGES = OpenWaterScenario(
    start_distance_range_m=(30.0, 200.0),
    goal_distance_range_m=(100.0, 320.0),
    goal_bearing_range_rad=(-180 * DEG, 180 * DEG),
    goal_lateral_range_m=(0.0, 60.0),
    heading_offset_range_rad=(-180 * DEG, 180 * DEG),
    vessel_turn_rate_range_radps=(-0.3 * DEG, 0.3 * DEG),
    current_speed_range_mps=(0.0, 0.8),
    speed_range_mps=(1.5, 5.0),
    gnss_noise_scale_range=(1.0, 3.0),
    gnss_outlier_probability_range=(0.0, 0.05),
    gnss_dropout_probability=0.3,
    gnss_dropout_duration_range_s=(10.0, 30.0),
    radar_clutter_range=(0.0, 0.001),
    radar_speckle_range=(0.0, 0.5),
    radar_missed_range=(0.0, 0.2),
    radar_noise_range=(0.0, 40.0),
)

# poles: the study's pole plus 0-6 obstacles of 1-3 m (a fifth of them islets) in the route's
# corridor, 0-2 vessels
_POLES = replace(
    _RANGES, n_extra_range=(0, 6), extra_radius_range_m=(1.0, 3.0), islet_probability=0.2,
    n_vessels_range=(0, 2),
)  # fmt: skip
# islets: the primary obstacle 8-25 m in radius, 0-2 more islets
_ISLETS = replace(
    _RANGES, primary_radius_range_m=(8.0, 25.0), n_extra_range=(0, 2), islet_probability=1.0
)
# traffic: no pole, 1-3 vessels head-on, crossing or overtaken
_TRAFFIC = replace(_RANGES, primary_obstacle=False, n_vessels_range=(1, 3))
# a close pair: a second pole 15-30 m from the first
_PAIR = replace(_RANGES, n_extra_range=(1, 1), near_primary_range_m=(15.0, 30.0), min_gap_m=0.0)

OPEN_WATER_FAMILY = ScenarioMixture(
    members=(OpenWaterScenario(), _POLES, _ISLETS, _TRAFFIC, _PAIR),  # the study's task first
    weights=(0.15, 0.45, 0.15, 0.15, 0.10),
    names=("study", "poles", "islets", "traffic", "close-pair"),
)


def crowded_family(family: ScenarioMixture = OPEN_WATER_FAMILY) -> ScenarioMixture:
    """``family`` with each member's obstacle and vessel counts fixed at the most it draws; the
    members with neither (the study's lone pole) left out, the others keeping their weights."""
    kept = [
        (m, w, name)
        for m, w, name in zip(family.members, family.probabilities, family.names, strict=True)
        if m.n_extra_range[1] > 0 or m.n_vessels_range[1] > 0
    ]
    if not kept:
        raise ValueError("crowded_family: no member of the family has obstacles or vessels")
    members = tuple(
        replace(
            m,
            n_extra_range=(m.n_extra_range[1],) * 2,
            n_vessels_range=(m.n_vessels_range[1],) * 2,
        )
        for m, _, _ in kept
    )
    return replace(
        family,
        members=members,
        weights=tuple(float(w) for _, w, _ in kept),
        names=tuple(name for _, _, name in kept),
    )


# goal approach: no obstacle, the goal just outside its 10 m circle to a few turning circles away
# (14-40 m), the heading up to 115° off it (the goal ahead, abeam or behind the beam), cruise
# 2-4 m/s (turning circles of about 8-15 m at the ±30° heading steps); the family's current,
# GNSS and radar draws. usvsim's curriculum for the goal orbits of docs/notes/2026-12-traffic.md
# (a boat that passes the goal 10-15 m off and circles it), not tuned.
_GOAL_APPROACH = replace(
    _RANGES, primary_obstacle=False, goal_distance_range_m=(14.0, 40.0),
    goal_bearing_range_rad=(0.0, 0.0), goal_lateral_range_m=(0.0, 0.0),
    heading_offset_range_rad=(-115 * DEG, 115 * DEG), speed_range_mps=(2.0, 4.0),
)  # fmt: skip


def goal_approach_family() -> ScenarioMixture:
    """One member, ``goal-approach``: episodes that start near the goal, pointed past it
    (module constants above), for training the last metres of an approach; mixed into a
    training family by :func:`mix_families` (``RLSetup.approach_share``)."""
    return ScenarioMixture(members=(_GOAL_APPROACH,), weights=(1.0,), names=("goal-approach",))


# goal beside an islet: a late approach, the goal 40-100 m ahead and up to 60° off the heading
# (the goal orbits begin 25 m out with it 36-47° off), cruise 2-4 m/s, and one or two islets
# (8-25 m radius) from half-way along the route to beyond the goal, their edges at least the
# family's 25 m from start and goal (a median 29 m from the goal's centre): the stress suite's
# extended-obstacles ends, where the radar policies turn away from an islet the goal is nearer
# than (benchmarks/goal_response.py --islet). usvsim's curriculum, not tuned.
_GOAL_ISLET = replace(
    _GOAL_APPROACH, goal_distance_range_m=(40.0, 100.0),
    heading_offset_range_rad=(-60 * DEG, 60 * DEG), n_extra_range=(1, 2), islet_probability=1.0,
    islet_radius_range_m=(8.0, 25.0), corridor_along_range=(0.5, 1.5),
)  # fmt: skip


def goal_islet_family() -> ScenarioMixture:
    """One member, ``goal-islet``: a late approach to a goal with islets beside and beyond it
    (module constants above); mixed into a training family by :func:`mix_families`
    (``RLSetup.goal_islet_share``)."""
    return ScenarioMixture(members=(_GOAL_ISLET,), weights=(1.0,), names=("goal-islet",))


RADAR_RANGES = (  # the OpenWaterScenario fields of the radar's degradation
    "radar_clutter_range",
    "radar_speckle_range",
    "radar_missed_range",
    "radar_noise_range",
)


def harsh_radar_family(family: ScenarioMixture = OPEN_WATER_FAMILY) -> ScenarioMixture:
    """``family`` with each radar degradation (clutter, speckle, missed returns, noise) fixed at
    the highest level any of its members draws, in every member (the level of the stress suite's
    ``radar-noise`` set)."""
    top = {name: max(getattr(m, name)[1] for m in family.members) for name in RADAR_RANGES}
    fixed: dict[str, Any] = {name: (v, v) for name, v in top.items()}
    members = tuple(replace(m, **fixed) for m in family.members)
    return replace(family, members=members)


def weather_family(
    family: ScenarioMixture = OPEN_WATER_FAMILY, ranges: WeatherRanges | None = None
) -> ScenarioMixture:
    """``family`` with every member drawing wind and waves from ``ranges`` (default
    ``WEATHER_SETS["moderate"]``: up to 8 m/s of wind and 1 m of H_s, calm included;
    :mod:`usvsim.task.weather_draw`), e.g. ``gymnasium.make_vec("usvsim/OpenWater-v0",
    num_envs=N, family=weather_family())``. The default family draws no weather."""
    weather = WEATHER_SETS["moderate"] if ranges is None else ranges
    return replace(family, members=tuple(replace(m, weather=weather) for m in family.members))


def mix_families(
    base: ScenarioMixture, extra: ScenarioMixture, extra_share: float, prefix: str = "crowded-"
) -> ScenarioMixture:
    """One mixture drawing from ``extra`` with probability ``extra_share`` and from ``base``
    otherwise (each keeping its members' relative weights); ``extra``'s member names get
    ``prefix``. ``extra_share`` must lie in [0, 1)."""
    if not 0.0 <= extra_share < 1.0:
        raise ValueError(f"mix_families: extra_share must be in [0, 1), got {extra_share!r}")
    names: tuple[str, ...] = ()
    if base.names and extra.names:
        names = base.names + tuple(prefix + n for n in extra.names)
    return ScenarioMixture(
        members=base.members + extra.members,
        weights=tuple((1.0 - extra_share) * base.probabilities)
        + tuple(extra_share * extra.probabilities),
        names=names,
    )


def draw_family_episode(
    family: ScenarioMixture | OpenWaterScenario, rng: np.random.Generator
) -> OpenWaterEpisode:
    """One episode of ``family`` from ``rng``: the member (a mixture only), then an episode
    seed, then :func:`usvsim.task.openwater.draw_open_water` of that member with that seed."""
    member = family if isinstance(family, OpenWaterScenario) else family.pick(rng)
    return draw_open_water(member, seeds63(rng, 1)[0], 1)[0]


def draw_family(
    family: ScenarioMixture | OpenWaterScenario, seed: int, n: int
) -> tuple[OpenWaterEpisode, ...]:
    """``n`` episodes of ``family``; episode k from ``default_rng([seed, k])`` (a fixed set)."""
    return tuple(draw_family_episode(family, np.random.default_rng([seed, k])) for k in range(n))


class OpenWaterVectorEnv(VectorEnv):
    """Native batched open-water environment: ``num_envs`` boats, one plant call per step.

    ## Description
    The family of :mod:`usvsim.task.openwater` (many, large and moving obstacles, goals
    anywhere, currents, degraded GNSS and radar), one episode per boat drawn from ``family``
    (default :data:`OPEN_WATER_FAMILY`). Every 2 s the helmsman changes the heading reference
    relative to the estimated heading, as in the pole task.

    ## Action Space
    As the pole task: ``"gaussian"`` ``Box(-1, 1, (1,))`` (Δψ = 30° · a), ``"categorical"``
    ``Discrete(41)``.

    ## Observation Space
    From the navigation estimate (:mod:`usvsim.task.openwater_batch`): ``"positional"`` (the
    nearest obstacle by pole-equivalent distance as the study's pole), ``"scene"`` (52 floats:
    goal, own velocity, the k = 8 nearest obstacles), ``"radar"``, ``"radar+goal"`` (every disc
    at its true extent, with the episode's radar degradation). ``normalize_observation=True``
    standardises the positional observation as in the pole task; the others are unchanged.

    ## Rewards
    The study's reward (Vedeler 2019; :class:`usvsim.task.reward.GaussianReward`) with the pole
    term on the nearest obstacle's pole-equivalent distance ``d = min_j |p - c_j| - R_j + 1 m``
    (obstacle j's centre c_j and radius R_j, vessels where they are at that step), the
    quantity of the success rule::

        r = r_pole + r_goal
        r_pole = -2 · exp(-½ (d / 5 m)²)               ∈ (-2, 0)
        r_goal = -1 + exp(-½ (d_goal / 100 m)²)        ∈ (-1, 0)

    ``info["reward_pole"]``, ``info["reward_goal"]``. ``reward_horizon="fixed"`` (train with
    it) adds on a terminating step the discounted reward of staying there until the episode's
    own time limit, as in :class:`usvsim.task.env.PoleAvoidanceEnv`. ``colreg_reward``
    (:class:`usvsim.task.colreg_reward.ColregRewardWeights`; default None: off) adds the
    per-decision COLREG terms of :mod:`usvsim.task.colreg_reward` (``info["reward_colreg"]``
    and ``info["reward_colreg_<term>"]``). ``safety_reward``
    (:class:`usvsim.task.reward.SafetyMarginReward`; default None: off) adds a penalty for every
    decision period that comes within the success rule's safety distance, over all its plant
    steps (``info["reward_safety"]``). ``success_reward``
    (:class:`usvsim.task.reward.SuccessReward`; default None: off) pays once at the decision an
    episode ends in success, after the fixed horizon's scaling (``info["reward_success"]``).
    ``aim_reward`` (:class:`usvsim.task.reward.GoalAimReward`; default None: off) adds a penalty
    for pointing off the goal within its range of it, from the true pose at the end of each
    decision period (``info["reward_aim"]``).

    ## Starting State
    Boat i draws its episodes from its own generator, seeded ``seed + i`` by
    ``reset(seed=seed)`` (or ``seed[i]``); ``reset(options={"episodes": [OpenWaterEpisode,
    ...]})`` starts the given episodes (one per boat), later autoresets draw again.

    ## Episode End
    Terminated: goal reached or a collision (and, under the fixed horizon, leaving the area);
    truncated: the episode's time limit or leaving the area (its ``area_radius_m``). With
    ``unsafe_ends=True`` (training only; default False) a decision period that comes within the
    success rule's safety distance also terminates the episode (``info["unsafe_end"]``): the
    episode has failed by that rule, and under the fixed horizon its terminal reward carries the
    decisions left, as a collision's does. Autoreset
    ``SAME_STEP``: ``info["final_obs"]``, ``info["final_info"]`` as in
    :class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`.

    ## Arguments
    ``num_envs``, ``observation``, ``action``, ``family``, ``reward_horizon``, ``gamma``,
    ``normalize_observation``, ``reward`` (a :class:`usvsim.task.reward.RewardFunction`),
    ``plant``, ``radar``, ``backend``, ``colreg_reward``, ``safety_reward``, ``success_reward``,
    ``aim_reward``, ``unsafe_ends`` (wind and waves:
    ``family=weather_family()``; the default family is calm). ``render_mode`` must be
    ``None``: the top view draws one pole (:mod:`usvsim.task.render`). ``info_observation``
    (e.g. ``"scene"``): ``reset`` and every ``step`` also return that form of the returned
    observation as ``info["observation_<kind>"]`` (N, ...) (after an autoreset the new
    episode's, as the observation; ``final_info`` does not carry it): privileged input for a
    learner that trains on more than the policy sees (a GAIL discriminator on the true scene
    beside a radar policy). ``on_decision`` (default None): an object with ``reset(sim,
    boats)`` (boats starting episodes) and ``steer(sim, time_s) -> bool`` (after each
    decision's reward, at each boat's episode time; True: the scene changed, observe again)
    that may steer the vessels, e.g. reactive targets
    (:class:`usvsim.evaluation.colreg_rollout.TrainingReactiveTargets`).
    """

    def __init__(
        self,
        num_envs: int,
        observation: ObservationKind = "positional",
        action: ActionKind = "gaussian",
        family: ScenarioMixture | OpenWaterScenario | None = None,
        render_mode: str | None = None,
        reward_horizon: RewardHorizon = "episode",
        gamma: float = 0.99,
        normalize_observation: bool = False,
        reward: RewardFunction | None = None,
        plant: Plant | None = None,
        radar: RadarConfig | None = None,
        backend: Literal["auto", "compiled", "casadi"] = "auto",
        info_observation: ObservationKind | None = None,
        colreg_reward: ColregRewardWeights | None = None,
        on_decision: Any = None,
        safety_reward: SafetyMarginReward | None = None,
        success_reward: SuccessReward | None = None,
        aim_reward: GoalAimReward | None = None,
        unsafe_ends: bool = False,
    ) -> None:
        self.options = EnvOptions(reward_horizon, gamma, normalize_observation, render_mode)
        if render_mode is not None:
            raise ValueError(
                f"render_mode must be None for the open-water env (the top view draws one "
                f"pole), got {render_mode!r}"
            )
        self.metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
        self.render_mode = None
        self.family = OPEN_WATER_FAMILY if family is None else family
        self.reward: RewardFunction = reward or GaussianReward()
        self.colreg = None if colreg_reward is None else ColregReward(colreg_reward, num_envs)
        self.safety = safety_reward
        self.success = success_reward
        self.aim = aim_reward
        self.unsafe_ends = bool(unsafe_ends)
        self.on_decision = on_decision
        self.sim = OpenWaterBatch(
            num_envs, observation=observation, action=action, plant=plant, radar=radar,
            backend=backend,
        )  # fmt: skip
        self.num_envs = self.sim.n_boats
        if info_observation is not None and info_observation not in OBSERVATION_KINDS:
            raise ValueError(
                f"info_observation must be None or one of {OBSERVATION_KINDS}, "
                f"got {info_observation!r}"
            )
        self.info_observation = info_observation
        self._normalize = normalize_observation and observation == "positional"
        space = self.sim.single_observation_space
        if self._normalize:
            space = normalized_positional_space(space)
        self.single_observation_space = space
        self.single_action_space = self.sim.inner.single_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._boat_rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        base = self.sim.base
        self._horizon = replace(base, time_limit_s=_HORIZON_REF_S)  # K_ref (module docstring)
        self._decisions = np.zeros(self.num_envs, dtype=np.int64)
        self._max_decisions = np.zeros(self.num_envs, dtype=np.int64)

    def _draw(self, boats: NDArray[np.intp]) -> list[OpenWaterEpisode]:
        return [draw_family_episode(self.family, self._boat_rngs[i]) for i in boats.tolist()]

    def _start(self, boats: NDArray[np.intp], episodes: Sequence[OpenWaterEpisode]) -> Observation:
        """Start ``episodes`` on ``boats`` in one batched reset; their first observation."""
        obs = self.sim.reset(boats, episodes)
        limits = self.sim.time_limit[boats]
        self._max_decisions[boats] = np.ceil(limits / self.sim.base.decision_period_s - 1e-9)
        self._decisions[boats] = 0
        if self.colreg is not None:
            self.colreg.reset(boats)
        if self.on_decision is not None:
            self.on_decision.reset(self.sim, boats)
        return self._observation(obs)

    def _observation(self, obs: Observation) -> Observation:
        if self._normalize:
            return normalized_observation("positional", obs)
        return obs

    def reset(
        self, *, seed: int | Sequence[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Reset every boat; ``seed`` int → boat i uses ``seed + i``; ``options``: ``episodes``."""
        super().reset(seed=seed if isinstance(seed, int) or seed is None else None)
        if seed is not None:
            self._boat_rngs = boat_generators(self.num_envs, seed)
        episodes = episodes_option(options)
        everyone = np.arange(self.num_envs)
        if episodes is None:
            episodes = self._draw(everyone)
        if len(episodes) != self.num_envs:
            raise ValueError(f"need one episode per boat ({self.num_envs}), got {len(episodes)}")
        obs = self._start(everyone, list(episodes))
        info = {"goal_ne": self.sim.goal_ne.copy()}
        return obs, self._add_info_observation(info)

    def _goal_bearing_rad(self, res: Any) -> FloatArray:
        """The goal's bearing off each boat's true heading (rad) at the end of the step's
        decision period (its last plant state, ``res.end_step - 1``)."""
        end = res.trajectory[np.arange(self.num_envs), res.end_step - 1]
        d = self.sim.goal_ne - end[:, 0:2]
        return np.arctan2(d[:, 1], d[:, 0]) - end[:, 2]

    def _add_info_observation(self, info: dict[str, Any]) -> dict[str, Any]:
        """``info`` with ``observation_<kind>`` of ``info_observation`` (unchanged if None)."""
        if self.info_observation is not None:
            info[f"observation_{self.info_observation.replace('+', '_')}"] = self.sim.observe(
                self.info_observation
            )
        return info

    def step(
        self, actions: Any
    ) -> tuple[Observation, FloatArray, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        res = self.sim.step(actions)
        self._decisions += 1
        d_obstacle = res.distance_to_obstacle_m
        terms = self.reward(d_obstacle, res.distance_to_goal_m)
        dp = self.sim.base.decision_period_s
        time_s = (self._decisions * dp).astype(np.float64)
        o = self.options
        shifted = time_s + (self._horizon.max_decisions - self._max_decisions) * dp
        total, extra = terms.total, {}
        if self.colreg is not None:
            colreg = self.colreg.from_batch(self.sim, res, time_s - dp)
            total = total + colreg.total
            extra = {f"reward_colreg_{t}": getattr(colreg, t) for t in COLREG_TERMS}
            extra["reward_colreg"] = colreg.total
        if self.safety is not None:
            safety = self.safety(res.period_nearest_m, self.sim.base.safety_distance_m)
            total = total + safety
            extra["reward_safety"] = safety
        if self.aim is not None:
            aim = self.aim(self._goal_bearing_rad(res), res.distance_to_goal_m)
            total = total + aim
            extra["reward_aim"] = aim
        ended, cut = res.terminated, res.truncated
        if self.unsafe_ends:  # failed by the success rule: an end, as a collision is
            unsafe = (res.period_nearest_m < self.sim.base.safety_distance_m) & ~ended
            ended, cut = ended | unsafe, cut & ~unsafe
            extra["unsafe_end"] = unsafe
        reward, terminated, truncated = apply_reward_horizon(
            o.reward_horizon, o.gamma, self._horizon, total, ended, cut, res.out_of_area, shifted
        )
        if self.success is not None:  # after the horizon's scaling (SuccessReward)
            success = self.success(res.is_success & terminated)
            reward = reward + success
            extra["reward_success"] = success
        arrays: dict[str, NDArray[np.generic]] = {
            "reward_pole": terms.pole,
            "reward_goal": terms.goal,
            "heading_change_rad": res.heading_change_rad,
            "distance_to_obstacle_m": d_obstacle,
            "distance_to_goal_m": res.distance_to_goal_m,
            "min_distance_m": res.min_distance_m,
            "reached_goal": res.reached_goal,
            "collision": res.collision,
            "out_of_area": res.out_of_area,
            "time_limit": res.time_limit,
            "is_success": res.is_success,
            "time_s": time_s,
            "time_to_goal_s": res.time_to_goal_s,
            **extra,
        }
        everyone = np.ones(self.num_envs, dtype=bool)
        info: dict[str, Any] = {}
        for key, value in arrays.items():
            info[key], info[f"_{key}"] = value, everyone
        obs = res.observation
        if self.on_decision is not None and self.on_decision.steer(self.sim, time_s):
            obs = self.sim.observe(self.sim.observation_kind)  # the targets' new courses
        obs = self._observation(obs)
        done = terminated | truncated
        if done.any():
            idx = np.flatnonzero(done)
            final_obs = np.full(self.num_envs, None, dtype=object)
            for i, row in zip(idx.tolist(), _rows_list(obs, idx), strict=True):
                final_obs[i] = row
            final_info: dict[str, Any] = {}
            for key, value in arrays.items():
                final_info[key], final_info[f"_{key}"] = value.copy(), done
            info.update(
                final_obs=final_obs, _final_obs=done, final_info=final_info, _final_info=done
            )
            write_observation_rows(obs, idx, self._start(idx, self._draw(idx)))
        return obs, reward, terminated, truncated, self._add_info_observation(info)


def _rows_list(obs: Observation, idx: NDArray[np.intp]) -> list[Any]:
    """The rows ``idx`` of a batched observation as a list of single observations (copies)."""
    rows = observation_rows(obs, idx)
    if isinstance(rows, dict):
        return [{k: v[j] for k, v in rows.items()} for j in range(idx.size)]
    return list(rows)
