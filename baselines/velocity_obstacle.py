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
``vessel_margin_m`` for one that does.) Cost of a candidate (Kuwata's weighted sum, our
weights)::

    J(θ) = w_g |ssa(θ − φ_goal)| + w_t |θ| + w_k |ssa(θ − θ_prev)|
           + Σ_j w_vo (1.1 − t*_j/τ) [θ ∈ VO_j] + Σ_j w_c [COLREG_j(θ) violated]

COLREG (rules 14 and 15) for a moving obstacle met head-on (|φ_j| < 15°, courses within 30° of
opposite) or crossing from starboard (0 < φ_j < 112.5°, closing), when the present course is a
risk of collision (the present course inside the VO; Kuwata et al.): candidates that would pass it
on the own starboard side (w × p_j > 0, i.e. ahead of a crossing vessel) are penalised, which
makes the boat alter to starboard and pass astern / port-to-port. θ_prev (the previous choice,
kept relative to the goal's bearing) damps switching between the two edges of a cone.

The course θ* becomes a heading through the crab angle β = atan2(v, u) (current, sway):
Δψ = clip(ssa(θ* − β), ±30°). Without obstacles this is line-of-sight (pursuit) guidance to the
goal, course over ground on the goal's bearing (Fossen 2021, §12.4: ψ_d = χ_d − β).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from baselines.los import heading_change_to_action
from usvsim.common.angles import ssa
from usvsim.task.batch import ActionKind
from usvsim.task.observations import SCENE_FEATURES, ObservationKind

__all__ = ["VOConfig", "VOHelmsman", "vo_course"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class VOConfig:
    """Parameters of the velocity-obstacle layer (module docstring; tuned on the stress sets'
    validation seeds, not their evaluation seeds)."""

    static_margin_m: float = 17.0  # m, R_safe = R + 17: 18 m for a pole, as los-avoid (tuned)
    vessel_margin_m: float = 25.0  # m, moving vessels: their motion is predicted, not known
    horizon_s: float = 60.0  # s, τ: 180 m at 3 m/s (Kuwata et al.: tens of seconds)
    n_candidates: int = 120  # courses over the full circle (3° apart)
    w_goal: float = 1.0  # 1/rad
    w_turn: float = 0.3  # 1/rad
    w_keep: float = 0.5  # 1/rad
    w_vo: float = 10.0
    w_colreg: float = 2.0
    moving_speed_mps: float = 0.3  # m/s, an obstacle faster than this over ground is a vessel
    max_heading_change_rad: float = math.radians(30.0)  # the task's action bound

    def __post_init__(self) -> None:
        if self.n_candidates < 8 or self.horizon_s <= 0:
            raise ValueError("VOConfig needs n_candidates >= 8 and horizon_s > 0")


def vo_course(
    cfg: VOConfig, observation: NDArray[np.generic], previous_rad: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The chosen course over ground θ* (N,) rad relative to the heading, and whether any
    candidate near the goal's bearing was blocked (avoiding), from ``scene`` observations."""
    obs = np.asarray(observation, dtype=np.float64)
    n = obs.shape[0]
    phi_goal, u, v = obs[:, 1], obs[:, 2], obs[:, 3]
    slots = obs[:, 4:].reshape(n, -1, SCENE_FEATURES)
    r, phi, radius = slots[..., 0], slots[..., 1], slots[..., 2]
    valid = slots[..., 5] > 0.5
    speed = np.maximum(np.hypot(u, v), 0.5)
    p = np.stack([r * np.cos(phi), r * np.sin(phi)], axis=-1)  # (N, K, 2)
    v_obs = slots[..., 3:5] + np.stack([u, v], axis=-1)[:, None, :]
    moving = np.hypot(v_obs[..., 0], v_obs[..., 1]) > cfg.moving_speed_mps
    r_safe = radius + np.where(moving, cfg.vessel_margin_m, cfg.static_margin_m)
    theta = np.linspace(-math.pi, math.pi, cfg.n_candidates, endpoint=False)  # (C,)
    cand = speed[:, None, None] * np.stack([np.cos(theta), np.sin(theta)], -1)[None]  # (N, C, 2)
    w = cand[:, :, None, :] - v_obs[:, None, :, :]  # (N, C, K, 2)
    pw = np.einsum("nckd,nkd->nck", w, p)
    ww = np.maximum(np.einsum("nckd,nckd->nck", w, w), 1e-9)
    t_star = np.clip(pw / ww, 0.0, cfg.horizon_s)
    miss = p[:, None] - w * t_star[..., None]
    d_cpa = np.hypot(miss[..., 0], miss[..., 1])
    in_vo = valid[:, None] & (pw > 0) & (d_cpa < r_safe[:, None])
    cost_vo = cfg.w_vo * np.sum(in_vo * (1.1 - t_star / cfg.horizon_s), axis=-1)
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
    starboard_pass = (w[..., 0] * p[:, None, :, 1] - w[..., 1] * p[:, None, :, 0]) > 0
    cost_colreg = cfg.w_colreg * np.sum(give_way[:, None] & starboard_pass & (pw > 0), axis=-1)
    cost = (
        cfg.w_goal * np.abs(ssa(theta[None] - phi_goal[:, None]))
        + cfg.w_turn * np.abs(theta)[None]
        + cfg.w_keep
        * np.where(np.isfinite(previous_rad), 1.0, 0.0)[:, None]
        * np.abs(ssa(theta[None] - np.nan_to_num(previous_rad)[:, None]))
        + cost_vo
        + cost_colreg
        + 1e-6 * (theta < 0)[None]  # ties go to starboard (COLREG rule 14)
    )
    best = np.argmin(cost, axis=1)
    rows = np.arange(n)
    goal_c = np.argmin(np.abs(ssa(theta[None] - phi_goal[:, None])), axis=1)
    return theta[best], (cost_vo[rows, goal_c] + cost_colreg[rows, goal_c]) > 0


@dataclass
class VOHelmsman:
    """LOS to the goal with velocity-obstacle avoidance (module docstring), ``scene`` input.

    ``last_avoiding`` marks the boats whose course to the goal was blocked at the last decision.
    """

    config: VOConfig = field(default_factory=VOConfig)
    observation: ObservationKind = field(default="scene", init=False)
    action: ActionKind = field(default="gaussian", init=False)
    last_avoiding: NDArray[np.bool_] | None = field(default=None, init=False, repr=False)

    def reset(self, n_boats: int) -> None:
        self._prev_from_goal = np.full(n_boats, np.nan)  # θ* − φ_goal of the last decision
        self.last_avoiding = None

    def act(self, observation: NDArray[np.generic]) -> NDArray[np.float32]:
        """Gaussian actions (N, 1) from ``scene`` observations (N, 4 + 6 k)."""
        obs = np.asarray(observation, dtype=np.float64)
        if obs.shape[0] != self._prev_from_goal.size:
            raise ValueError(
                f"reset({obs.shape[0]}) first: this helmsman has {self._prev_from_goal.size}"
            )
        previous = ssa(self._prev_from_goal + obs[:, 1])  # NaN stays NaN: no previous choice
        course, avoiding = vo_course(
            self.config, obs, np.where(np.isnan(self._prev_from_goal), np.nan, previous)
        )
        self._prev_from_goal = np.where(avoiding, ssa(course - obs[:, 1]), np.nan)
        self.last_avoiding = avoiding
        crab = np.where(np.hypot(obs[:, 2], obs[:, 3]) > 0.3, np.arctan2(obs[:, 3], obs[:, 2]), 0.0)
        return heading_change_to_action(ssa(course - crab), self.config.max_heading_change_rad)
