"""Per-decision COLREG reward terms for training in traffic (issue 41).

:class:`ColregReward` pays a boat, at the end of each decision period, for how it keeps the
rules of the road towards every target vessel of its episode, from the TRUE own-ship state and
vessel states; batched over boats and vessels (arrays (N, K), no Python loop over either). It is
added to the open-water env's reward by ``OpenWaterVectorEnv(colreg_reward=
ColregRewardWeights())`` (default off: the env's rewards unchanged).

Encounters (the scorer's, :mod:`usvsim.evaluation.colreg` after Woerner et al. 2019, with the
shared geometry of :mod:`usvsim.task.colreg_geometry` and the ranges of
:class:`usvsim.task.colreg_params.ColregParams`): an encounter with vessel k begins at the
first decision where it is within ``entry_range_m`` and a risk of collision exists (predicted
CPA < ``risk_cpa_m`` within ``risk_tcpa_s``, or the range already below ``risk_cpa_m``); the own
ship's role (head-on, crossing or overtaking, give-way or stand-on) and its course χ₀ are fixed
then, for the rest of the episode (one encounter per vessel and episode, as the scorer). The
encounter is *open* while the vessel is not yet passed (TCPA > 0). With δ = ssa(χ − χ₀) the own
course change since the encounter began (+ starboard), χ the course over ground (rad) over the
last second of the period, the terms (each summed over vessels; weights
:class:`ColregRewardWeights`) are::

    head_on_side     −w · clip(y_cpa / r_pref, 0, 1)    head-on, open: the target's predicted
                     position at the CPA to starboard of the own course (y_cpa > 0, m) is a
                     starboard-to-starboard passing (rule 14(a): pass port to port)
    head_on_port     −w · clip(−δ / δ_min, 0, 1)        head-on, open, before a starboard
                     alteration of δ_min: altered to port (rule 14(a): each alters to
                     starboard; δ_min = starboard_min_rad, 10°; as the scorer, the first
                     alteration decides, so resuming the course after it is not charged)
    crossing_ahead   −w   (once)                        give-way (crossing or overtaking): the
                     own ship crosses the target's course line ahead of its bow, within
                     ahead_range_m (rule 15: avoid crossing ahead; 13 for overtaking)
    starboard        +w · Δ clip(δ, 0, δ_app) / δ_app   give-way (head-on, crossing), open: the
                     growth of the starboard alteration up to a readily apparent δ_app
                     (apparent_course_rad, 30°) this period; at most +w per encounter, paid
                     back if the alteration is taken back before the vessel is passed
                     (rules 8(b), 16: early and substantial action)
    stand_on         −w · clip((|δ| − δ_det) / (δ_so − δ_det), 0, 1)   stand-on, open, before the
                     give-way vessel has had time to act (range > stand_on_free_range_m, or
                     less than ``stand_on_grace_s`` since the encounter began), and the own ship
                     giving way to no other vessel (δ_det 2°, δ_so 10°; rule 17(a)(i))
    cpa              −w · clip((r_pref − cpa) / (r_pref − r_min), 0, 1)   every vessel at risk
                     (0 < TCPA ≤ risk_tcpa_s, range < entry_range_m): a predicted passing
                     distance below the preferred one (the scorer's safety ramp, 57 → 30 m)

Each term is 0 outside its situation (tested on hand-made geometries). A boat's encounter
memory is cleared when it starts a new episode (:meth:`ColregReward.reset`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.colreg_geometry import (
    GIVE_WAY,
    STAND_ON,
    EncounterType,
    classify_encounter,
    encounter_kinematics,
)
from usvsim.task.colreg_params import ColregParams

__all__ = [
    "COLREG_TERMS",
    "ColregReward",
    "ColregRewardWeights",
    "ColregTerms",
    "colreg_weights",
    "own_motion",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
COLREG_TERMS = ("head_on_side", "head_on_port", "crossing_ahead", "starboard", "stand_on", "cpa")


def _roles(*roles: EncounterType) -> NDArray[np.bool_]:
    """A lookup table: ``table[role]`` is True for ``roles`` (faster than ``np.isin``)."""
    table = np.zeros(len(EncounterType), dtype=bool)
    table[[int(r) for r in roles]] = True
    table.flags.writeable = False
    return table


_GIVE_WAY = _roles(*GIVE_WAY)
_STAND_ON = _roles(*STAND_ON)
_AHEAD_ROLES = _roles(EncounterType.CROSSING_GIVE_WAY, EncounterType.OVERTAKING_GIVE_WAY)
_ALTER_ROLES = _roles(EncounterType.HEAD_ON, EncounterType.CROSSING_GIVE_WAY)


@dataclass(frozen=True)
class ColregRewardWeights:
    """Weights of the COLREG terms (module docstring), reward units of the study's reward
    (:class:`usvsim.task.reward.GaussianReward`: −3 … 0 per decision); 0 switches a term off.
    The weights are usvsim's choice, ordered as Woerner et al. 2019's rule penalties (crossing
    ahead 0.5, head-on wrong side 0.6, not to starboard 0.4, stand-on course change 0.5, safety
    0.2), scaled so that one violated encounter costs about what 5-10 s next to an obstacle
    does in the study's reward."""

    # reward units (r); every weight usvsim's choice (class docstring), the rule it serves:
    head_on_side: float = 0.5  # r per decision and vessel at a full starboard passing; rule 14
    head_on_port: float = 0.5  # r per decision and vessel at >= 10° to port; rule 14
    crossing_ahead: float = 10.0  # r per crossing ahead (once per encounter); rules 13, 15
    starboard: float = 5.0  # r per encounter for a >= 30° starboard alteration; rules 8, 16
    stand_on: float = 0.5  # r per decision and vessel at >= 10° off course; rule 17
    cpa: float = 0.3  # r per decision and vessel at a predicted CPA <= 30 m; Woerner 2019 ramp
    stand_on_grace_s: float = 20.0  # s, the give-way vessel's time to act; rule 17(a)(ii)
    params: ColregParams = field(default_factory=ColregParams)  # ranges and sectors (scorer's)

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name != "params" and not (math.isfinite(v) and v >= 0.0):
                raise ValueError(f"ColregRewardWeights.{f.name} must be finite and >= 0, got {v}")

    def without(self, *terms: str) -> ColregRewardWeights:
        """These weights with ``terms`` (names of :data:`COLREG_TERMS`) set to 0 (ablations)."""
        unknown = [t for t in terms if t not in COLREG_TERMS]
        if unknown:
            raise ValueError(f"unknown COLREG term {unknown[0]!r}; choose from {COLREG_TERMS}")
        zero: dict[str, Any] = dict.fromkeys(terms, 0.0)
        return replace(self, **zero)


def colreg_weights(terms: str) -> ColregRewardWeights | None:
    """The default weights with ``terms`` on (``"all"`` or comma-separated names of
    :data:`COLREG_TERMS`), the others 0; None for ``""`` (the reward off). ``ValueError`` names
    an unknown term."""
    if not terms:
        return None
    on = COLREG_TERMS if terms == "all" else tuple(t.strip() for t in terms.split(",") if t.strip())
    unknown = [t for t in on if t not in COLREG_TERMS]
    if unknown:
        raise ValueError(
            f"unknown COLREG reward term {unknown[0]!r}; use 'all' or names from "
            f"{', '.join(COLREG_TERMS)}"
        )
    return ColregRewardWeights().without(*(t for t in COLREG_TERMS if t not in on))


@dataclass(frozen=True)
class ColregTerms:
    """The COLREG terms of N boats, each (N,) (module docstring); the reward is their sum."""

    head_on_side: FloatArray
    head_on_port: FloatArray
    crossing_ahead: FloatArray
    starboard: FloatArray
    stand_on: FloatArray
    cpa: FloatArray

    @property
    def total(self) -> FloatArray:
        """The sum of the terms (N,)."""
        out: FloatArray = sum((getattr(self, t) for t in COLREG_TERMS[1:]), self.head_on_side)
        return out


class ColregReward:
    """The COLREG terms of ``n_boats`` boats, with each boat's encounters (module docstring).

    State per boat and vessel slot (N, K): role, course at the encounter's start, the own ship's
    side of the target's course line and its course change at the previous decision, the
    encounter's age. The slot count grows with the widest episode seen.
    """

    def __init__(self, weights: ColregRewardWeights, n_boats: int) -> None:
        self.weights = weights
        self.role: NDArray[np.intp] = np.zeros((n_boats, 0), dtype=np.intp)  # EncounterType
        self.chi0: FloatArray = np.zeros((n_boats, 0))  # rad, own course at the start
        self.prev_y: FloatArray = np.zeros((n_boats, 0))  # m, own side of the target's track
        self.prev_dev: FloatArray = np.zeros((n_boats, 0))  # rad, δ at the previous decision
        self.age_s: FloatArray = np.zeros((n_boats, 0))  # s, since the encounter began
        self.max_dev: FloatArray = np.zeros((n_boats, 0))  # rad, largest δ so far (starboard)

    def _resize(self, k: int) -> None:
        """Grow to ``k`` vessel slots (new slots empty: role NONE)."""
        pad = ((0, 0), (0, k - self.role.shape[1]))
        self.role = np.pad(self.role, pad)
        self.chi0, self.prev_y = np.pad(self.chi0, pad), np.pad(self.prev_y, pad)
        self.prev_dev, self.age_s = np.pad(self.prev_dev, pad), np.pad(self.age_s, pad)
        self.max_dev = np.pad(self.max_dev, pad)

    def reset(self, boats: NDArray[np.intp]) -> None:
        """Forget the encounters of ``boats`` (they start new episodes)."""
        self.role[boats] = int(EncounterType.NONE)
        self.age_s[boats] = 0.0

    def __call__(
        self, own_ne: FloatArray, own_course_rad: FloatArray, own_speed_mps: FloatArray,
        vessel_ne: FloatArray, vessel_velocity_ne: FloatArray, vessel_ok: BoolArray,
        dt_s: float,
    ) -> ColregTerms:  # fmt: skip
        """The terms of one decision: own position (N, 2) m, course over ground (N,) rad, speed
        (N,) m/s; vessels' positions (N, K, 2) m, velocities (N, K, 2) m/s, valid (N, K); the
        time since the previous call ``dt_s`` (s, the decision period)."""
        w, p = self.weights, self.weights.params
        k = vessel_ok.shape[1]
        if k > self.role.shape[1]:
            self._resize(k)
        role, chi0 = self.role[:, :k], self.chi0[:, :k]
        v_course = np.arctan2(vessel_velocity_ne[..., 1], vessel_velocity_ne[..., 0])
        v_speed = np.hypot(vessel_velocity_ne[..., 0], vessel_velocity_ne[..., 1])
        chi, u = own_course_rad[:, None], own_speed_mps[:, None]
        kin = encounter_kinematics(own_ne[:, None], chi, u, vessel_ne, v_course, v_speed)
        risk = (kin.cpa_m < p.risk_cpa_m) & (kin.tcpa_s > 0.0) & (kin.tcpa_s <= p.risk_tcpa_s)
        entry = vessel_ok & (kin.range_m < p.entry_range_m) & (risk | (kin.range_m < p.risk_cpa_m))
        new = (role == int(EncounterType.NONE)) & entry
        role[...] = np.where(new, classify_encounter(kin.bearing_rad, kin.aspect_rad,
                                                     u, v_speed, p), role)  # fmt: skip
        chi0[...] = np.where(new, chi, chi0)
        prev_y = np.where(new, kin.y_t_m, self.prev_y[:, :k])
        prev_dev = np.where(new, 0.0, self.prev_dev[:, :k])
        age = np.where(new, 0.0, self.age_s[:, :k] + dt_s)
        engaged = vessel_ok & (role != int(EncounterType.NONE))
        open_ = engaged & (kin.tcpa_s > 0.0)
        dev = np.where(engaged, ssa(chi - chi0), 0.0)
        head_on = open_ & (role == int(EncounterType.HEAD_ON))

        # rule 14: the target's predicted position at the CPA, in the own body frame (y starboard)
        rel_v = vessel_velocity_ne - u[..., None] * np.stack([np.cos(chi), np.sin(chi)], -1)
        d_cpa = vessel_ne - own_ne[:, None] + rel_v * kin.tcpa_s[..., None]
        y_cpa = -np.sin(chi) * d_cpa[..., 0] + np.cos(chi) * d_cpa[..., 1]
        side = np.where(head_on, np.clip(y_cpa / p.preferred_cpa_m, 0.0, 1.0), 0.0)
        max_dev = np.where(new, 0.0, np.maximum(self.max_dev[:, :k], np.where(open_, dev, 0.0)))
        first = head_on & (max_dev < p.starboard_min_rad)  # no starboard alteration yet
        port = np.where(first, np.clip(-dev / p.starboard_min_rad, 0.0, 1.0), 0.0)
        # rules 13, 15: crossed the target's course line (its y changed sign) ahead of its bow
        flip = np.sign(kin.y_t_m) != np.sign(prev_y)
        ahead = (engaged & _AHEAD_ROLES[role] & flip & (kin.x_t_m > 0.0)
                 & (kin.x_t_m < p.ahead_range_m))  # fmt: skip
        # rules 8, 16: growth of the starboard alteration up to a readily apparent one
        a = p.apparent_course_rad
        alter = open_ & _ALTER_ROLES[role]
        gain = np.where(alter, (np.clip(dev, 0.0, a) - np.clip(prev_dev, 0.0, a)) / a, 0.0)
        # rule 17: stand-on course change before the give-way vessel had time to act
        busy = np.any(open_ & _GIVE_WAY[role], axis=1, keepdims=True)
        early = (kin.range_m > p.stand_on_free_range_m) | (age < w.stand_on_grace_s)
        stand = open_ & _STAND_ON[role] & early & ~busy
        span = p.stand_on_course_rad - p.detectable_course_rad
        so = np.where(stand, np.clip((np.abs(dev) - p.detectable_course_rad) / span, 0, 1), 0.0)
        # safety: predicted passing distance below the preferred one (Woerner's ramp)
        at_risk = (vessel_ok & (kin.tcpa_s > 0.0) & (kin.tcpa_s <= p.risk_tcpa_s)
                   & (kin.range_m < p.entry_range_m))  # fmt: skip
        short = (p.preferred_cpa_m - kin.cpa_m) / (p.preferred_cpa_m - p.min_cpa_m)
        cpa = np.where(at_risk, np.clip(short, 0.0, 1.0), 0.0)

        self.prev_y[:, :k] = kin.y_t_m
        self.prev_dev[:, :k] = np.where(engaged, np.where(open_, dev, prev_dev), 0.0)
        self.age_s[:, :k] = age
        self.max_dev[:, :k] = max_dev
        return ColregTerms(
            head_on_side=-w.head_on_side * side.sum(axis=1),
            head_on_port=-w.head_on_port * port.sum(axis=1),
            crossing_ahead=-w.crossing_ahead * ahead.sum(axis=1),
            starboard=w.starboard * gain.sum(axis=1),
            stand_on=-w.stand_on * so.sum(axis=1),
            cpa=-w.cpa * cpa.sum(axis=1),
        )

    def from_batch(self, sim: Any, step: Any, period_start_s: FloatArray) -> ColregTerms:
        """The terms of an :class:`usvsim.task.openwater_batch.OpenWaterBatch` decision just
        taken (``step`` its :class:`~usvsim.task.openwater_batch.OpenWaterStep`, which began at
        episode times ``period_start_s`` (N,) s): the own ship at the period's last plant step
        (:func:`own_motion`), the vessels where they are at that time."""
        # here, not at the top: the torch path (usvsim.task.torch_colreg) imports this module
        # where SciPy and CasADi are absent, and openwater needs them
        from usvsim.task.openwater import vessel_motion

        base = sim.base
        pos, course, speed, t_s = own_motion(step.trajectory, step.end_step, base.dt_s)
        v_pos, v_vel = vessel_motion(sim.v_p0, sim.v_course, sim.v_speed, sim.v_turn,
                                     (period_start_s + t_s)[:, None])  # fmt: skip
        return self(pos, course, speed, v_pos, v_vel, sim.vessel_ok, base.decision_period_s)


def own_motion(
    trajectory: FloatArray, end_step: NDArray[np.intp], dt_s: float, window: int = 10
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Position (N, 2) m at each boat's last plant step of the period (``end_step`` counts the
    steps, ≥ 1), its course (rad) and speed (m/s) over ground over the ``window`` steps before
    (fewer at the period's start), and that step's time within the period (N,) s.
    ``trajectory`` (N, T, ≥ 2): the period's true states, one per plant step of ``dt_s``."""
    n = trajectory.shape[0]
    rows = np.arange(n)
    hi = np.maximum(np.asarray(end_step) - 1, 1)
    lo = np.maximum(hi - window, 0)
    d = trajectory[rows, hi, 0:2] - trajectory[rows, lo, 0:2]
    span = (hi - lo) * dt_s
    course = np.arctan2(d[:, 1], d[:, 0])
    return trajectory[rows, hi, 0:2], course, np.hypot(d[:, 0], d[:, 1]) / span, (hi + 1) * dt_s
