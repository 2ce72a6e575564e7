"""Expert-likeness in traffic: how closely a helmsman follows the COLREG expert on the same
encounters (issue 41, "IL against RL of the same observation").

The traffic counterpart of :mod:`usvsim.evaluation.likeness` (the study's pole) and
:mod:`usvsim.evaluation.family_likeness` (the open-water family). The expert (``sb-mpc`` on the
true scene, or the human-like SB-MPC expert of :mod:`baselines.sbmpc_expert`) and each helmsman
drive the SAME episodes; their recorded tracks (:class:`usvsim.evaluation.colreg.EncounterTracks`,
sampled every ``dt_s``, 1 s in the suite) are compared by the pure, vectorised functions here
(arrays over E episodes, K targets, T samples; no Python loop over episodes or targets):

=====================  ==========================================================================
metric                 definition
=====================  ==========================================================================
``path_distance_m``    symmetric mean closest-point distance between the own ship's two paths,
                       ½ (mean_{p∈P} d(p, E) + mean_{e∈E} d(e, P)), d(x, Y) the distance from
                       sample x to the polyline through Y's samples (m; lower is more alike).
                       The definition of :func:`usvsim.evaluation.likeness.chamfer_m` (the
                       "chamfer" distance, Barrow et al. 1977, "Parametric correspondence and
                       chamfer matching", IJCAI), to the polyline instead of its vertices, so
                       that 1 s samples lose nothing (tested equal to ``chamfer_m`` on dense
                       paths). Symmetric: a path cut short by a collision is far from the
                       expert's remainder. Timing does not count.
``sync_mean_m``,       lock-step Euclidean distance (Toohey & Duckham 2015, "Trajectory
``sync_max_m``         similarity measures", SIGSPATIAL Special 7(1)): |p(t) − e(t)| at equal
                       episode times t, each ship held at its last position after its episode
                       ended, over t up to the later end; its mean and maximum (m). Timing
                       counts: a slower detour on the same line is far.
``side``               per target, the side it is passed on: the sign of its relative bearing
                       β (+1: on the own ship's starboard side) at the sample of closest range
                       while the own ship's episode runs (the scorer's β:
                       :func:`usvsim.task.colreg_geometry.encounter_kinematics`, own course over
                       ground; :func:`usvsim.evaluation.likeness.pass_side`'s rule for a moving
                       target). 0 for an empty slot
``side_agreement``     share of the expert's scored encounters (the COLREG scorer's entry and
                       classification on the expert's run) whose target the helmsman passes on
                       the expert's side; higher is more alike. Wilson 95 % interval
=====================  ==========================================================================

Intervals of the mean distances: percentile bootstrap over episodes (:func:`mean_interval`,
seeded). Across seeds (checkpoints of one setup) the interquartile mean with rliable's interval
is :func:`usvsim.evaluation.seed_stats.iqm_with_interval`'s; the runner and its tables:
:mod:`usvsim.evaluation.colreg_likeness_bench`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.evaluation.stats import Proportion, proportion
from usvsim.task.colreg_geometry import EncounterType, encounter_kinematics

__all__ = [
    "BOOTSTRAP_REPS",
    "Estimate",
    "SideAgreement",
    "held_positions",
    "lockstep_distance_m",
    "mean_interval",
    "pass_sides",
    "path_distance_m",
    "side_agreement",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
BOOTSTRAP_REPS = 2000  # resamples of the per-episode means (a percentile interval's usual size)
BOOTSTRAP_SEED = 41  # the resampling's generator: the same distances give the same interval
CHUNK_ELEMENTS = 2_000_000  # (episode, sample, segment) triples per block: 8 MB an array


@dataclass(frozen=True)
class Estimate:
    """A mean with its 95 % interval (units of the quantity)."""

    mean: float
    ci95: tuple[float, float]
    n: int  # values it is the mean of

    def to_json(self) -> dict[str, Any]:
        return {"mean": self.mean, "ci95": list(self.ci95), "n": self.n}


def mean_interval(
    values: NDArray[np.floating], reps: int = BOOTSTRAP_REPS, seed: int = BOOTSTRAP_SEED
) -> Estimate:
    """The mean of ``values`` (n,) and its 95 % percentile-bootstrap interval over them (Efron &
    Tibshirani 1993, "An Introduction to the Bootstrap", §13.3), resampled in one array
    (reps, n) from ``numpy.random.default_rng(seed)``; NaN values are left out.

    >>> mean_interval(np.array([2.0, 2.0, 2.0]))
    Estimate(mean=2.0, ci95=(2.0, 2.0), n=3)
    """
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return Estimate(float("nan"), (float("nan"), float("nan")), 0)
    idx = np.random.default_rng(seed).integers(0, v.size, size=(reps, v.size))
    lo, hi = np.percentile(v[idx].mean(axis=1), [2.5, 97.5])
    return Estimate(float(v.mean()), (float(lo), float(hi)), int(v.size))


def held_positions(ne: FloatArray, valid: BoolArray, samples: int) -> FloatArray:
    """Positions (E, ``samples``, 2) from ``ne`` (E, T, 2) whose ``valid`` (E, T) samples are a
    prefix: each ship held at its last valid sample after it (the first sample where none is)."""
    n_valid = np.maximum(np.asarray(valid).sum(axis=1), 1)
    idx = np.minimum(np.arange(samples)[None, :], n_valid[:, None] - 1)
    idx = np.minimum(idx, ne.shape[1] - 1)
    return np.take_along_axis(np.asarray(ne, float), idx[..., None], axis=1)


def _to_polyline(p: FloatArray, q: FloatArray, q_valid: BoolArray) -> FloatArray:
    """Distance (E, Tp) m from each sample of ``p`` (E, Tp, 2) to the polyline through the valid
    samples of ``q`` (E, Tq, 2) (segment j from q_j to q_{j+1}, a point at the last one).

    The (E, Tp, Tq) search runs in float32 on x and y apart, in place (6x faster than float64
    pairs on 2 cores; rounding < 0.1 mm at 1 km from the start, identical paths still 0)."""
    p32, q32 = p.astype(np.float32), q.astype(np.float32)
    nxt_ok = np.concatenate([q_valid[:, 1:], np.zeros_like(q_valid[:, :1])], axis=1)
    q_next = np.concatenate([q32[:, 1:], q32[:, -1:]], axis=1)
    seg = np.where(nxt_ok[..., None], q_next, q32) - q32  # the last valid sample: a point
    sx, sy = seg[:, None, :, 0], seg[:, None, :, 1]  # (E, 1, Tq)
    inv_len2 = 1.0 / np.maximum(sx * sx + sy * sy, np.float32(1e-12))
    rx = p32[:, :, None, 0] - q32[:, None, :, 0]  # (E, Tp, Tq): from segment start to sample
    ry = p32[:, :, None, 1] - q32[:, None, :, 1]
    s = rx * sx
    s += ry * sy
    s *= inv_len2
    np.clip(s, 0.0, 1.0, out=s)  # the closest point's place along the segment
    rx -= s * sx
    ry -= s * sy
    rx *= rx
    ry *= ry
    rx += ry  # squared distance to the segment
    rx[~np.broadcast_to(q_valid[:, None, :], rx.shape)] = np.inf
    return np.sqrt(rx.min(axis=-1)).astype(np.float64)


def path_distance_m(
    a_ne: FloatArray, a_valid: BoolArray, b_ne: FloatArray, b_valid: BoolArray
) -> FloatArray:
    """Symmetric mean closest-point distance (E,) m between paths ``a`` and ``b`` (module table).

    ``a_ne`` (E, Ta, 2), ``b_ne`` (E, Tb, 2): positions (north, east) m; ``*_valid`` (E, T)
    bool, a prefix of each row (an episode's samples), at least one per row. Blocks of whole
    episodes bound the memory (each block one vectorised call).

    >>> line = np.stack([np.arange(5.0), np.zeros(5)], axis=-1)[None]
    >>> ok = np.ones((1, 5), dtype=bool)
    >>> path_distance_m(line, ok, line + [0.0, 3.0], ok).tolist()
    [3.0]
    """
    a, b = np.asarray(a_ne, float), np.asarray(b_ne, float)
    av, bv = np.asarray(a_valid, bool), np.asarray(b_valid, bool)
    if not (av.any(axis=1).all() and bv.any(axis=1).all()):
        raise ValueError("every path needs at least one valid sample")
    per = max(1, CHUNK_ELEMENTS // max(a.shape[1] * b.shape[1], 1))
    out = np.empty(a.shape[0])
    for i in range(0, a.shape[0], per):  # blocks of episodes, not a loop per episode
        sl = slice(i, i + per)
        d_ab = _to_polyline(a[sl], b[sl], bv[sl])
        d_ba = _to_polyline(b[sl], a[sl], av[sl])
        mean_ab = np.sum(np.where(av[sl], d_ab, 0.0), axis=1) / av[sl].sum(axis=1)
        mean_ba = np.sum(np.where(bv[sl], d_ba, 0.0), axis=1) / bv[sl].sum(axis=1)
        out[sl] = 0.5 * (mean_ab + mean_ba)
    return out


def lockstep_distance_m(
    a_ne: FloatArray, a_valid: BoolArray, b_ne: FloatArray, b_valid: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Lock-step distance (module table): mean (E,) and maximum (E,) of |a(t) − b(t)| m over the
    samples up to the later of the two ends, both sampled at the same times from t = 0."""
    av, bv = np.asarray(a_valid, bool), np.asarray(b_valid, bool)
    t = max(av.shape[1], bv.shape[1])
    d = np.hypot(*np.moveaxis(held_positions(a_ne, av, t) - held_positions(b_ne, bv, t), -1, 0))
    span = np.maximum(av.sum(axis=1), bv.sum(axis=1))  # (E,) samples compared
    inside = np.arange(t)[None, :] < span[:, None]
    mean = np.sum(np.where(inside, d, 0.0), axis=1) / np.maximum(span, 1)
    return mean, np.max(np.where(inside, d, 0.0), axis=1)


def pass_sides(tracks: Any) -> NDArray[np.int8]:
    """Side (E, K) each target is passed on (module table): +1 on the own ship's starboard side,
    −1 on her port side, 0 for an empty slot, from
    :class:`usvsim.evaluation.colreg.EncounterTracks`."""
    own = np.asarray(tracks.own_north_east_m, float)[:, None]  # (E, 1, T, 2)
    kin = encounter_kinematics(
        own, np.asarray(tracks.own_course_rad, float)[:, None],
        np.asarray(tracks.own_speed_mps, float)[:, None],
        np.asarray(tracks.target_north_east_m, float),
        np.asarray(tracks.target_course_rad, float), np.asarray(tracks.target_speed_mps, float),
    )  # fmt: skip
    rng = np.where(np.asarray(tracks.valid, bool)[:, None, :], kin.range_m, np.inf)
    k_cpa = np.argmin(rng, axis=-1)  # (E, K): the sample of closest range
    beta = np.take_along_axis(kin.bearing_rad, k_cpa[..., None], axis=-1)[..., 0]
    side = np.where(beta >= 0.0, 1, -1).astype(np.int8)
    slots = tracks.target_valid
    ok = np.ones(side.shape, bool) if slots is None else np.asarray(slots, bool)
    return np.where(ok, side, 0).astype(np.int8)


@dataclass(frozen=True)
class SideAgreement:
    """Side agreement over the expert's scored encounters, overall and per encounter type
    (:class:`usvsim.task.colreg_geometry.EncounterType` name → (agreeing, encounters))."""

    overall: Proportion | None  # None without an encounter
    by_type: dict[str, tuple[int, int]]

    def to_json(self) -> dict[str, Any]:
        o = self.overall
        return {
            "encounters": 0 if o is None else o.n,
            "agreeing": 0 if o is None else o.successes,
            "rate": None if o is None else o.rate,
            "ci95": None if o is None else [o.lower, o.upper],
            "by_type": {k: {"agreeing": a, "encounters": n} for k, (a, n) in self.by_type.items()},
        }


def side_agreement(
    sides: NDArray[np.integer], expert_sides: NDArray[np.integer], expert_encounter: Any
) -> SideAgreement:
    """Agreement of ``sides`` (E, K) with ``expert_sides`` (E, K) over the encounters the
    expert's run has (``expert_encounter`` (E, K): :attr:`usvsim.evaluation.colreg.ColregResult.
    encounter`, an :class:`EncounterType` value, NONE and empty slots left out)."""
    kind = np.asarray(expert_encounter, dtype=np.intp)
    scored = (kind != int(EncounterType.NONE)) & (np.asarray(expert_sides) != 0)
    agree = scored & (np.asarray(sides) == np.asarray(expert_sides))
    n_types = len(EncounterType)
    total = np.bincount(kind[scored], minlength=n_types)
    same = np.bincount(kind[agree], minlength=n_types)
    by_type = {t.name.lower(): (int(same[t]), int(total[t])) for t in EncounterType if total[t]}
    n = int(scored.sum())
    return SideAgreement(proportion(int(agree.sum()), n) if n else None, by_type)
