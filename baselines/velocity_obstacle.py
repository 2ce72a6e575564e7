"""The ``vo`` helmsman: line-of-sight to the goal with velocity-obstacle collision avoidance.

After Kuwata, Wolf, Zarzhitsky & Huntsberger (2014), "Safe maritime autonomous navigation with
COLREGS, using velocity obstacles", IEEE J. Oceanic Eng. 39(1): every decision the helmsman
scores a fan of candidate courses over ground and takes the cheapest; a candidate is inside an
obstacle's velocity obstacle when, held for the horizon τ, it would bring the boat within that
obstacle's safety radius.

What it sees: only the ``scene`` observation (:mod:`usvsim.task.observations`): the goal's range
and bearing, the estimated velocity over ground in the body frame (u, v), and the k nearest
obstacles (range r, bearing φ, radius R, velocity relative to the boat, validity), all from the
navigation estimate. In the body frame (x ahead, y starboard)::

    p_j = r_j (cos φ_j, sin φ_j)            obstacle position
    v_j = v_rel,j + (u, v)                  obstacle velocity over ground
    w(θ) = U (cos θ, sin θ) − v_j           own velocity relative to it, candidate course θ
    t* = clip(p_j·w / |w|², 0, τ),   d_cpa = |p_j − w t*|          closest point of approach
    θ ∈ VO_j  ⇔  d_cpa < R_j + m_j  and  p_j·w > 0 (closing)

(U = |(u, v)|; m_j the margin: ``static_margin_m`` for an obstacle that does not move,
``vessel_margin_m`` for one that does.) A boat cannot take a new course at once: each candidate
is predicted as a turn at rate ω from the present course over ground (an arc of radius U/ω,
sampled at 6 points, against each obstacle where it is by then), then the course held; the cone
test above runs from the arc's end, and an arc that closes within R_j + ``arc_margin_m`` of an
obstacle counts as inside the VO too (the dynamic VO of Wilkie, van den Berg & Manocha 2009, in
its simplest form). Without it, a boat starting 40 m from an islet turned into it while turning
towards a course that clears it (measured on the tuning seeds: "everything" 91 % → 94 %). Cost
of a candidate (Kuwata's weighted sum, our
weights)::

    J(θ) = w_g |ssa(θ − φ_goal)| + w_t |θ| + w_k |ssa(θ − θ_prev)|
           + Σ_j w_vo (1.1 − t*_j/τ) [θ ∈ VO_j] + Σ_j w_c [COLREG_j(θ) violated]

COLREG (rules 14 and 15) for a moving obstacle met head-on (|φ_j| < 15°, courses within 30° of
opposite) or crossing from starboard (0 < φ_j < 112.5°, closing), when the present course is a
risk of collision (the present course inside the VO; Kuwata et al.): candidates that would pass it
on the own starboard side (w × p_j > 0, i.e. ahead of a crossing vessel) are penalised, which
makes the boat alter to starboard and pass astern / port-to-port. θ_prev (the previous choice,
kept relative to the goal's bearing) damps switching between the two edges of a cone.

Two optional terms, off in ``vo`` (used by the family expert, :mod:`baselines.family_expert`):
``w_shortfall`` Σ_j (1 − d_j / R_j) over a candidate's blocked obstacles (d_j its closest
approach, R_j the clearance it wanted), so that where every course is blocked the widest pass
wins; and ``w_static_starboard`` on candidates that would leave a static obstacle blocking the
goal's course on the own starboard side (a turn to port).

The course θ* becomes a heading through the crab angle β = atan2(v, u) (current, sway):
Δψ = clip(ssa(θ* − β), ±30°). Without obstacles this is line-of-sight (pursuit) guidance to the
goal, course over ground on the goal's bearing (Fossen 2021, §12.4: ψ_d = χ_d − β).

Speed: the candidate-by-obstacle terms (arc, cone, COLREG flags) run in one C call
(:mod:`baselines.vo_kernel`) where it builds, bit for bit the NumPy path's (``backend="numpy"``,
the reference): 3,000 scenes of up to 8 obstacles in 0.08 s against 2.1 s CPU (load ~10 on 2
cores), so that ``vo`` can steer every target vessel in training (issue 41).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from baselines.los import heading_change_to_action
from baselines.vo_kernel import load_vo_kernel
from usvsim.common.angles import ssa
from usvsim.task.batch import ActionKind
from usvsim.task.observations import SCENE_FEATURES, ObservationKind

__all__ = ["VOConfig", "VOHelmsman", "vo_course"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class VOConfig:
    """Parameters of the velocity-obstacle layer (module docstring). Tuned by hand on draws of
    the stress sets from other seeds (12345, 777), not on the suite's own episodes."""

    static_margin_m: float = 17.0  # m, R_safe = R + 17: 18 m for a pole, as los-avoid (tuned)
    vessel_margin_m: float = 25.0  # m, moving vessels: their motion is predicted, not known
    horizon_s: float = 60.0  # s, τ: 180 m at 3 m/s (Kuwata et al.: tens of seconds)
    n_candidates: int = 120  # courses over the full circle (3° apart)
    w_goal: float = 1.0  # 1/rad
    w_turn: float = 0.3  # 1/rad
    w_keep: float = 0.5  # 1/rad
    w_vo: float = 10.0
    w_colreg: float = 2.0
    # weight of how far a blocked candidate falls short of the margin (0: the cone is a yes/no,
    # the tuned ``vo``): where every course is blocked, the one that passes widest wins
    w_shortfall: float = 0.0
    # cost of passing a static obstacle that blocks the course to the goal with it on the own
    # starboard side, i.e. of turning to port (0: either side, the tuned ``vo``). A habit of
    # altering to starboard makes the side of a pass dead ahead a rule instead of a coin toss
    w_static_starboard: float = 0.0
    moving_speed_mps: float = 0.3  # m/s, an obstacle faster than this over ground is a vessel
    arc_margin_m: float = 8.0  # m, clearance the predicted turn must keep (the cone keeps R_safe)
    turn_rate_radps: float = math.radians(11.5)  # rad/s, ω of the predicted turn (30° per 2 s
    # asked, the autopilot's lag included: usv105 turns ~12°/s at 3 m/s)
    max_heading_change_rad: float = math.radians(30.0)  # the task's action bound

    def __post_init__(self) -> None:
        if self.n_candidates < 8 or self.horizon_s <= 0:
            raise ValueError("VOConfig needs n_candidates >= 8 and horizon_s > 0")


_ARC_FRACTIONS = np.linspace(0.0, 1.0, 6)  # samples along a turn (start ... end)


def _turn(
    cfg: VOConfig, speed: FloatArray, course: FloatArray, theta: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The turn from ``course`` onto each candidate ``theta`` (N, C) rad, its duration (N, C) s
    at rate ω and the arc's signed radius U / ω (N, C) m (positive: to starboard)."""
    turn = ssa(theta[None, :] - course[:, None])  # (N, C)
    t_turn = np.abs(turn) / cfg.turn_rate_radps
    sign = np.where(turn >= 0, 1.0, -1.0)
    return turn, t_turn, speed[:, None] / cfg.turn_rate_radps * sign


def _turn_arc(
    cfg: VOConfig, speed: FloatArray, course: FloatArray, theta: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Positions (N, C, S, 2) along the turn from ``course`` onto each candidate ``theta`` at
    rate ω (body frame, from the boat), and the turn's duration (N, C) s.

    Velocity U (cos α, sin α), α = course + s ω t, so the position is
    (U / (s ω)) (sin α − sin course, cos course − cos α).
    """
    turn, t_turn, radius = _turn(cfg, speed, course, theta)
    alpha = course[:, None, None] + turn[..., None] * _ARC_FRACTIONS  # (N, C, S)
    c0 = course[:, None, None]
    x = radius[..., None] * (np.sin(alpha) - np.sin(c0))
    y = radius[..., None] * (np.cos(c0) - np.cos(alpha))
    return np.stack([x, y], axis=-1), t_turn


@dataclass(frozen=True)
class _Geometry:
    """What the candidate-by-slot terms need: own speed U (N,) m/s and course over ground (N,)
    rad (body frame), candidates θ (C,) rad; per slot (N, K): position p (N, K, 2) m and
    velocity over ground (N, K, 2) m/s in the body frame, validity, cone radius R_safe m, disc
    radius R m and whether the COLREG terms apply (give way)."""

    speed: FloatArray
    course: FloatArray
    theta: FloatArray
    p: FloatArray
    v_obs: FloatArray
    valid: NDArray[np.bool_]
    r_safe: FloatArray
    radius: FloatArray
    give_way: NDArray[np.bool_]


@dataclass(frozen=True)
class _SlotTerms:
    """Per boat, candidate and slot (N, C, K): the VO cost term [θ ∈ VO] (1.1 − t_hit/τ); per
    boat and candidate (N, C): how many slots' COLREG terms apply; per slot, only when asked
    for (else None): [θ ∈ VO], the starboard-pass flag and the shortfall."""

    vo: FloatArray
    colreg: NDArray[np.int64]
    in_vo: NDArray[np.bool_] | None = None
    starboard: NDArray[np.bool_] | None = None
    shortfall: FloatArray | None = None


def _slot_terms_numpy(cfg: VOConfig, g: _Geometry) -> _SlotTerms:
    """The terms with (N, C, S, K, 2) arrays (the reference; module docstring)."""
    p, v_obs, valid, r_safe = g.p, g.v_obs, g.valid, g.r_safe
    cand = g.speed[:, None, None] * np.stack([np.cos(g.theta), np.sin(g.theta)], -1)[None]
    w = cand[:, :, None, :] - v_obs[:, None, :, :]  # (N, C, K, 2)
    # the boat first turns onto θ at rate ω (an arc), then holds it: the cone starts at the
    # arc's end, and the arc itself must keep clear too
    arc_pos, t_turn = _turn_arc(cfg, g.speed, g.course, g.theta)  # (N, C, S, 2), (N, C)
    t_arc = t_turn[..., None] * _ARC_FRACTIONS  # (N, C, S)
    obst_at = p[:, None, None] + v_obs[:, None, None] * t_arc[..., None, None]  # (N, C, S, K, 2)
    gap = np.hypot(*np.moveaxis(obst_at - arc_pos[:, :, :, None, :], -1, 0))  # (N, C, S, K)
    r_arc = g.radius + cfg.arc_margin_m  # the turn itself only has to stay off the obstacle
    arc_hit = valid[:, None, None] & (gap < r_arc[:, None, None]) & (gap < gap[:, :, :1])
    first = np.argmax(arc_hit, axis=2)  # first intruding sample
    hit_arc = arc_hit.any(axis=2)  # (N, C, K)
    t_arc_hit = np.take_along_axis(t_arc, first, axis=2)  # (N, C, K)
    rel = obst_at[:, :, -1] - arc_pos[:, :, -1, None, :]  # at the arc's end (N, C, K, 2)
    pw = np.einsum("nckd,nckd->nck", w, rel)
    ww = np.maximum(np.einsum("nckd,nckd->nck", w, w), 1e-9)
    t_star = np.clip(pw / ww, 0.0, cfg.horizon_s)
    miss = rel - w * t_star[..., None]
    d_cpa = np.hypot(miss[..., 0], miss[..., 1])
    in_cone = valid[:, None] & (pw > 0) & (d_cpa < r_safe[:, None])
    t_hit = np.where(hit_arc, t_arc_hit, t_turn[..., None] + t_star)
    in_vo = hit_arc | in_cone
    term = in_vo * (1.1 - np.minimum(t_hit, cfg.horizon_s) / cfg.horizon_s)
    short_cone = in_cone * (1.0 - d_cpa / r_safe[:, None])
    short_arc = hit_arc * (1.0 - gap.min(axis=2) / r_arc[:, None])
    pw = np.einsum("nckd,nkd->nck", w, p)  # closing, from the present position (COLREG)
    starboard = (w[..., 0] * p[:, None, :, 1] - w[..., 1] * p[:, None, :, 0]) > 0
    colreg = np.sum(g.give_way[:, None] & starboard & (pw > 0), axis=-1)
    return _SlotTerms(term, colreg, in_vo, starboard, np.maximum(short_cone, short_arc))


def _slot_terms_compiled(
    kernel: Callable[..., None], cfg: VOConfig, g: _Geometry, more: bool
) -> _SlotTerms:
    """The terms from :mod:`baselines.vo_kernel` (equal to :func:`_slot_terms_numpy`'s);
    ``more``: also [θ ∈ VO], the starboard flags and the shortfall."""
    n, k = g.valid.shape
    c, s = g.theta.size, _ARC_FRACTIONS.size
    turn, t_turn, radius = _turn(cfg, g.speed, g.course, g.theta)
    term = np.empty((n, c, k))
    colreg = np.empty((n, c), dtype=np.int64)
    in_vo = np.empty((n, c, k), dtype=np.bool_) if more else None
    starboard = np.empty((n, c, k), dtype=np.bool_) if more else None
    shortfall = np.empty((n, c, k)) if more else None
    arrays = [
        np.ascontiguousarray(a)
        for a in (_ARC_FRACTIONS, np.cos(g.theta), np.sin(g.theta), g.speed, g.course,
                  np.sin(g.course), np.cos(g.course), turn, t_turn, radius, g.p, g.v_obs,
                  g.valid, g.give_way, g.r_safe, g.radius + cfg.arc_margin_m)
    ]  # fmt: skip
    out = [None if a is None else a.ctypes.data for a in (in_vo, starboard, shortfall)]
    kernel(n, c, k, s, *(a.ctypes.data for a in arrays), cfg.horizon_s, term.ctypes.data,
           colreg.ctypes.data, *out)  # fmt: skip
    return _SlotTerms(term, colreg, in_vo, starboard, shortfall)


def vo_course(
    cfg: VOConfig,
    observation: NDArray[np.generic],
    previous_rad: FloatArray,
    extra_margin_m: FloatArray | None = None,
    backend: Literal["auto", "compiled", "numpy"] = "auto",
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The chosen course over ground θ* (N,) rad relative to the heading, and whether any
    candidate near the goal's bearing was blocked (avoiding), from ``scene`` observations.

    ``extra_margin_m`` (N,) m, optional: added to every obstacle's margin m_j in the cone test
    of that boat only (wider passes); the turn's own clearance (``arc_margin_m``) is unchanged.
    ``backend``: the candidate-by-obstacle terms from the compiled kernel of
    :mod:`baselines.vo_kernel` where it builds (``"auto"``; the same numbers, bit for bit), or
    from NumPy (``"numpy"``, the reference).
    """
    obs = np.asarray(observation, dtype=np.float64)
    n = obs.shape[0]
    phi_goal, u, v = obs[:, 1], obs[:, 2], obs[:, 3]
    slots = obs[:, 4:].reshape(n, (obs.shape[1] - 4) // SCENE_FEATURES, SCENE_FEATURES)
    used = np.flatnonzero((slots[..., 5] > 0.5).any(axis=0))  # slots fill from the first
    slots = slots[:, : (used[-1] + 1 if used.size else 0)]
    r, phi, radius = slots[..., 0], slots[..., 1], slots[..., 2]
    valid = slots[..., 5] > 0.5
    speed = np.maximum(np.hypot(u, v), 0.5)
    p = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=-1)  # (N, K, 2)
    v_obs = slots[..., 3:5] + np.stack([u, v], axis=-1)[:, None, :]
    moving = np.hypot(v_obs[..., 0], v_obs[..., 1]) > cfg.moving_speed_mps
    r_safe = radius + np.where(moving, cfg.vessel_margin_m, cfg.static_margin_m)
    if extra_margin_m is not None:
        extra = np.asarray(extra_margin_m, dtype=np.float64)
        if extra.shape != (n,):
            raise ValueError(
                f"extra_margin_m must have shape ({n},) m, one per boat; got {extra.shape}"
            )
        r_safe = r_safe + extra[:, None]
    theta = np.linspace(-math.pi, math.pi, cfg.n_candidates, endpoint=False)  # (C,)
    course = np.arctan2(v, u)  # present course over ground (rad, relative to the heading)
    # COLREG 14/15 for moving obstacles: head-on, or crossing from starboard and closing
    course_rel = np.arctan2(v_obs[..., 1], v_obs[..., 0])
    closing = np.einsum("nkd,nkd->nk", p, slots[..., 3:5]) < 0
    head_on = (np.abs(phi) < math.radians(15.0)) & (
        np.abs(ssa(course_rel - math.pi)) < math.radians(30.0)
    )
    crossing = (phi > 0) & (phi < math.radians(112.5)) & closing
    # ... only where the present course is a risk of collision (inside the VO)
    w0 = -slots[..., 3:5]  # own velocity relative to the obstacle, on the present course
    t0 = np.einsum("nkd,nkd->nk", p, w0) / np.maximum(np.einsum("nkd,nkd->nk", w0, w0), 1e-9)
    d0 = np.hypot(*np.moveaxis(p - w0 * np.clip(t0, 0.0, None)[..., None], -1, 0))
    risk = (t0 > 0) & (t0 < cfg.horizon_s) & (d0 < r_safe)
    give_way = valid & moving & risk & (head_on | crossing)
    geometry = _Geometry(speed, course, theta, p, v_obs, valid, r_safe, radius, give_way)
    more = cfg.w_shortfall > 0 or cfg.w_static_starboard > 0
    kernel = load_vo_kernel() if backend != "numpy" else None
    if backend == "compiled" and kernel is None:
        raise ValueError("backend 'compiled': the vo kernel did not build (no C compiler?)")
    if kernel is not None:
        terms = _slot_terms_compiled(kernel, cfg, geometry, more)
    else:
        terms = _slot_terms_numpy(cfg, geometry)
    cost_vo = cfg.w_vo * np.sum(terms.vo, -1)
    if cfg.w_shortfall > 0 and terms.shortfall is not None:  # share of the margin a blocked
        # candidate misses, arc or cone
        cost_vo = cost_vo + cfg.w_shortfall * np.sum(terms.shortfall, -1)
    cost_colreg = cfg.w_colreg * terms.colreg
    off_goal = np.abs(ssa(theta[None] - phi_goal[:, None]))  # (N, C) rad
    keep = np.zeros((n, theta.size))  # boats without a previous choice: 0, as 0 · |…| is
    kept = np.isfinite(previous_rad)
    keep[kept] = cfg.w_keep * 1.0 * np.abs(ssa(theta[None] - previous_rad[kept][:, None]))
    cost = (
        cfg.w_goal * off_goal
        + cfg.w_turn * np.abs(theta)[None]
        + keep
        + cost_vo
        + cost_colreg
        + 1e-6 * (theta < 0)[None]  # ties go to starboard (COLREG rule 14)
    )
    rows = np.arange(n)
    goal_c = np.argmin(off_goal, axis=1)
    if cfg.w_static_starboard > 0 and terms.in_vo is not None and terms.starboard is not None:
        in_the_way = valid & ~moving & terms.in_vo[rows, goal_c]  # (N, K): blocks the goal
        cost = cost + cfg.w_static_starboard * np.sum(
            in_the_way[:, None] & terms.starboard, axis=-1
        )
    best = np.argmin(cost, axis=1)
    return theta[best], (cost_vo[rows, goal_c] + cost_colreg[rows, goal_c]) > 0


@dataclass
class VOHelmsman:
    """LOS to the goal with velocity-obstacle avoidance (module docstring), ``scene`` input.

    ``last_avoiding`` marks the boats whose course to the goal was blocked at the last decision.
    """

    config: VOConfig = field(default_factory=VOConfig)
    backend: Literal["auto", "compiled", "numpy"] = "auto"  # vo_course's (the same numbers)
    observation: ObservationKind = field(default="scene", init=False)
    action: ActionKind = field(default="gaussian", init=False)
    last_avoiding: NDArray[np.bool_] | None = field(default=None, init=False, repr=False)

    def reset(self, n_boats: int) -> None:
        self._prev_from_goal = np.full(n_boats, np.nan)  # θ* − φ_goal of the last decision
        self.last_avoiding = None

    def act(
        self, observation: NDArray[np.generic], boats: NDArray[np.intp] | None = None
    ) -> NDArray[np.float32]:
        """Gaussian actions (N, 1) from ``scene`` observations (N, 4 + 6 k); ``boats`` (N,),
        optional: which of the ``reset`` boats these are (the others' memory is kept, and
        ``last_avoiding`` is False for them), e.g. only the vessels present."""
        obs = np.asarray(observation, dtype=np.float64)
        size = self._prev_from_goal.size
        rows = np.arange(size) if boats is None else np.asarray(boats, dtype=np.intp)
        if obs.shape[0] != rows.size or (rows.size and not 0 <= rows.min() <= rows.max() < size):
            raise ValueError(
                f"reset({obs.shape[0]}) first, or give boats in [0, {size}) one per observation:"
                f" this helmsman has {size}"
            )
        prev_from_goal = self._prev_from_goal[rows]
        previous = ssa(prev_from_goal + obs[:, 1])  # NaN stays NaN: no previous choice
        course, avoiding = vo_course(
            self.config,
            obs,
            np.where(np.isnan(prev_from_goal), np.nan, previous),
            backend=self.backend,
        )
        self._prev_from_goal[rows] = np.where(avoiding, ssa(course - obs[:, 1]), np.nan)
        if boats is None:
            self.last_avoiding = avoiding
        else:
            self.last_avoiding = np.zeros(size, dtype=bool)
            self.last_avoiding[rows] = avoiding
        crab = np.where(np.hypot(obs[:, 2], obs[:, 3]) > 0.3, np.arctan2(obs[:, 3], obs[:, 2]), 0.0)
        return heading_change_to_action(ssa(course - crab), self.config.max_heading_change_rad)
