"""COLREG compliance of recorded encounters: classification (rules 13-15) and a Woerner-style score.

Pure NumPy functions on recorded trajectories (:class:`EncounterTracks`), vectorised over E
episodes, K targets and T samples: no Python loop over episodes, targets or time.

Frame and signs: NED, positions (north, east) m, courses clockwise from north (rad). The
*relative bearing* β of a target is its direction from the own ship minus the own course
(positive to starboard); its *aspect* α is the own ship's direction from the target minus the
target's course (the own ship's bearing as the target sees it).

Entry (Woerner et al. 2019, "Quantifying protocol evaluation for autonomous collision
avoidance", Autonomous Robots 43, entry criteria): an own-ship/target encounter begins at the
first sample where the range is below ``entry_range_m`` and a risk of collision exists: the CPA
predicted from the present velocities is below ``risk_cpa_m`` and comes within ``risk_tcpa_s``
(or the range is already below ``risk_cpa_m``). A target that never meets both has no encounter.

Classification at that sample: COLREG rules 13-15 by the relative bearing β and the aspect α
(overtaking, overtaken, head-on, crossing give-way or stand-on; sectors of :class:`ColregParams`),
by :func:`usvsim.task.colreg_geometry.classify_encounter` (the table: that module's docstring); the
training reward :mod:`usvsim.task.colreg_reward` uses the same function.

Score (after Woerner et al. 2019 and the evaluator of NTNU's colav-simulator; weights in
:class:`ColregParams`). The encounter runs from its start to the CPA (manoeuvres) and on until the
range exceeds the entry range again (crossing the target's track)::

    safety  = 1 − w_min·clip((r_pref − cpa)/(r_pref − r_min), 0, 1)
                − w_nm·[cpa < r_nm] − w_col·[cpa < r_col]
    rule    = clip(1 − Σ rule penalties, 0, 1)
    score   = safety · rule                    (in [0, 1]; NaN where no encounter)

Rule penalties: head-on — passing starboard to starboard (target on our starboard side at CPA),
a first alteration ≥ 10° that is not to starboard (or none); give-way roles — the manoeuvre not
readily apparent, ``penalty × min(course deficiency, speed deficiency)`` with a deficiency falling
linearly from 1 at a detectable to 0 at a readily apparent change (rule 8); crossing ahead of the
target (our track crosses its course line within ``ahead_range_m`` ahead of its bow: rule 15 for
crossing, 13 for overtaking); stand-on roles — a course change ≥ 10° or a speed change ≥ 20 %
while the range is above ``stand_on_free_range_m`` (rule 17(a)(i): keep course and speed until
the give-way vessel is evidently not acting), unless the own ship is at that time in a give-way
encounter with another target (from its start until the range opens past the entry range): a
change needed for one vessel is not charged to the stand-on duty towards another. Each
own-ship/target pair is otherwise scored on its own (Woerner 2019's pairwise evaluation).

``passed`` (per encounter): CPA ≥ the minimum acceptable CPA (no near miss, no collision), none
of the rule's discrete penalties (passing side, side of the manoeuvre, crossing ahead, stand-on
course or speed change) and a give-way manoeuvre that is at least half-way readily apparent
(deficiency ≤ ``pass_apparent_fraction``). An encounter of type NONE never passes or fails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.evaluation.stats import Proportion, proportion
from usvsim.task.colreg_geometry import (
    GIVE_WAY,
    STAND_ON,
    EncounterType,
    classify_encounter,
    encounter_kinematics,
)
from usvsim.task.colreg_params import ColregParams

__all__ = [
    "ColregParams",
    "ColregResult",
    "ColregSummary",
    "EncounterTracks",
    "EncounterType",
    "evaluate_colreg",
    "summarize_colreg",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class EncounterTracks:
    """What one set of episodes recorded, sampled every ``dt_s`` seconds (shapes: E episodes,
    K target slots, T samples; NED, m, rad, m/s).

    ``own_course_rad`` is the course over ground (or the heading); ``valid`` is False after an
    episode ended (padding), ``target_valid`` False for an empty target slot (None: all valid).
    """

    dt_s: float
    own_north_east_m: np.ndarray  # (E, T, 2)
    own_course_rad: np.ndarray  # (E, T)
    own_speed_mps: np.ndarray  # (E, T)
    target_north_east_m: np.ndarray  # (E, K, T, 2)
    target_course_rad: np.ndarray  # (E, K, T)
    target_speed_mps: np.ndarray  # (E, K, T)
    valid: np.ndarray  # (E, T) bool
    target_valid: np.ndarray | None = None  # (E, K) bool

    def __post_init__(self) -> None:
        e, t = np.shape(self.own_course_rad)
        k = np.shape(self.target_course_rad)[1] if np.ndim(self.target_course_rad) == 3 else -1
        expected = {
            "own_north_east_m": (e, t, 2),
            "own_speed_mps": (e, t),
            "target_north_east_m": (e, k, t, 2),
            "target_course_rad": (e, k, t),
            "target_speed_mps": (e, k, t),
            "valid": (e, t),
        }
        if self.target_valid is not None:
            expected["target_valid"] = (e, k)
        for name, shape in expected.items():
            if np.shape(getattr(self, name)) != shape:
                got = np.shape(getattr(self, name))
                raise ValueError(f"EncounterTracks.{name} must have shape {shape}, got {got}")
        if not (math.isfinite(self.dt_s) and self.dt_s > 0.0):
            raise ValueError(f"EncounterTracks.dt_s must be a positive number, got {self.dt_s}")


@dataclass(frozen=True)
class ColregResult:
    """Per-encounter arrays of shape (E, K) (module docstring for the score and ``passed``).

    ``cpa_m`` is the closest range during the encounter, or over the whole episode where there is
    none (NaN for an empty target slot); ``start_index`` the sample where the encounter began (−1:
    none); ``penalties`` maps each component (safety terms and rule penalties, as subtracted) to
    an (E, K) array, NaN where there is no encounter.
    """

    encounter: np.ndarray
    start_index: np.ndarray
    cpa_m: np.ndarray
    score: np.ndarray
    passed: np.ndarray
    penalties: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def scored(self) -> BoolArray:
        """(E, K) bool: encounters that a rule applies to (type other than NONE)."""
        return np.asarray(self.encounter) != int(EncounterType.NONE)

    @property
    def episode_passed(self) -> BoolArray:
        """(E,) bool: every scored encounter of the episode passed (True without one)."""
        return np.all(np.asarray(self.passed) | ~self.scored, axis=1)


def _gather(a: np.ndarray, idx: IntArray) -> np.ndarray:
    """a[..., idx] along the last axis for an (E, K) index array (a broadcast to (E, K, T))."""
    a = np.broadcast_to(a, (*idx.shape, a.shape[-1]))
    return np.take_along_axis(a, idx[..., None], axis=-1)[..., 0]


def _first(mask: BoolArray) -> tuple[BoolArray, IntArray]:
    """Whether and where ``mask`` is first True along the last axis (index 0 where never)."""
    return np.asarray(mask.any(axis=-1)), np.asarray(np.argmax(mask, axis=-1))


def _kinematics(tr: EncounterTracks) -> dict[str, np.ndarray]:
    """Range, bearing, aspect, CPA and TCPA of every target at every sample, (E, K, T)
    (:func:`usvsim.task.colreg_geometry.encounter_kinematics`)."""
    chi_o = np.asarray(tr.own_course_rad, float)[:, None]  # (E, 1, T)
    u_o = np.asarray(tr.own_speed_mps, float)[:, None]
    u_t = np.asarray(tr.target_speed_mps, float)
    kin = encounter_kinematics(
        np.asarray(tr.own_north_east_m, float)[:, None], chi_o, u_o,
        np.asarray(tr.target_north_east_m, float), np.asarray(tr.target_course_rad, float), u_t,
    )  # fmt: skip
    rng = kin.range_m
    return {
        "range": rng,
        "bearing": kin.bearing_rad,
        "aspect": kin.aspect_rad,
        "cpa": kin.cpa_m,
        "tcpa": kin.tcpa_s,
        "x_t": kin.x_t_m,
        "y_t": kin.y_t_m,
        "u_o": np.broadcast_to(u_o, rng.shape),
        "u_t": u_t,
        "chi_o": np.broadcast_to(chi_o, rng.shape),
    }


def _ramp(value: FloatArray, full: float, zero: float) -> FloatArray:
    """1 at ``value ≤ full``, 0 at ``value ≥ zero``, linear between (a deficiency)."""
    return np.clip((zero - value) / (zero - full), 0.0, 1.0)


def evaluate_colreg(tracks: EncounterTracks, params: ColregParams | None = None) -> ColregResult:
    """Classify and score every own-ship/target encounter of ``tracks`` (module docstring).

    Parameters
    ----------
    tracks : EncounterTracks
        E episodes × K targets × T samples.
    params : ColregParams, optional
        Ranges, sectors and weights (default: boat scale).

    Returns
    -------
    ColregResult
        (E, K) arrays: type, start index, CPA (m), score in [0, 1] (NaN: no encounter), passed,
        penalty components.
    """
    p = params or ColregParams()
    e, k, t = np.shape(tracks.target_course_rad)
    per = max(1, CHUNK_ELEMENTS // max(k * t, 1))
    if e <= per:
        return _evaluate_block(tracks, p)
    # bounded memory: blocks of whole episodes, each one vectorised call (not a loop per episode)
    parts = [_evaluate_block(_episodes(tracks, slice(i, i + per)), p) for i in range(0, e, per)]
    arrays = {f: np.concatenate([getattr(r, f) for r in parts]) for f in _ARRAY_FIELDS}
    return ColregResult(
        **arrays,
        penalties={n: np.concatenate([r.penalties[n] for r in parts]) for n in parts[0].penalties},
    )


_ARRAY_FIELDS = ("encounter", "start_index", "cpa_m", "score", "passed")
CHUNK_ELEMENTS = 4_000_000  # (episode, target, sample) triples per block: ~30 MB per array


def _episodes(tr: EncounterTracks, sl: slice) -> EncounterTracks:
    """The tracks of the episodes ``sl``."""
    tv = None if tr.target_valid is None else np.asarray(tr.target_valid)[sl]
    a = {f: np.asarray(getattr(tr, f))[sl] for f in _TRACK_FIELDS}
    return EncounterTracks(tr.dt_s, **a, target_valid=tv)


_TRACK_FIELDS = ("own_north_east_m", "own_course_rad", "own_speed_mps", "target_north_east_m",
                 "target_course_rad", "target_speed_mps", "valid")  # fmt: skip


def _evaluate_block(tracks: EncounterTracks, p: ColregParams) -> ColregResult:
    """:func:`evaluate_colreg` on one block of episodes."""
    kin = _kinematics(tracks)
    rng = kin["range"]
    e, k, t = rng.shape
    target_ok = (np.ones((e, k), bool) if tracks.target_valid is None
                 else np.asarray(tracks.target_valid, bool))  # fmt: skip
    live = np.asarray(tracks.valid, bool)[:, None, :] & target_ok[..., None] & np.isfinite(rng)
    risk = (kin["cpa"] < p.risk_cpa_m) & (kin["tcpa"] > 0.0) & (kin["tcpa"] <= p.risk_tcpa_s)
    entry = live & (rng < p.entry_range_m) & (risk | (rng < p.risk_cpa_m))
    has, t0 = _first(entry)
    at0 = {name: _gather(kin[name], t0) for name in ("bearing", "aspect", "u_o", "u_t", "chi_o")}
    role = classify_encounter(at0["bearing"], at0["aspect"], at0["u_o"], at0["u_t"], p)
    kind = np.where(has, role, EncounterType.NONE).astype(np.intp)

    tt = np.arange(t)
    after = live & has[..., None] & (tt >= t0[..., None])
    t_cpa = np.argmin(np.where(after, rng, np.inf), axis=-1)
    cpa_enc = _gather(rng, t_cpa)
    whole = np.min(np.where(live, rng, np.inf), axis=-1)
    cpa_m = np.where(has, cpa_enc, np.where(np.isfinite(whole), whole, np.nan))
    opened, t_open = _first(after & (tt > t_cpa[..., None]) & (rng > p.entry_range_m))
    encounter = after & (tt < np.where(opened, t_open, t)[..., None])
    to_cpa = after & (tt <= t_cpa[..., None])

    # own manoeuvre from the start to the CPA: course deviation and speed reduction
    dev = ssa(kin["chi_o"] - at0["chi_o"][..., None])
    ratio = kin["u_o"] / np.maximum(at0["u_o"], 1e-9)[..., None]
    max_dev = np.max(np.where(to_cpa, np.abs(dev), 0.0), axis=-1)
    slow = np.max(np.where(to_cpa, 1.0 - ratio, 0.0), axis=-1)
    turned, t_turn = _first(to_cpa & (np.abs(dev) >= p.starboard_min_rad))
    to_starboard = turned & (_gather(dev, t_turn) > 0.0)
    # crossing the target's course line ahead of its bow (its body frame: x ahead, y starboard)
    y = kin["y_t"]
    flip = np.zeros_like(encounter)
    flip[..., 1:] = (
        encounter[..., 1:] & encounter[..., :-1] & (np.sign(y[..., 1:]) != np.sign(y[..., :-1]))
    )
    ahead = np.any(flip & (kin["x_t"] > 0.0) & (kin["x_t"] < p.ahead_range_m), axis=-1)
    # stand-on: course or speed changed while the give-way vessel still had room to act and the
    # own ship gave way to no other target (multi-target scenes: module docstring)
    head_on = kind == EncounterType.HEAD_ON
    give_way = np.isin(kind, [int(x) for x in GIVE_WAY])
    stand_on = np.isin(kind, [int(x) for x in STAND_ON])
    busy = np.any(encounter & give_way[..., None], axis=1, keepdims=True)  # (E, 1, T)
    early = to_cpa & (rng > p.stand_on_free_range_m) & ~busy
    so_course = np.max(np.where(early, np.abs(dev), 0.0), axis=-1) >= p.stand_on_course_rad
    so_speed = np.max(np.where(early, np.abs(ratio - 1.0), 0.0), axis=-1) >= p.stand_on_speed_ratio

    deficiency = np.minimum(
        _ramp(max_dev, p.detectable_course_rad, p.apparent_course_rad),
        _ramp(slow, p.detectable_speed_ratio, p.apparent_speed_ratio),
    )
    beta_cpa = _gather(kin["bearing"], t_cpa)
    rule = {
        "head_on_starboard_pass": p.penalty_head_on_starboard_pass * (head_on & (beta_cpa > 0.0)),
        "head_on_not_to_starboard": p.penalty_head_on_not_starboard * (head_on & ~to_starboard),
        "crossing_ahead": p.penalty_crossing_ahead
        * ((kind == EncounterType.CROSSING_GIVE_WAY) & ahead),
        "overtaking_ahead": p.penalty_overtaking_ahead
        * ((kind == EncounterType.OVERTAKING_GIVE_WAY) & ahead),
        "not_readily_apparent": p.penalty_not_apparent * np.where(give_way, deficiency, 0.0),
        "stand_on_course_change": p.penalty_stand_on_course * (stand_on & so_course),
        "stand_on_speed_change": p.penalty_stand_on_speed * (stand_on & so_speed),
    }
    safety = {
        "cpa_below_preferred": p.weight_min_cpa * _ramp(cpa_enc, p.min_cpa_m, p.preferred_cpa_m),
        "near_miss": p.weight_near_miss * (cpa_enc < p.near_miss_m),
        "collision": p.weight_collision * (cpa_enc < p.collision_m),
    }
    rule_score = np.clip(1.0 - sum(rule.values()), 0.0, 1.0)
    safety_score = np.clip(1.0 - sum(safety.values()), 0.0, 1.0)
    scored = kind != EncounterType.NONE
    score = np.where(scored, safety_score * rule_score, np.nan)
    discrete = [v for name, v in rule.items() if name != "not_readily_apparent"]
    passed = (
        scored
        & (cpa_enc >= p.min_cpa_m)
        & ~np.any(np.stack(discrete) > 0.0, axis=0)
        & ~(give_way & (deficiency > p.pass_apparent_fraction))
    )
    penalties = {name: np.where(scored, np.asarray(v, float), np.nan)
                 for name, v in {**safety, **rule}.items()}  # fmt: skip
    return ColregResult(
        encounter=kind,
        start_index=np.where(has, t0, -1).astype(np.intp),
        cpa_m=cpa_m,
        score=score,
        passed=passed,
        penalties=penalties,
    )


@dataclass(frozen=True)
class ColregSummary:
    """Compliance of one set of episodes: scored encounters, the share that passed with its
    Wilson 95 % interval (:mod:`usvsim.evaluation.stats`), mean score, episodes with every
    encounter passed, and per encounter type and penalty the counts."""

    encounters: int
    compliance: Proportion | None  # None without a scored encounter
    mean_score: float  # NaN without a scored encounter
    episodes: int
    episodes_with_encounter: int
    episodes_compliant: int
    by_type: dict[str, dict[str, Any]]  # type name -> encounters, passed, compliance, mean_score
    penalty_counts: dict[str, int]  # component -> encounters where it was > 0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (rates as fractions, the interval as ``ci95_low``/``ci95_high``)."""
        c = self.compliance
        return {
            "encounters": self.encounters,
            "compliant": 0 if c is None else c.successes,
            "compliance_rate": math.nan if c is None else c.rate,
            "compliance_ci95_low": math.nan if c is None else c.lower,
            "compliance_ci95_high": math.nan if c is None else c.upper,
            "mean_score": self.mean_score,
            "episodes": self.episodes,
            "episodes_with_encounter": self.episodes_with_encounter,
            "episodes_compliant": self.episodes_compliant,
            "by_type": self.by_type,
            "penalty_counts": self.penalty_counts,
        }


def summarize_colreg(result: ColregResult) -> ColregSummary:
    """Per-set figures of a :class:`ColregResult` (see :class:`ColregSummary`)."""
    kind = np.asarray(result.encounter)
    scored = kind != int(EncounterType.NONE)
    passed = np.asarray(result.passed, bool) & scored
    score = np.asarray(result.score, float)
    n = int(scored.sum())
    by_type: dict[str, dict[str, Any]] = {}
    for member in EncounterType:
        if member is EncounterType.NONE:
            continue
        m = kind == int(member)
        cnt, ok = int(m.sum()), int((passed & m).sum())
        by_type[member.name.lower()] = {
            "encounters": cnt,
            "passed": ok,
            "compliance_rate": ok / cnt if cnt else math.nan,
            "mean_score": float(score[m].mean()) if cnt else math.nan,
        }
    applies = scored.any(axis=1)
    return ColregSummary(
        encounters=n,
        compliance=proportion(int(passed.sum()), n) if n else None,
        mean_score=float(score[scored].mean()) if n else math.nan,
        episodes=int(kind.shape[0]),
        episodes_with_encounter=int(applies.sum()),
        episodes_compliant=int((applies & result.episode_passed).sum()),
        by_type=by_type,
        penalty_counts={
            name: int((np.nan_to_num(v) > 0.0).sum()) for name, v in result.penalties.items()
        },
    )
