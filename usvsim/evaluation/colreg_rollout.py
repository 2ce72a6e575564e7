"""Open-water episodes recorded for COLREG scoring, with target vessels that may react.

:func:`run_encounters` runs a helmsman on a set of open-water episodes
(:func:`usvsim.evaluation.openwater.evaluate_open_water`, one batch) and returns the records
with the own ship's and every target vessel's track sampled every ``sample_s`` seconds as
:class:`usvsim.evaluation.colreg.EncounterTracks` (shapes: E episodes, K targets, T samples)::

    own_north_east_m (E, T, 2)     own_course_rad, own_speed_mps (E, T): over ground
    target_north_east_m (E, K, T, 2)   target_course_rad, target_speed_mps (E, K, T)
    valid (E, T): sample inside the episode     target_valid (E, K): a vessel in that slot

The own course and speed over ground are central differences of the true 0.1 s trajectory
(one-sided at the ends). Target tracks come from each vessel's motion law
(:func:`usvsim.task.openwater.vessel_motion`), with its parameters as they were during each
decision period when the targets react. No Python loop over boats or targets in the sampling.

Reactive targets (``reactive_targets=True``): after every decision each target vessel is steered
by the project's ``vo`` helmsman (Kuwata et al. 2014, :mod:`baselines.velocity_obstacle`, its
COLREG rule 14/15 terms on) from a ``scene`` observation of its own: the own ship (true state,
radius half the beam of a 10.5 m hull rounded up to 5 m) and the other targets and obstacles of
its episode, its goal far ahead on its initial course (it resumes that course once clear). The
A target that is the give-way vessel to the own ship (rules 15-16 from its side: the own ship on
its starboard bow and a risk of collision) steers instead for a point behind the own ship's stern
until the own ship is abaft its beam (:meth:`ReactiveTargets._give_way`): ``vo`` alone kept clear
but crossed ahead in a third of the stand-on crossings measured (Imazu 4 and trafficgen CR-SO,
25 episodes), as its COLREG term only acts while the present course is inside the velocity
obstacle. The target's course becomes its course plus the chosen heading change (at most ±30°
per 2 s decision, the task's own bound), applied at the decision instant; its speed is kept.
Its motion is re-anchored so its position is continuous: ``p0 ← p(t) − U t (cos χ, sin χ)``
with the new course χ and zero turn rate. The helmsman then sees the scene as it is after the
targets' choice.

Cost (issue 41): every target of every boat is one batch through ``vo`` (rows: the occupied
target slots only, when the helmsman's ``act`` takes ``boats``), whose candidate-by-obstacle
terms run in C (:mod:`baselines.vo_kernel`, bit for bit its NumPy path); the give-way rule is
array code. CPU time a decision, ``nice python benchmarks/colreg_reward_cost.py --n N --steps S
--reactive --reference`` (radar+goal, training family, 2026-12-06, load 5.6-6.2 on 2 cores; the
reference env steers as before: vo's NumPy path on every slot, in the same run)::

    N     env step    reactive targets    before (NumPy vo, every slot)
    64    2.66 ms     3.26 ms (1.2x)      111 ms (42x)        S = 50
    256   6.20 ms     13.9 ms (2.2x)      811 ms (131x)       S = 20

Before, the profile (cProfile, N = 256) put 99 % of the hook in ``vo_course``'s (N·M, C, S, K, 2)
NumPy arrays (1,024 target rows × 120 candidates × 6 arc samples × 8 slots), 59 % of the rows
empty slots; the targets' observations and the give-way rule under 1 %, and no Python loop.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.openwater import OpenWaterEpisode, vessel_motion
from usvsim.task.openwater_batch import OpenWaterBatch, SceneDiscs, observe_scene

__all__ = [
    "EncounterRun",
    "ReactiveTargets",
    "TrainingReactiveTargets",
    "encounter_tracks",
    "run_encounters",
]

FloatArray = NDArray[np.float64]
OWN_RADIUS_M = 5.0  # m, the own ship as the targets see it (a 10 m hull's disc, as theirs)
GOAL_AHEAD_M = 10_000.0  # m, a reactive target's goal: this far along its initial course
SECTOR_RAD = np.radians(112.5)  # rad, 22.5° abaft the beam (COLREG rule 13)
CROSS_MIN_RAD = np.radians(22.5)  # rad, courses within this of parallel or opposite: no crossing
GIVE_WAY_CPA_M = 50.0  # m, closest approach that is a risk of collision (usvsim's choice: vo's
# 25 m margin around two 5 m hulls plus a margin; the scorer's preferred passing distance
# is of that order for a 10 m boat)
GIVE_WAY_TCPA_S = 90.0  # s, risk assessed this far ahead (the Imazu targets meet after ~100 s)
ASTERN_CLEARANCE_M = 30.0  # m, a give-way target aims this far behind the own ship's stern


Schedule = list[tuple[FloatArray, FloatArray, FloatArray]]


@dataclass(frozen=True)
class EncounterRun:
    """Records (:class:`usvsim.evaluation.openwater.OpenWaterRecord`) and their tracks;
    ``schedule`` the reactive vessels' motion per decision period (None: not reactive)."""

    records: list[Any]
    tracks: Any  # usvsim.evaluation.colreg.EncounterTracks
    schedule: Schedule | None = None
    sample_s: float = 1.0

    def part(self, episodes: slice) -> EncounterRun:
        """The run of a contiguous part of its episodes (tracks recomputed for that part), so
        that several sets can share one batch."""
        schedule = None
        if self.schedule is not None:
            schedule = [(p[episodes], c[episodes], t[episodes]) for p, c, t in self.schedule]
        records = self.records[episodes]
        return EncounterRun(
            records, encounter_tracks(records, self.sample_s, schedule), schedule, self.sample_s
        )


class ReactiveTargets:
    """Steers every target vessel of an :class:`OpenWaterBatch` with ``vo`` (module docstring).

    Call as the ``on_decision`` hook of :func:`usvsim.evaluation.openwater.evaluate_open_water`;
    :attr:`schedule` holds the vessels' motion parameters for each decision period.
    """

    def __init__(self, sim: OpenWaterBatch, helmsman: Any) -> None:
        self.sim = sim
        n, m = sim.vessel_ok.shape
        self.n, self.m = n, m
        self.helmsman = helmsman
        self.helmsman.reset(n * m)
        # a helmsman that can act for some of its boats is asked for the vessels present only
        self.by_rows = "boats" in inspect.signature(helmsman.act).parameters
        pos0, _ = vessel_motion(sim.v_p0, sim.v_course, sim.v_speed, sim.v_turn, np.zeros((n, m)))
        u = np.stack([np.cos(sim.v_course), np.sin(sim.v_course)], axis=-1)
        self.goal_ne = pos0 + GOAL_AHEAD_M * u  # (N, M, 2)
        self.schedule: list[tuple[FloatArray, FloatArray, FloatArray]] = [
            (sim.v_p0.copy(), sim.v_course.copy(), sim.v_turn.copy())
        ]
        self.giving_way = np.zeros((n, m), dtype=bool)  # latched per target (rule 15/16)

    def _give_way(
        self,
        own_p: FloatArray,
        own_v: FloatArray,
        pos: FloatArray,
        vel: FloatArray,
        chi: FloatArray,
    ) -> FloatArray:
        """Update :attr:`giving_way` and return each target's course to pass astern (rad).

        A target gives way (rules 15-16, its own view) while the own ship is on its starboard
        side forward of 22.5° abaft the beam (0 < β < 112.5°, Rule 13's sector), their courses
        cross (22.5° < |Δχ| < 157.5°: not head-on, not overtaking) and its straight-line closest
        approach is nearer than ``GIVE_WAY_CPA_M`` within ``GIVE_WAY_TCPA_S``; it holds that until
        the own ship is abaft its beam (|β| > 112.5°). It then steers for a point
        ``ASTERN_CLEARANCE_M`` behind the own ship's stern, which takes it astern.
        """
        rel = own_p[:, None, :] - pos  # (N, M, 2): target → own ship
        beta = ssa(np.arctan2(rel[..., 1], rel[..., 0]) - chi)
        chi_own = np.arctan2(own_v[:, 1], own_v[:, 0])[:, None]
        d_chi = np.abs(ssa(chi_own - chi))
        w = own_v[:, None, :] - vel  # own velocity relative to the target
        ww = np.maximum(np.sum(w * w, axis=-1), 1e-9)
        tcpa = -np.sum(rel * w, axis=-1) / ww
        cpa = np.hypot(*np.moveaxis(rel + w * np.clip(tcpa, 0.0, None)[..., None], -1, 0))
        enters = (
            (beta > 0.0) & (beta < SECTOR_RAD) & (d_chi > CROSS_MIN_RAD)
            & (d_chi < np.pi - CROSS_MIN_RAD) & (tcpa > 0.0) & (tcpa < GIVE_WAY_TCPA_S)
            & (cpa < GIVE_WAY_CPA_M)
        )  # fmt: skip
        self.giving_way = self.sim.vessel_ok & (
            enters | (self.giving_way & (np.abs(beta) < SECTOR_RAD))
        )
        speed = np.maximum(np.hypot(own_v[:, 0], own_v[:, 1]), 1e-6)[:, None, None]
        stern = own_p[:, None, :] - ASTERN_CLEARANCE_M * own_v[:, None, :] / speed
        to = stern - pos
        return np.arctan2(to[..., 1], to[..., 0])

    @staticmethod
    def _own(sim: OpenWaterBatch) -> tuple[FloatArray, FloatArray]:
        """The own ships' true positions (N, 2) m and velocities over ground (N, 2) m/s."""
        x = sim.inner.state.x
        c, s = np.cos(x[:, 2]), np.sin(x[:, 2])
        return x[:, 0:2], np.stack([c * x[:, 3] - s * x[:, 4], s * x[:, 3] + c * x[:, 4]], -1)

    def __call__(self, sim: OpenWaterBatch, k: int) -> Any:
        """Steer the targets at the end of decision ``k``; return the helmsman's observation."""
        if self.m == 0:
            self.schedule.append(self.schedule[-1])
            return None
        self.steer(sim, np.full((self.n, 1), (k + 1) * sim.base.decision_period_s))
        self.schedule.append((sim.v_p0.copy(), sim.v_course.copy(), sim.v_turn.copy()))
        return sim.observe(sim.observation_kind)

    def steer(self, sim: OpenWaterBatch, t: FloatArray) -> None:
        """Steer every target at its boat's episode time ``t`` (N, 1) s (module docstring):
        the vessels' motion arrays of ``sim`` replaced from that time on."""
        n, m = self.n, self.m
        tt = np.broadcast_to(t, (n, m))
        pos, vel = vessel_motion(sim.v_p0, sim.v_course, sim.v_speed, sim.v_turn, tt)
        chi = sim.v_course + sim.v_turn * t
        bound = sim.base.max_heading_change_rad
        turn = np.zeros(n * m)
        if self.by_rows:  # the vessels present only: empty slots' turns are discarded below
            rows = np.flatnonzero(sim.vessel_ok.reshape(-1))
            if rows.size:
                obs = self._observations(sim, pos, vel, chi, rows)
                turn[rows] = np.asarray(self.helmsman.act(obs, rows), dtype=np.float64).ravel()
        else:
            obs = self._observations(sim, pos, vel, chi, np.arange(n * m))
            turn = np.asarray(self.helmsman.act(obs), dtype=np.float64).ravel()
        turn = turn.reshape(n, m) * bound
        own_p, own_v = self._own(sim)
        aim = self._give_way(own_p, own_v, pos, vel, chi)
        turn = np.where(self.giving_way, np.clip(ssa(aim - chi), -bound, bound), turn)
        new_chi = chi + turn
        new_chi = np.where(sim.vessel_ok, ssa(new_chi), 0.0)
        u = np.stack([np.cos(new_chi), np.sin(new_chi)], axis=-1)
        sim.v_p0 = np.where(sim.vessel_ok[..., None], pos - (sim.v_speed * t)[..., None] * u, 0.0)
        sim.v_course = new_chi
        sim.v_turn = np.zeros_like(sim.v_turn)

    def restart(self, sim: OpenWaterBatch, boats: NDArray[np.intp]) -> None:
        """``boats`` started new episodes (training, :class:`TrainingReactiveTargets`): their
        targets' goals from their new starts, no target giving way; the slots grow with the
        batch's (``vo``'s per-target memory is kept: at most one stale decision per slot)."""
        n, m = sim.vessel_ok.shape
        if m != self.m:
            grow = ((0, 0), (0, m - self.m))
            self.goal_ne = np.pad(self.goal_ne, (*grow, (0, 0)))
            self.giving_way = np.pad(self.giving_way, grow)
            self.m = m
            self.helmsman.reset(n * m)
        pos0, _ = vessel_motion(sim.v_p0[boats], sim.v_course[boats], sim.v_speed[boats],
                                sim.v_turn[boats], np.zeros((len(boats), m)))  # fmt: skip
        u = np.stack([np.cos(sim.v_course[boats]), np.sin(sim.v_course[boats])], axis=-1)
        self.goal_ne[boats] = pos0 + GOAL_AHEAD_M * u
        self.giving_way[boats] = False

    def _observations(
        self,
        sim: OpenWaterBatch,
        pos: FloatArray,
        vel: FloatArray,
        chi: FloatArray,
        rows: NDArray[np.intp],
    ) -> NDArray[np.float32]:
        """``scene`` observations (R, ...) of the targets ``rows`` (R,) of the N·M flattened
        slots: the own ship first, then the other targets of its episode, then its static
        obstacles."""
        n, m = self.n, self.m
        own_p, own_v = self._own(sim)
        k_static = sim.centres.shape[1]
        centres = np.concatenate(
            [
                np.broadcast_to(own_p[:, None, None], (n, m, 1, 2)),
                np.broadcast_to(pos[:, None], (n, m, m, 2)),
                np.broadcast_to(sim.centres[:, None], (n, m, k_static, 2)),
            ],
            axis=2,
        )
        velocity = np.concatenate(
            [
                np.broadcast_to(own_v[:, None, None], (n, m, 1, 2)),
                np.broadcast_to(vel[:, None], (n, m, m, 2)),
                np.zeros((n, m, k_static, 2)),
            ],
            axis=2,
        )
        radii = np.concatenate(
            [
                np.full((n, m, 1), OWN_RADIUS_M),
                np.broadcast_to(sim.v_radius[:, None], (n, m, m)),
                np.broadcast_to(sim.radii[:, None], (n, m, k_static)),
            ],
            axis=2,
        )
        others = sim.vessel_ok[:, None, :] & ~np.eye(m, dtype=bool)[None]
        valid = np.concatenate(
            [
                np.broadcast_to(sim.vessel_ok[:, :, None], (n, m, 1)),
                others,
                np.broadcast_to(sim.static_ok[:, None], (n, m, k_static)),
            ],
            axis=2,
        )
        j = valid.shape[2]
        discs = SceneDiscs(
            centres.reshape(n * m, j, 2)[rows], radii.reshape(n * m, j)[rows],
            velocity.reshape(n * m, j, 2)[rows], valid.reshape(n * m, j)[rows],
        )  # fmt: skip
        return observe_scene(
            "scene", pos.reshape(-1, 2)[rows], chi.reshape(-1)[rows], vel.reshape(-1, 2)[rows],
            self.goal_ne.reshape(-1, 2)[rows], discs,
        )  # fmt: skip


class TrainingReactiveTargets:
    """Reactive targets in training: the ``on_decision`` hook of
    :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` (:class:`ReactiveTargets` at each
    boat's own episode time, restarted per boat when it starts an episode). ``target_helmsman``:
    what steers them (default ``vo`` from the registry)."""

    def __init__(self, target_helmsman: Any = None) -> None:
        self.target_helmsman = target_helmsman
        self.targets: ReactiveTargets | None = None

    def reset(self, sim: OpenWaterBatch, boats: NDArray[np.intp]) -> None:
        """``boats`` of ``sim`` started new episodes."""
        if self.targets is None:
            from usvsim.helm.registry import make_helmsman

            self.targets = ReactiveTargets(sim, self.target_helmsman or make_helmsman("vo"))
        self.targets.restart(sim, boats)

    def steer(self, sim: OpenWaterBatch, time_s: FloatArray) -> bool:
        """Steer every target at its boat's episode time ``time_s`` (N,) s; False (nothing
        changed) without targets."""
        if self.targets is None or self.targets.m == 0:
            return False
        self.targets.steer(sim, np.asarray(time_s, dtype=float)[:, None])
        return True


def run_encounters(
    helmsman: Any,
    episodes: Sequence[OpenWaterEpisode],
    *,
    reactive_targets: bool = False,
    sample_s: float = 1.0,
    target_helmsman: Any = None,
) -> EncounterRun:
    """Run ``helmsman`` on ``episodes`` and record the tracks (module docstring).

    ``target_helmsman``: what steers reactive targets (default ``vo`` from the registry).
    """
    from usvsim.evaluation.openwater import evaluate_open_water
    from usvsim.helm.registry import helmsman_kinds, make_helmsman

    obs_kind, act_kind = helmsman_kinds(helmsman)
    hook: dict[str, ReactiveTargets] = {}

    def on_decision(sim: OpenWaterBatch, k: int) -> Any:
        if "r" not in hook:
            hook["r"] = ReactiveTargets(sim, target_helmsman or make_helmsman("vo"))
        return hook["r"](sim, k)

    records = evaluate_open_water(
        helmsman, episodes, observation=obs_kind, action=act_kind,
        on_decision=on_decision if reactive_targets else None,
    )  # fmt: skip
    schedule = hook["r"].schedule if "r" in hook else None
    return EncounterRun(records, encounter_tracks(records, sample_s, schedule), schedule, sample_s)


def encounter_tracks(
    records: Sequence[Any],
    sample_s: float = 1.0,
    schedule: Sequence[tuple[FloatArray, FloatArray, FloatArray]] | None = None,
    dt_s: float = 0.1,
    decision_period_s: float = 2.0,
) -> Any:
    """:class:`usvsim.evaluation.colreg.EncounterTracks` of open-water records (module
    docstring). ``schedule``: the vessels' (p0, course, turn rate) per decision period, as
    :class:`ReactiveTargets` keeps it; None: each episode's vessels as drawn."""
    from usvsim.evaluation.colreg import EncounterTracks

    stride = round(sample_s / dt_s)
    if stride < 1 or abs(stride * dt_s - sample_s) > 1e-9:
        raise ValueError(f"sample_s must be a positive multiple of {dt_s} s, got {sample_s}")
    e = len(records)
    lengths = np.array([len(r.trajectory) for r in records])
    steps = int(lengths.max())
    full = np.empty((e, steps, 2))
    for i, r in enumerate(records):  # ragged per-episode arrays into one padded block
        full[i, : lengths[i]] = r.trajectory[:, 0:2]
        full[i, lengths[i] :] = r.trajectory[-1, 0:2]
    idx = np.arange(0, steps, stride)
    lo, hi = np.maximum(idx - 1, 0), np.minimum(idx + 1, steps - 1)
    hi_i = np.minimum(hi[None, :], lengths[:, None] - 1)  # one-sided at each episode's end
    lo_i = np.minimum(lo[None, :], np.maximum(hi_i - 1, 0))
    rows = np.arange(e)[:, None]
    d = full[rows, hi_i] - full[rows, lo_i]
    span = np.maximum(hi_i - lo_i, 1)[..., None] * dt_s
    vel = d / span
    own = full[:, idx]
    valid = idx[None, :] < lengths[:, None]
    t = idx * dt_s  # (T,)
    episodes = [r.episode for r in records]
    p0, course, speed, turn, ok = _vessel_arrays(episodes)
    if schedule is None or ok.shape[1] == 0:
        pos, v = vessel_motion(
            p0[:, :, None], course[:, :, None], speed[:, :, None], turn[:, :, None],
            np.broadcast_to(t, (*ok.shape, t.size)),
        )  # fmt: skip
    else:
        seg = np.minimum((t // decision_period_s).astype(np.intp), len(schedule) - 1)
        sp0 = np.stack([s[0] for s in schedule])[seg][:, :e]  # (T, E, K, 2)
        sc = np.stack([s[1] for s in schedule])[seg][:, :e]
        st = np.stack([s[2] for s in schedule])[seg][:, :e]
        k = ok.shape[1]
        sp0, sc, st = sp0[:, :, :k], sc[:, :, :k], st[:, :, :k]
        tt = np.broadcast_to(t[:, None, None], sc.shape)
        pos, v = vessel_motion(sp0, sc, np.broadcast_to(speed, sc.shape), st, tt)
        pos, v = np.moveaxis(pos, 0, 2), np.moveaxis(v, 0, 2)  # (E, K, T, 2)
    return EncounterTracks(
        dt_s=sample_s,
        own_north_east_m=own,
        own_course_rad=np.arctan2(vel[..., 1], vel[..., 0]),
        own_speed_mps=np.hypot(vel[..., 0], vel[..., 1]),
        target_north_east_m=pos,
        target_course_rad=np.arctan2(v[..., 1], v[..., 0]),
        target_speed_mps=np.hypot(v[..., 0], v[..., 1]),
        valid=valid,
        target_valid=ok,
    )


def _vessel_arrays(
    episodes: Sequence[OpenWaterEpisode],
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
    """Each episode's vessels padded to K slots: p0 (E, K, 2), course, speed, turn (E, K), ok."""
    e, k = len(episodes), max((len(ep.vessels) for ep in episodes), default=0)
    table = np.zeros((e, k, 5))
    ok = np.zeros((e, k), dtype=bool)
    for i, ep in enumerate(episodes):  # per-episode dataclasses into arrays (not a hot path)
        for j, v in enumerate(ep.vessels):
            table[i, j] = (v.x0_n, v.y0_e, v.course_rad, v.speed_mps, v.turn_rate_radps)
            ok[i, j] = True
    return table[..., 0:2], table[..., 2], table[..., 3], table[..., 4], ok
