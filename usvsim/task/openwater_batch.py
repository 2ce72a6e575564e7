"""N boats on open-water episodes (:mod:`usvsim.task.openwater`), stepped together.

:class:`OpenWaterBatch` drives a :class:`usvsim.task.batch.PoleAvoidanceBatch` (the plant, the
navigation filter, the noise streams, the per-boat disturbances: the one task step) and judges
the scene itself, the way the waypoint courses do (:mod:`usvsim.task.waypoints`):

* the inner batch starts each boat from the episode's start (its ``EpisodeSpec`` relative to the
  episode's anchor, so a study episode starts exactly as in the pole task) with the episode's
  :class:`usvsim.task.disturbance.EpisodeDisturbance`; its own pole/goal flags are ignored;
* every 0.1 s plant step of the returned true trajectory is checked against every static disc
  and every vessel (at its position at that step): collision, the pole-equivalent distance
  ``|p − c| − R + R_pole`` (the success rule of :mod:`usvsim.task.openwater`), the goal;
  no Python loop over boats, obstacles or steps (:mod:`usvsim.task.scene_distances`: one
  compiled call, or the NumPy reference with the CasADi plant or without a C compiler);
* observations come from the navigation estimate: ``positional`` reports the obstacle nearest
  by pole-equivalent distance as the study's pole ([r_eq, φ, r_goal, φ_goal]; no obstacle: a
  pole 1 km astern); ``radar`` / ``radar+goal`` draw every disc at its true extent
  (:mod:`usvsim.task.scene_radar`, with the episode's radar degradation); ``scene`` is the
  k-nearest form (:func:`usvsim.task.observations.scene_observation`).

On a study episode (:func:`usvsim.task.openwater.from_pole_episodes`) with the positional
observation, the records equal the pole task's (tested).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from usvsim.task.batch import ActionKind, PoleAvoidanceBatch
from usvsim.task.observations import (
    GOAL_STANDARDIZATION,
    ObservationKind,
    nav_vector,
    observation_space,
    relative_polar,
    scene_observation,
)
from usvsim.task.openwater import OpenWaterEpisode, vessel_motion
from usvsim.task.radar import RadarConfig
from usvsim.task.scenario import EpisodeSpec, Scenario
from usvsim.task.scene_distances import PackedDiscs, judge_period, nearest_and_hits
from usvsim.task.scene_radar import RadarDegradation, RadarStreams, render_scene
from usvsim.vessel.plant import Plant

__all__ = ["NO_OBSTACLE_RANGE_M", "OpenWaterBatch", "OpenWaterStep", "SceneDiscs", "observe_scene"]

FloatArray = NDArray[np.float64]
NO_OBSTACLE_RANGE_M = 1000.0  # m, the positional observation's pole when nothing is around
_R_POLE = 1.0  # m, the study's pole: ranges are pole-equivalent (usvsim.task.openwater)


@dataclass(frozen=True)
class OpenWaterStep:
    """One decision step of N boats; arrays (N,) unless stated (true state, like BatchStep)."""

    observation: Any
    terminated: NDArray[np.bool_]  # reached_goal | collision
    truncated: NDArray[np.bool_]  # (time_limit | out_of_area) and not terminated
    heading_change_rad: FloatArray
    min_distance_m: FloatArray  # pole-equivalent, over every obstacle and plant step so far
    distance_to_obstacle_m: FloatArray  # pole-equivalent, nearest obstacle at the end step
    period_nearest_m: FloatArray  # pole-equivalent, nearest over this period's plant steps
    distance_to_goal_m: FloatArray  # at the end step
    reached_goal: NDArray[np.bool_]
    collision: NDArray[np.bool_]
    out_of_area: NDArray[np.bool_]
    time_limit: NDArray[np.bool_]
    is_success: NDArray[np.bool_]
    time_to_goal_s: FloatArray  # inf if not yet
    trajectory: FloatArray  # (N, T, 13)
    end_step: NDArray[np.intp]


class OpenWaterBatch:
    """N boats on open-water episodes (module docstring); no autoreset.

    Parameters
    ----------
    n_boats : int
    observation : "positional" | "radar" | "radar+goal" | "scene"
    action : "gaussian" | "categorical"
    plant : Plant, optional
        Shared plant; default ``Plant("default")``.
    radar : RadarConfig, optional
        Image geometry (degradation comes from each episode).
    scenario : Scenario, optional
        Decision period, plant step and action bound (default the study's: 2 s, 0.1 s, ±30°);
        a shorter period lets a helmsman steer more often (the human-like expert, 0.2 s). The
        episodes bring everything else.
    """

    def __init__(
        self,
        n_boats: int,
        *,
        observation: ObservationKind = "positional",
        action: ActionKind = "gaussian",
        plant: Plant | None = None,
        radar: RadarConfig | None = None,
        backend: Literal["auto", "compiled", "casadi"] = "auto",
        scenario: Scenario | None = None,
    ) -> None:
        self.n_boats = n_boats
        self.observation_kind = observation
        self.single_observation_space = observation_space(observation, radar)
        self.radar = radar or RadarConfig()
        self.base = replace(scenario or Scenario(), area_radius_m=1e9)
        self.inner = PoleAvoidanceBatch(
            n_boats, observation="positional", action=action, scenario=self.base, plant=plant,
            backend=backend,
        )  # fmt: skip
        self._radar_streams = RadarStreams(n_boats)
        self._r_pole = self.base.pole_radius_m
        self._half_beam = self.inner.plant.vessel.half_beam_m
        # the compiled distances; the NumPy reference along with the CasADi plant
        self._distance_backend: Literal["auto", "numpy"] = (
            "numpy" if backend == "casadi" else "auto"
        )
        self._set_scene(list(range(n_boats)), [])
        self._n_dec = np.zeros(n_boats, dtype=np.int64)
        self._min_d = np.full(n_boats, np.inf)
        self._t_goal = np.full(n_boats, np.inf)

    def _set_scene(self, boats: Sequence[int], episodes: Sequence[OpenWaterEpisode]) -> None:
        """Pack the episodes' obstacles and vessels into padded per-boat arrays."""
        n = self.n_boats
        if not episodes:
            self.centres, self.radii = np.zeros((n, 0, 2)), np.zeros((n, 0))
            self.static_ok = np.zeros((n, 0), dtype=bool)
            self.v_p0, self.v_course = np.zeros((n, 0, 2)), np.zeros((n, 0))
            self.v_speed, self.v_turn, self.v_radius = (np.zeros((n, 0)) for _ in range(3))
            self.vessel_ok = np.zeros((n, 0), dtype=bool)
            self.goal_ne, self.area_ne = np.zeros((n, 2)), np.zeros((n, 2))
            self.area_radius, self.time_limit = np.full(n, np.inf), np.full(n, np.inf)
            zeros = np.zeros(n)
            self.degradation = RadarDegradation(zeros, zeros, zeros, zeros)
            self._pack_scene()
            return
        k = max(max((len(e.obstacles) for e in episodes), default=0), self.centres.shape[1])
        m = max(max((len(e.vessels) for e in episodes), default=0), self.v_p0.shape[1])
        self.centres, self.radii = _pad(self.centres, k), _pad(self.radii, k)
        self.static_ok = _pad(self.static_ok, k)
        self.v_p0, self.v_course = _pad(self.v_p0, m), _pad(self.v_course, m)
        self.v_speed, self.v_turn = _pad(self.v_speed, m), _pad(self.v_turn, m)
        self.v_radius, self.vessel_ok = _pad(self.v_radius, m), _pad(self.vessel_ok, m)
        q = self.degradation
        cl, sp, mi, no = (a.copy() for a in (q.clutter_probability, q.speckle,
                                             q.missed_probability, q.noise_amplitude))  # fmt: skip
        for i, e in zip(boats, episodes, strict=True):
            obs = np.array(e.obstacles, dtype=float).reshape(-1, 3)
            self.static_ok[i] = False
            self.static_ok[i, : len(obs)] = True
            self.centres[i, : len(obs)], self.radii[i, : len(obs)] = obs[:, :2], obs[:, 2]
            self.vessel_ok[i] = False
            self.vessel_ok[i, : len(e.vessels)] = True
            for j, v in enumerate(e.vessels):
                self.v_p0[i, j] = (v.x0_n, v.y0_e)
                self.v_course[i, j], self.v_speed[i, j] = v.course_rad, v.speed_mps
                self.v_turn[i, j], self.v_radius[i, j] = v.turn_rate_radps, v.radius_m
            self.goal_ne[i], self.area_ne[i] = e.goal_ne, e.anchor_ne
            self.area_radius[i], self.time_limit[i] = e.area_radius_m, e.time_limit_s
            cl[i], sp[i] = e.radar.clutter_probability, e.radar.speckle
            mi[i], no[i] = e.radar.missed_probability, e.radar.noise_amplitude
        self.degradation = RadarDegradation(cl, sp, mi, no)
        self._pack_scene()

    def _pack_scene(self) -> None:
        """Every disc's radius and validity (N, J), statics then vessels: constant within an
        episode, so joined once per reset, not per step (a caller that steers the vessels, as
        :mod:`usvsim.evaluation.colreg_rollout` does, replaces their motion arrays only)."""
        self._disc_radii = np.concatenate([self.radii, self.v_radius], axis=1)
        self._disc_ok = np.concatenate([self.static_ok, self.vessel_ok], axis=1)

    def reset(self, boats: NDArray[np.intp] | None, episodes: Sequence[OpenWaterEpisode]) -> Any:
        """Start ``episodes`` on ``boats`` (None: all); returns their first observation."""
        idx = np.arange(self.n_boats) if boats is None else np.asarray(boats, dtype=np.intp)
        if len(episodes) != idx.size:
            raise ValueError(f"need one episode per reset boat ({idx.size}), got {len(episodes)}")
        inner = self.inner
        # the starts are EpisodeSpecs relative to per-episode anchors: the inner scenario's poles
        # are the reset episodes' anchors, spec j naming pole j
        limit = max(float(self.time_limit[np.isfinite(self.time_limit)].max(initial=0.0)),
                    max(e.time_limit_s for e in episodes))  # fmt: skip
        inner.scenario = replace(
            inner.scenario, poles_ne=tuple(e.anchor_ne for e in episodes), time_limit_s=limit
        )
        specs = [  # e.start naming pole j (built directly: dataclasses.replace costs ~5 µs)
            EpisodeSpec(j, e.start.start_distance_m, e.start.start_bearing_rad,
                        e.start.heading_offset_rad, e.start.noise_seed)
            for j, e in enumerate(episodes)
        ]  # fmt: skip
        inner.start(idx, specs, [e.disturbance for e in episodes])  # the scene observes below
        inner.pole_ne[idx] = 1e9  # the inner single-pole flags are not used
        self._set_scene(idx.tolist(), episodes)
        inner.goal_ne[idx] = self.goal_ne[idx]
        self._radar_streams.seed(idx.tolist(), [e.radar_seed for e in episodes])
        pos = inner.state.x[idx, 0:2]
        self._n_dec[idx] = 0
        d0, _ = self._nearest_and_hits(pos[:, None, :], np.zeros((idx.size, 1)), idx)
        self._min_d[idx] = d0[:, 0]
        self._t_goal[idx] = np.inf
        return self._observe(idx)

    def _discs_at(
        self, t_s: FloatArray, idx: Any = slice(None)
    ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
        """Every disc of boats ``idx`` at their episode times ``t_s`` (n,): centres (n, J, 2),
        radii (n, J), velocities (n, J, 2), valid (n, J); statics first, then vessels (the
        vessels by :func:`usvsim.task.openwater.vessel_motion`)."""
        c = self.centres[idx]
        pos, vel = vessel_motion(
            self.v_p0[idx], self.v_course[idx], self.v_speed[idx], self.v_turn[idx],
            t_s[:, None],
        )  # fmt: skip
        centres = np.concatenate([c, pos], axis=1)
        velocity = np.concatenate([np.zeros_like(c), vel], axis=1)
        return centres, self._disc_radii[idx], velocity, self._disc_ok[idx]

    def scene_at(
        self, t_s: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
        """Every boat's discs at its own episode time ``t_s`` (N,) s: centres (N, J, 2) m, radii
        (N, J) m, velocities over ground (N, J, 2) m/s, valid (N, J); statics, then vessels."""
        return self._discs_at(np.asarray(t_s, dtype=float))

    def _nearest_and_hits(
        self, pos: FloatArray, t_s: FloatArray, idx: Any = slice(None)
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Smallest pole-equivalent distance (n, T) m and any-hit flags (n, T) of boats ``idx``
        at positions ``pos`` (n, T, ≥ 2) and episode times ``t_s`` (n, T)
        (:func:`usvsim.task.scene_distances.nearest_and_hits`)."""
        return nearest_and_hits(
            pos, t_s, self._discs_now(idx), self._r_pole, self._half_beam,
            self._distance_backend,
        )  # fmt: skip

    def _discs_now(self, idx: Any = slice(None)) -> PackedDiscs:
        """The discs of boats ``idx`` as the distance kernels take them (all: views, no
        copies; read now, since a caller may steer the vessels between steps)."""
        arrays = (self.centres, self.radii, self.static_ok, self.v_p0, self.v_course,
                  self.v_speed, self.v_turn, self.v_radius, self.vessel_ok)  # fmt: skip
        if not (isinstance(idx, slice) and idx == slice(None)):
            arrays = tuple(a[idx] for a in arrays)
        return PackedDiscs(*arrays)

    def observe(self, kind: ObservationKind) -> Any:
        """Every boat's ``kind`` observation now (the step's own is ``observation_kind``'s), from
        the same navigation estimate and scene: e.g. the true-scene ``scene`` form beside a
        radar policy's image, for an asymmetric learner. A radar kind draws the frame the
        step drew."""
        return self._observe(kind=kind)

    def _observe(
        self, idx: NDArray[np.intp] | None = None, kind: ObservationKind | None = None
    ) -> Any:
        sl: Any = slice(None) if idx is None else idx
        pos, psi = self.inner.estimate
        t = (self._n_dec[sl] * self.base.decision_period_s).astype(float)
        centres, radii, velocity, ok = self._discs_at(t, sl)
        q = self.degradation
        degr = RadarDegradation(
            q.clutter_probability[sl], q.speckle[sl], q.missed_probability[sl],
            q.noise_amplitude[sl],
        )  # fmt: skip
        return observe_scene(
            kind or self.observation_kind, pos[sl], psi[sl], self.inner.estimated_velocity[sl],
            self.goal_ne[sl], SceneDiscs(centres, radii, velocity, ok),
            self.radar, degr, self._radar_streams.frame_keys(sl),
        )  # fmt: skip

    def step(self, actions: Any) -> OpenWaterStep:
        """One decision step of every boat (module docstring)."""
        traj, dpsi = self.inner.advance(actions)
        sc = self.base
        T = sc.steps_per_decision
        steps = self._n_dec[:, None] * T + np.arange(1, T + 1)
        t: FloatArray = steps.astype(np.float64) * sc.dt_s  # (N, T) episode time
        judged = judge_period(
            traj, t, self._discs_now(), self.goal_ne, self._r_pole, self._half_beam,
            sc.goal_radius_m, self._distance_backend,
        )  # fmt: skip
        reached, collision = judged.reached_goal, judged.collision
        terminated: NDArray[np.bool_] = reached | collision
        end = judged.end_step
        self._min_d = np.minimum(self._min_d, judged.nearest_m)
        first = (self._n_dec * T + judged.first_goal_step + 1) * sc.dt_s
        self._t_goal = np.where(reached & np.isinf(self._t_goal), first, self._t_goal)
        self._n_dec += 1
        rows = np.arange(self.n_boats)
        end_pos = traj[rows, end, 0:2]
        out_of_area = np.hypot(*(end_pos - self.area_ne).T) > self.area_radius
        time_limit = self._n_dec * sc.decision_period_s >= self.time_limit - 1e-9
        return OpenWaterStep(
            observation=self._observe(),
            terminated=terminated,
            truncated=(time_limit | out_of_area) & ~terminated,
            heading_change_rad=dpsi,
            min_distance_m=self._min_d.copy(),
            distance_to_obstacle_m=judged.distance_to_obstacle_m,
            period_nearest_m=judged.nearest_m,
            distance_to_goal_m=judged.distance_to_goal_m,
            reached_goal=reached,
            collision=collision,
            out_of_area=out_of_area,
            time_limit=time_limit,
            is_success=reached & ~collision & (self._min_d >= sc.safety_distance_m),
            time_to_goal_s=self._t_goal.copy(),
            trajectory=traj,
            end_step=end + 1,
        )


@dataclass(frozen=True)
class SceneDiscs:
    """What N boats have around them at one time: centres (N, J, 2) m, radii (N, J) m, velocities
    over ground (N, J, 2) m/s, valid (N, J)."""

    centres_ne: FloatArray
    radii_m: FloatArray
    velocity_ne: FloatArray
    valid: NDArray[np.bool_]


def observe_scene(
    kind: ObservationKind,
    pos_ne: FloatArray,
    psi_rad: FloatArray,
    velocity_ne: FloatArray,
    goal_ne: FloatArray,
    discs: SceneDiscs,
    radar: RadarConfig | None = None,
    degradation: RadarDegradation | None = None,
    keys: NDArray[np.uint64] | None = None,
) -> Any:
    """The ``kind`` observation of N boats at poses ``pos_ne`` (N, 2), ``psi_rad`` (N,) with
    velocity over ground (N, 2) m/s, goals (N, 2) and ``discs`` around them: ``scene`` (the
    k-nearest form), ``positional`` (the nearest disc, pole-equivalent range, in the pole's
    slot; :data:`NO_OBSTACLE_RANGE_M` without one), ``radar`` or ``radar+goal`` (every disc,
    ``degradation`` drawing from the boats' frame ``keys``;
    :func:`usvsim.task.scene_radar.render_scene`). The open-water step's observation, and the
    demonstrations' (:mod:`learning.imitation.preprocess`).
    """
    c, radii, ok = discs.centres_ne, discs.radii_m, discs.valid
    if kind == "scene":
        return scene_observation(
            pos_ne, psi_rad, velocity_ne, goal_ne, c, radii, discs.velocity_ne, ok
        )
    r, b = relative_polar(pos_ne, psi_rad, c)
    if kind == "positional":
        n = len(pos_ne)
        r_eq = np.where(ok, r + (_R_POLE - radii), np.inf)
        j = np.argmin(r_eq, axis=1) if r_eq.shape[1] else np.zeros(n, dtype=np.intp)
        rows = np.arange(n)
        none = ~np.isfinite(r_eq[rows, j]) if r_eq.shape[1] else np.ones(n, dtype=bool)
        r_g, b_g = relative_polar(pos_ne, psi_rad, goal_ne)
        out = np.empty((n, 4), dtype=np.float32)
        out[:, 0] = np.where(none, NO_OBSTACLE_RANGE_M, r_eq[rows, j] if r.shape[1] else 0.0)
        out[:, 1] = np.where(none, -math.pi, b[rows, j] if r.shape[1] else 0.0)
        out[:, 2], out[:, 3] = r_g, b_g
        return out
    image = render_scene(r, b, radii, ok, radar, degradation, keys)
    if kind == "radar":
        return image
    r_g, b_g = relative_polar(pos_ne, psi_rad, goal_ne)
    goal = GOAL_STANDARDIZATION.apply(np.stack([r_g, b_g], -1))
    if kind == "radar+nav":
        return {"radar": image, "goal": goal, "nav": nav_vector(pos_ne, psi_rad, velocity_ne)}
    return {"radar": image, "goal": goal}


def _pad(a: NDArray[Any], width: int) -> NDArray[Any]:
    """``a`` (N, k, ...) padded with zeros / False along axis 1 to ``width``."""
    if a.shape[1] >= width:
        return a
    pad = np.zeros((a.shape[0], width - a.shape[1], *a.shape[2:]), dtype=a.dtype)
    return np.concatenate([a, pad], axis=1)
