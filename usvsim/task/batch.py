"""The pole-avoidance task for N boats at once: the batch simulator.

:class:`PoleAvoidanceBatch` is the one implementation of the task's step (the single-boat
:class:`usvsim.task.env.PoleAvoidanceEnv` is its N = 1 case,
:func:`usvsim.evaluation.episodes.evaluate` runs a whole episode set through it). One decision
step of all N boats is::

    Δψ     = action → heading change (rad)                       (N,)
    ψ_ref  = ssa(ψ̂ + Δψ)                 ψ̂: ESTIMATED heading at the decision
    plant  : 20 steps of 0.1 s, one compiled call                 traj (N, 20, 13)
    nav    : Kalman filters over the 20 steps (noisy sensors)     ψ̂, p̂ at the period's end
    done   : from the TRUE positions at every 0.1 s step of traj
    reward : from the TRUE distances at the period's end (for an episode that terminated,
             at its first collision / goal step: the rest of the period is discarded)
    obs    : from the ESTIMATE at the period's end

Shapes (N boats; T = 20 plant steps per decision):

=======================  ==============  ============================================
name                     shape           meaning
=======================  ==============  ============================================
actions (gaussian)       (N, 1) float    in [-1, 1]; Δψ = 30° · a (linear, no clipping)
actions (categorical)    (N,) int        in 0..40; Δψ = -30° + 1.5° · k
observation              (N, ...)        :mod:`usvsim.task.observations`
BatchStep.trajectory     (N, T, 13)      true plant [x, c] after each 0.1 s step
=======================  ==============  ============================================

The Gaussian action is scaled linearly, not squashed: a policy that wants the study's sigmoid
(or tanh) applies it itself; actions outside [-1, 1] raise rather than being clipped silently.

:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv` wraps the batch as a native
``gymnasium.vector.VectorEnv`` (autoreset ``SAME_STEP``).

In weather (:attr:`PoleAvoidanceBatch.in_weather`, issue 38) the plant is
:class:`usvsim.vessel.weather_plant.WeatherPlant` fused with the filter: the packed state gains
the weather states, and each boat with weather draws 3 T more normals per decision from its
episode stream (after the filter's), so calm episodes' streams are untouched.

Why this module is long: the batch is the one implementation of the task's step (actions, the
fused plant and filter, calm or in weather, the flags, the reward, the observation); splitting
it would spread one step's state over modules.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any, Literal, cast, get_args

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.common.interrupt import check_interrupt
from usvsim.nav.compiled import export_nav_state, started_nav_rows
from usvsim.nav.filter import Navigator
from usvsim.nav.models import NavConfig
from usvsim.nav.navplant import PACKED, NavigatedPlant, PackedLayout
from usvsim.task.disturbance import BoatDisturbances, EpisodeDisturbance
from usvsim.task.observations import ObservationKind, build_observation, observation_space
from usvsim.task.radar import RadarConfig
from usvsim.task.reward import GaussianReward, RewardFunction, RewardTerms
from usvsim.task.scenario import BoatNoise, EpisodeSpec, Scenario, episode_geometry
from usvsim.vessel.autopilot import AutopilotConfig
from usvsim.vessel.plant import Plant, PlantState
from usvsim.vessel.vessels import VesselParams
from usvsim.vessel.weather_plant import WeatherPlant

__all__ = [
    "ACTION_KINDS",
    "N_CATEGORIES",
    "ActionKind",
    "BatchStep",
    "PoleAvoidanceBatch",
    "action_space",
    "heading_change_rad",
    "observation_rows",
    "parse_action_kind",
    "within_radius",
    "write_observation_rows",
]

ActionKind = Literal["gaussian", "categorical"]
ACTION_KINDS: tuple[str, ...] = get_args(ActionKind)
N_CATEGORIES = 41  # study: 0 → -30°, 20 → 0°, 40 → +30°
FloatArray = NDArray[np.float64]
Observation = NDArray[np.generic] | dict[str, NDArray[np.generic]]


def parse_action_kind(kind: object) -> ActionKind:
    """``kind`` as an :data:`ActionKind` (e.g. a string read from a file or a flag).

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`ACTION_KINDS`.
    """
    if kind not in ACTION_KINDS:
        raise ValueError(f"action must be one of {ACTION_KINDS}, got {kind!r}")
    return cast(ActionKind, kind)


def action_space(kind: ActionKind) -> spaces.Space:
    """Single-boat action space: ``Box(-1, 1, (1,))`` or ``Discrete(41)``."""
    if kind == "gaussian":
        return spaces.Box(-1.0, 1.0, (1,), dtype=np.float32)
    if kind == "categorical":
        return spaces.Discrete(N_CATEGORIES)
    raise ValueError(f"action must be one of {ACTION_KINDS}, got {kind!r}")


def heading_change_rad(
    kind: ActionKind, actions: Any, n_boats: int, max_change_rad: float
) -> FloatArray:
    """Validate batched actions and map them to heading changes Δψ (rad), shape (N,).

    Raises
    ------
    ValueError
        On a wrong shape, a non-numeric or NaN/inf action, a Box action outside [-1, 1], or a
        category that is not an integer in 0..40.
    """
    a = np.asarray(actions)
    if kind == "gaussian":
        if a.shape != (n_boats, 1):
            raise ValueError(
                f"gaussian actions must have shape ({n_boats}, 1) (one row per boat, one heading "
                f"change each), got {a.shape}"
            )
        if a.dtype.kind not in "fiu":
            raise ValueError(f"gaussian actions must be numbers, got dtype {a.dtype}")
        a = a[:, 0].astype(np.float64)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"gaussian actions contain NaN or inf: {a}")
        if np.any(np.abs(a) > 1.0):
            raise ValueError(
                f"gaussian actions must lie in [-1, 1] (scaled to ±30°; the env does "
                f"not clip), got {a[np.abs(a) > 1.0][:5]}"
            )
        return a * max_change_rad
    if kind == "categorical":
        if a.shape != (n_boats,):
            raise ValueError(
                f"categorical actions must have shape ({n_boats},) (one category per boat), "
                f"got {a.shape}"
            )
        if a.dtype.kind not in "iu":
            raise ValueError(
                f"categorical actions must be integers 0..{N_CATEGORIES - 1}, got dtype {a.dtype}"
            )
        if np.any((a < 0) | (a >= N_CATEGORIES)):
            raise ValueError(
                f"categorical actions must lie in 0..{N_CATEGORIES - 1}, got "
                f"{a[(a < 0) | (a >= N_CATEGORIES)][:5]}"
            )
        centre = (N_CATEGORIES - 1) // 2
        return (a.astype(np.float64) - centre) * (max_change_rad / centre)
    raise ValueError(f"action must be one of {ACTION_KINDS}, got {kind!r}")


def within_radius(dx: FloatArray, dy: FloatArray, radius_m: float) -> NDArray[np.bool_]:
    """``np.hypot(dx, dy) <= radius_m``, exactly, with hypot evaluated only inside the square
    ``|dx|, |dy| <= radius_m``: hypot (rounded faithfully) is never below ``max(|dx|, |dy|)``."""
    inside = (np.abs(dx) <= radius_m) & (np.abs(dy) <= radius_m)
    if inside.any():
        inside[inside] = np.hypot(dx[inside], dy[inside]) <= radius_m
    return inside


@dataclass(frozen=True)
class BatchStep:
    """Everything one decision step of N boats produced; every array has leading axis N.

    Distances and flags come from the TRUE state (checked at every 0.1 s plant step where it
    says so); ``est_pos_ne`` / ``est_psi_rad`` are the navigation estimate the observation uses.
    """

    observation: Observation
    reward: FloatArray
    terms: RewardTerms
    terminated: NDArray[np.bool_]  # reached_goal | collision
    truncated: NDArray[np.bool_]  # (time_limit | out_of_area) and not terminated
    heading_change_rad: FloatArray  # the action, in rad
    distance_to_pole_m: FloatArray  # at the episode's end step (see module docstring)
    distance_to_goal_m: FloatArray  # at the episode's end step
    min_distance_to_pole_m: FloatArray  # over the episode so far, every plant step
    reached_goal: NDArray[np.bool_]  # within goal_radius_m at some plant step of this period
    collision: NDArray[np.bool_]  # inside pole radius + half beam at some plant step
    out_of_area: NDArray[np.bool_]  # farther than area_radius_m from the pole at the end
    time_limit: NDArray[np.bool_]
    is_success: NDArray[np.bool_]  # reached_goal, no collision, never < safety_distance_m
    time_s: FloatArray  # episode time at the period's end
    time_to_goal_s: FloatArray  # first plant step within goal_radius_m; inf if not yet
    trajectory: FloatArray  # (N, T, 13) true [x, c] after each plant step
    end_step: NDArray[np.intp]  # plant steps of this period up to the end (event step or T)
    est_pos_ne: FloatArray  # (N, 2)
    est_psi_rad: FloatArray  # (N,)

    def info_arrays(self) -> dict[str, NDArray[np.generic]]:
        """The per-boat ``info`` entries (each (N,)): reward terms, distances, flags, times."""
        skip = {
            "observation",
            "reward",
            "terms",
            "terminated",
            "truncated",
            "trajectory",
            "end_step",
            "est_pos_ne",
            "est_psi_rad",
        }
        info: dict[str, NDArray[np.generic]] = {
            "reward_pole": self.terms.pole,
            "reward_goal": self.terms.goal,
        }
        info.update({f.name: getattr(self, f.name) for f in fields(self) if f.name not in skip})
        return info


class PoleAvoidanceBatch:
    """N boats on the pole-avoidance task, stepped together (no autoreset).

    Parameters
    ----------
    n_boats : int
    observation : "positional" | "radar" | "radar+goal"
    action : "gaussian" | "categorical"
    scenario : Scenario, optional
    reward : RewardFunction, optional
        Default :class:`usvsim.task.reward.GaussianReward`.
    radar : RadarConfig, optional
    nav : NavConfig, optional
        Sensor and filter settings; its ``dt_s`` must equal the scenario's.
    plant : Plant, optional
        A plant to share (it holds no boat state); default ``Plant(vessel, autopilot, dt_s)``.
    vessel, autopilot, backend
        Passed to :class:`usvsim.vessel.plant.Plant` when ``plant`` is not given.

    Notes
    -----
    The sensors run on the batch's clock (plant step counter since construction), so a boat's
    sensor schedule within a decision period is the same for every boat as long as the period
    (20 steps) is a multiple of every sensor period (GNSS 2, compass 1 by default).
    """

    def __init__(
        self,
        n_boats: int,
        *,
        observation: ObservationKind = "positional",
        action: ActionKind = "gaussian",
        scenario: Scenario | None = None,
        reward: RewardFunction | None = None,
        radar: RadarConfig | None = None,
        nav: NavConfig | None = None,
        plant: Plant | None = None,
        vessel: VesselParams | str = "default",
        autopilot: AutopilotConfig | None = None,
        backend: Literal["auto", "compiled", "casadi"] = "auto",
    ) -> None:
        if isinstance(n_boats, bool) or not isinstance(n_boats, (int, np.integer)) or n_boats < 1:
            raise ValueError(f"n_boats must be a positive integer, got {n_boats!r}")
        self.n_boats = n = int(n_boats)
        self.observation_kind = observation
        self.action_kind = action
        self.single_observation_space = observation_space(observation, radar)
        self.single_action_space = action_space(action)
        self.scenario = scenario or Scenario()
        self.reward: RewardFunction = reward or GaussianReward()
        self.radar = radar or RadarConfig()
        nav = nav or NavConfig(dt_s=self.scenario.dt_s)
        if abs(nav.dt_s - self.scenario.dt_s) > 1e-12:
            raise ValueError(f"NavConfig.dt_s {nav.dt_s} != Scenario.dt_s {self.scenario.dt_s}")
        self.plant = plant or Plant(vessel, autopilot, dt_s=self.scenario.dt_s, backend=backend)
        if abs(self.plant.dt_s - self.scenario.dt_s) > 1e-12:
            raise ValueError(f"Plant.dt_s {self.plant.dt_s} != Scenario.dt_s {self.scenario.dt_s}")
        # the filters' reference implementation, used to start them (reset); while stepping,
        # their states live packed in self._s
        self._nav = Navigator(nav, n)
        self._navplant = NavigatedPlant(self.plant, nav)  # plant + filter, compiled together
        self._noise = BoatNoise(n)
        self._collision_m = self.scenario.pole_radius_m + self.plant.vessel.half_beam_m
        # packed per-boat state [x (8), c (5), filter n (15)], the fused step's layout (N, 28)
        # (named slices: self._layout, usvsim.nav.navplant.PACKED; in weather [x, c, m (8), n],
        # see _start_weather); the filter part is meaningful once a boat is reset
        start = self.plant.initial_state(np.zeros((n, 3)))
        self._s = np.concatenate([start.x, start.c, export_nav_state(self._nav)], axis=1)
        self.pole_ne = np.zeros((n, 2))
        self.goal_ne = np.zeros((n, 2))
        self._est_pos = np.zeros((n, 2))
        self._est_psi = np.zeros(n)
        self._n_decisions = np.zeros(n, dtype=np.int64)
        self._min_pole = np.full(n, np.inf)
        self._t_goal = np.full(n, np.inf)
        self._plant_step = 0
        self._ready = np.zeros(n, dtype=bool)
        # per-episode speed, current and GNSS faults (usvsim.task.disturbance); none by default
        self.disturbances = BoatDisturbances(n, self.scenario.speed_mps, self.plant.current)

    @property
    def _layout(self) -> PackedLayout:
        """Named columns of the packed state (``PACKED``, or with the weather states)."""
        return self._navplant.layout

    @property
    def in_weather(self) -> bool:
        """True once a reset brought weather: the boats step in the weather plant."""
        return self._navplant.weather is not None

    def _start_weather(self) -> None:
        """Switch to the weather plant fused with the filter (the first reset that brings
        weather): the packed state gains the weather states ``m`` between ``c`` and ``n``, every
        boat's the calm ones (no wind, no waves, no wave filter) until its reset gives it a
        weather. A batch that never sees weather keeps the calm kernel and its numbers."""
        old, n = self._s, self.n_boats
        weather = WeatherPlant(self.plant, innovations="normal")
        self._navplant = NavigatedPlant(self.plant, self._nav.cfg, weather)
        lay = self._navplant.layout
        self._s = np.zeros((n, lay.size))
        self._s[:, lay.closed_loop] = old[:, PACKED.closed_loop]
        self._s[:, lay.nav] = old[:, PACKED.nav]
        self._s[:, lay.weather] = self.disturbances.start_calm_weather(
            weather, old[:, 0:3], old[:, 3]
        )

    @property
    def state(self) -> PlantState:
        """True plant state of all boats (for evaluation and plots, never for observations)."""
        lay = self._layout
        return PlantState(x=self._s[:, lay.plant].copy(), c=self._s[:, lay.controller].copy())

    @property
    def estimate(self) -> tuple[FloatArray, FloatArray]:
        """Navigation estimate at the last decision: position (N, 2) m and heading (N,) rad."""
        return self._est_pos.copy(), self._est_psi.copy()

    @property
    def estimated_velocity(self) -> FloatArray:
        """Navigation estimate of the velocity over ground (N, 2) m/s, [v_N, v_E], now."""
        return self._s[:, self._layout.nav_vel].copy()

    def reset(
        self,
        boats: NDArray[np.intp] | None,
        specs: Sequence[EpisodeSpec],
        disturbances: Sequence[EpisodeDisturbance | None] | None = None,
    ) -> Observation:
        """Start new episodes for ``boats`` (``None``: all) from ``specs`` (one per boat).

        ``disturbances`` (one per boat, or None for none): per-episode speed, current, GNSS
        faults and weather (:mod:`usvsim.task.disturbance`; the first weather switches the
        batch to the weather plant, :meth:`_start_weather`). Returns the first observation of
        the reset boats only (leading axis ``len(specs)``).
        """
        idx = self.start(boats, specs, disturbances)
        return self._observe(idx)

    def start(
        self,
        boats: NDArray[np.intp] | None,
        specs: Sequence[EpisodeSpec],
        disturbances: Sequence[EpisodeDisturbance | None] | None = None,
    ) -> NDArray[np.intp]:
        """:meth:`reset` without the first observation (for a caller that observes a scene of
        its own, as the open-water batch does); returns the started boats' indices. A radar
        observation draws from the boats' streams; a positional or scene one does not, so a
        positional batch started this way has every number of one reset."""
        idx = np.arange(self.n_boats) if boats is None else np.asarray(boats, dtype=np.intp)
        if len(specs) != idx.size:
            raise ValueError(f"need one EpisodeSpec per reset boat ({idx.size}), got {len(specs)}")
        geo = episode_geometry(self.scenario, specs)
        self.disturbances.set(idx, [None] * idx.size if disturbances is None else disturbances)
        if not self.in_weather and self.disturbances.brings_weather(disturbances):
            self._start_weather()
        lay = self._layout
        speed = self.disturbances.speed_mps[idx] if disturbances else self.scenario.speed_mps
        rows = self.plant.initial_state(geo.start_eta, speed)
        self._s[idx, lay.plant], self._s[idx, lay.controller] = rows.x, rows.c
        self.pole_ne[idx], self.goal_ne[idx] = geo.pole_ne, geo.goal_ne
        self._noise.seed(idx, [s.noise_seed for s in specs])
        # the freshly started filters: Navigator.reset's draws and numbers for these boats only
        nav = started_nav_rows(self._nav.cfg, rows.x[:, 0:3], rows.x[:, 3:6], self._rng_view(idx))
        self._noise.for_boats(None)
        self._s[idx, lay.nav] = nav
        if self._navplant.weather is not None:  # after the filter's draws: calm streams unchanged
            self._s[idx, lay.weather] = self.disturbances.start_weather(
                self._navplant.weather,
                idx,
                rows.x[:, 0:3],
                rows.x[:, 3],
                self._noise.for_boats,
                calm=rows,
            )
            self._noise.for_boats(None)
        self._est_pos[idx], self._est_psi[idx] = nav[:, 0:2], nav[:, 8]
        self._n_decisions[idx] = 0
        self._min_pole[idx] = [s.start_distance_m for s in specs]
        self._t_goal[idx] = np.inf
        self._ready[idx] = True
        return idx

    def _rng_view(self, idx: NDArray[np.intp] | None) -> np.random.Generator:
        """The per-boat noise streams of ``idx``, passed where a ``Generator`` is expected.

        The navigator only calls ``rng.normal(loc, scale, size=(n, ...))``, which
        :class:`usvsim.task.scenario.BoatNoise` implements row by row from each boat's own stream.
        """
        return cast(np.random.Generator, self._noise.for_boats(idx))

    def _observe(self, idx: NDArray[np.intp] | None = None) -> Observation:
        sl: Any = slice(None) if idx is None else idx
        noise = self._noise.for_boats(idx)
        obs = build_observation(
            self.observation_kind,
            self._est_pos[sl],
            self._est_psi[sl],
            self.pole_ne[sl],
            self.goal_ne[sl],
            self.scenario.pole_radius_m,
            self.radar,
            noise,
            self._s[sl, self._layout.nav_vel]
            if self.observation_kind in ("scene", "radar+nav")
            else None,
        )
        self._noise.for_boats(None)
        return obs

    def advance(self, actions: Any) -> tuple[FloatArray, FloatArray]:
        """Plant and navigation of one decision of every boat, nothing judged: the true
        trajectory (N, T, 13) (``BatchStep.trajectory``) and the heading changes Δψ (N,) rad.
        The boats' clocks advance; :meth:`step` is this plus the pole task's flags, reward and
        observation (the open-water batch judges its own scene)."""
        if not self._ready.all():
            raise RuntimeError("reset every boat before step()")
        check_interrupt()  # a Ctrl-C that a C extension swallowed ends the work here
        sc = self.scenario
        dpsi = heading_change_rad(
            self.action_kind, actions, self.n_boats, sc.max_heading_change_rad
        )
        T = sc.steps_per_decision
        psi_ref = ssa(self._est_psi + dpsi)
        # the same as plant.step then nav.run(..., self._rng_view(None), ...), fused in C
        first = self._plant_step + 1
        normals = self._noise.for_boats(None).standard_normal(
            (self.n_boats, self._navplant.draws_needed(first, T))
        )
        speed, current, gnss = self.disturbances.inputs(
            (self._n_decisions * sc.decision_period_s).astype(np.float64), sc.dt_s, T
        )
        w_in, w_normals = self._weather_inputs(T)  # None, None in a calm batch
        args: tuple[Any, ...]
        if speed is None:  # the study's call, unchanged
            args = (self._s, psi_ref, sc.speed_mps, T, first, normals, None, None, w_in, w_normals)
        else:
            layout = self._navplant.noise_steps(first, T, normals)
            fires = layout.factor[:, 1:5] > 0
            normals = self.disturbances.perturb_normals(normals, layout.index[:, 1:5][fires])
            args = (self._s, psi_ref, speed, T, first, normals, current, gnss, w_in, w_normals)
        lay = self._layout
        if w_in is None:
            packed = self._navplant.run(*args)
            self._s, traj = packed[:, -1].copy(), packed[:, :, lay.closed_loop]
        else:  # the weather states and the filter's are read at the last step only
            traj, self._s = self._navplant.run_recorded(*args)
        self._plant_step += T
        self._est_pos = self._s[:, lay.nav_pos].copy()
        self._est_psi = self._s[:, lay.nav_psi].copy()
        self._n_decisions += 1
        return traj, dpsi

    def _weather_inputs(self, n_steps: int) -> tuple[FloatArray | None, FloatArray | None]:
        """The weather plant's per-boat inputs and innovations for ``n_steps`` steps: 3 n_steps
        standard normals per boat drawn from its episode stream (after the filter's) for the
        boats with weather only, zeros for the others (their streams untouched); None, None in a
        calm batch."""
        if self._navplant.weather is None:
            return None, None
        assert self.disturbances.weather_inputs is not None
        normals = np.zeros((self.n_boats, 3 * n_steps))
        windy = np.flatnonzero(self.disturbances.weather_active)
        if windy.size:
            normals[windy] = self._noise.for_boats(windy).standard_normal((windy.size, 3 * n_steps))
            self._noise.for_boats(None)
        return self.disturbances.weather_inputs, normals

    def step(self, actions: Any) -> BatchStep:
        """One decision step of every boat (see the module docstring)."""
        traj, dpsi = self.advance(actions)
        sc = self.scenario
        T = sc.steps_per_decision
        x_n, y_e = traj[:, :, 0], traj[:, :, 1]  # true position at every plant step (N, T)
        d_pole = np.hypot(x_n - self.pole_ne[:, 0:1], y_e - self.pole_ne[:, 1:2])
        hit = d_pole < self._collision_m
        dx_goal, dy_goal = x_n - self.goal_ne[:, 0:1], y_e - self.goal_ne[:, 1:2]
        in_goal = within_radius(dx_goal, dy_goal, sc.goal_radius_m)
        collision, reached = np.any(hit, axis=1), np.any(in_goal, axis=1)
        terminated = reached | collision
        # a terminated episode ends at its first event step; the rest of the period is discarded
        end = np.where(terminated, np.argmax(hit | in_goal, axis=1), T - 1)
        upto_end = d_pole
        if terminated.any():
            upto_end = np.where(np.arange(T) > end[:, None], np.inf, d_pole)
        self._min_pole = np.minimum(self._min_pole, upto_end.min(axis=1))
        if reached.any():  # the decision that just ended: the clock's value before advance
            t_first = ((self._n_decisions - 1) * T + np.argmax(in_goal, axis=1) + 1) * sc.dt_s
            self._t_goal = np.where(reached & np.isinf(self._t_goal), t_first, self._t_goal)
        rows = np.arange(self.n_boats)
        d_pole_end = d_pole[rows, end]
        d_goal_end = np.hypot(dx_goal[rows, end], dy_goal[rows, end])
        out_of_area = d_pole_end > sc.area_radius_m
        time_limit = self._n_decisions >= sc.max_decisions
        terms = self.reward(d_pole_end, d_goal_end)
        return BatchStep(
            observation=self._observe(),
            reward=terms.total,
            terms=terms,
            terminated=terminated,
            truncated=(time_limit | out_of_area) & ~terminated,
            heading_change_rad=dpsi,
            distance_to_pole_m=d_pole_end,
            distance_to_goal_m=d_goal_end,
            min_distance_to_pole_m=self._min_pole.copy(),
            reached_goal=reached,
            collision=collision,
            out_of_area=out_of_area,
            time_limit=time_limit,
            is_success=reached & ~collision & (self._min_pole >= sc.safety_distance_m),
            time_s=(self._n_decisions * sc.decision_period_s).astype(np.float64),
            time_to_goal_s=self._t_goal.copy(),
            trajectory=traj,
            end_step=end + 1,
            est_pos_ne=self._est_pos.copy(),
            est_psi_rad=self._est_psi.copy(),
        )


def observation_rows(obs: Observation, idx: Any) -> Observation:
    """Rows ``idx`` of a batched observation (array or dict of arrays), as copies."""
    if isinstance(obs, dict):
        return {k: v[idx].copy() for k, v in obs.items()}
    return obs[idx].copy()


def write_observation_rows(obs: Observation, idx: NDArray[np.intp], rows: Observation) -> None:
    if isinstance(obs, dict):
        assert isinstance(rows, dict)
        for k in obs:
            obs[k][idx] = rows[k]
    else:
        assert not isinstance(rows, dict)
        obs[idx] = rows
