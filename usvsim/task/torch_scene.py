"""The open-water scene on tensors: vessel motion, the judge of a decision period, the ``scene``
observation and the study's reward, for :class:`usvsim.task.torch_openwater.TorchOpenWaterEnv`.

Each function is the twin of a NumPy original and does its operations in the same order on
tensors of N boats (any device, float64 or float32), tested equal to it in
``tests/usvsim/task/test_torch_openwater.py``:

=============================  ================================================================
here                           NumPy original
=============================  ================================================================
:func:`vessel_motion_torch`    :func:`usvsim.task.openwater.vessel_motion`
:func:`judge_period_torch`     :func:`usvsim.task.scene_distances.judge_period` (the reference
                               path: every disc at every sub-step, ``hypot``)
:func:`scene_observation_torch` :func:`usvsim.task.observations.scene_observation`
:func:`positional_torch`       ``observe_scene("positional", ...)``
                               (:mod:`usvsim.task.openwater_batch`)
:func:`gaussian_reward_torch`  :class:`usvsim.task.reward.GaussianReward`
=============================  ================================================================

Discs (:class:`TorchDiscs`), N boats, K static discs and M vessels per boat, padded with a
validity mask; statics first, then vessels, as :class:`usvsim.task.scene_distances.PackedDiscs`.
No Python loop over boats, discs or sub-steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch

from usvsim.task.torch_observations import relative_polar_torch

__all__ = [
    "SCENE_FEATURES",
    "SCENE_K",
    "TorchDiscs",
    "TorchJudgement",
    "fixed_horizon_torch",
    "gaussian_reward_torch",
    "judge_period_torch",
    "positional_torch",
    "scene_observation_torch",
    "vessel_motion_torch",
]

#: :data:`usvsim.task.observations.SCENE_K` and ``SCENE_FEATURES`` (repeated: that module needs
#: gymnasium; tested equal): k nearest discs, 6 features each.
SCENE_K = 8
SCENE_FEATURES = 6
NO_OBSTACLE_RANGE_M = 1000.0  # m, usvsim.task.openwater_batch.NO_OBSTACLE_RANGE_M


@dataclass(frozen=True)
class TorchDiscs:
    """N boats' discs: statics centres (N, K, 2) m, radii (N, K) m, valid (N, K); vessels start
    positions (N, M, 2) m, courses (N, M) rad, speeds (N, M) m/s, turn rates (N, M) rad/s,
    radii (N, M) m, valid (N, M)."""

    centres_ne: torch.Tensor
    radii_m: torch.Tensor
    static_ok: torch.Tensor
    vessel_p0_ne: torch.Tensor
    vessel_course_rad: torch.Tensor
    vessel_speed_mps: torch.Tensor
    vessel_turn_radps: torch.Tensor
    vessel_radius_m: torch.Tensor
    vessel_ok: torch.Tensor

    def where(self, rows: torch.Tensor, other: TorchDiscs) -> TorchDiscs:
        """``other``'s discs for the boats ``rows`` (N,) bool, this one's for the rest."""
        out = []
        for mine, theirs in zip(vars(self).values(), vars(other).values(), strict=True):
            mask = rows.view(-1, *([1] * (mine.ndim - 1)))
            out.append(torch.where(mask, theirs, mine))
        return TorchDiscs(*out)

    @property
    def radii_all(self) -> torch.Tensor:
        """Every disc's radius (N, K + M) m, statics then vessels."""
        return torch.cat([self.radii_m, self.vessel_radius_m], dim=1)

    @property
    def ok_all(self) -> torch.Tensor:
        """Every disc's validity (N, K + M)."""
        return torch.cat([self.static_ok, self.vessel_ok], dim=1)

    def at(self, t_s: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Every disc's centre (N, K + M, 2) m and velocity over ground (N, K + M, 2) m/s at each
        boat's episode time ``t_s`` (N,) s (``OpenWaterBatch._discs_at``)."""
        pos, vel = vessel_motion_torch(
            self.vessel_p0_ne, self.vessel_course_rad, self.vessel_speed_mps,
            self.vessel_turn_radps, t_s[:, None],
        )  # fmt: skip
        c = self.centres_ne
        return torch.cat([c, pos], dim=1), torch.cat([torch.zeros_like(c), vel], dim=1)


def vessel_motion_torch(
    p0: torch.Tensor,
    course: torch.Tensor,
    speed: torch.Tensor,
    turn: torch.Tensor,
    t_s: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Positions (..., 2) m and velocities (..., 2) m/s of vessels at times ``t_s``
    (:func:`usvsim.task.openwater.vessel_motion`: constant turn rate ω, the straight-line limit
    where |ω| t < 1e-9); ``p0`` (..., 2), the rest broadcastable to (...)."""
    chi = course + turn * t_s
    sin_chi, cos_chi = torch.sin(chi), torch.cos(chi)
    sin0, cos0 = torch.sin(course), torch.cos(course)
    small = torch.abs(turn * t_s) < 1e-9
    w = torch.where(small, 1.0, turn)
    dx = torch.where(small, speed * t_s * cos0, speed / w * (sin_chi - sin0))
    dy = torch.where(small, speed * t_s * sin0, speed / w * (cos0 - cos_chi))
    pos = torch.stack([p0[..., 0] + dx, p0[..., 1] + dy], dim=-1)
    vel = torch.stack([speed * cos_chi, speed * sin_chi], dim=-1)
    return pos, vel


@dataclass(frozen=True)
class TorchJudgement:
    """:class:`usvsim.task.scene_distances.PeriodJudgement` on tensors, all (N,)."""

    nearest_m: torch.Tensor
    collision: torch.Tensor
    reached_goal: torch.Tensor
    end_step: torch.Tensor
    first_goal_step: torch.Tensor
    distance_to_obstacle_m: torch.Tensor
    distance_to_goal_m: torch.Tensor


def nearest_and_hits_torch(
    x_n: torch.Tensor,
    y_e: torch.Tensor,
    t_s: torch.Tensor,
    discs: TorchDiscs,
    r_pole_m: float,
    half_beam_m: float,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Smallest pole-equivalent distance (N, T) m (inf without a valid disc) and any-hit flags
    (N, T) at positions ``x_n``, ``y_e`` (N, T) m and episode times ``t_s`` (N, T) s
    (:func:`usvsim.task.scene_distances.nearest_and_hits`'s reference path)."""
    c = discs.centres_ne
    vessels, _ = vessel_motion_torch(
        discs.vessel_p0_ne[:, :, None, :], discs.vessel_course_rad[:, :, None],
        discs.vessel_speed_mps[:, :, None], discs.vessel_turn_radps[:, :, None],
        t_s[:, None, :],
    )  # fmt: skip
    x, y = x_n[:, None, :], y_e[:, None, :]
    h = torch.cat(
        [
            torch.hypot(x - c[:, :, None, 0], y - c[:, :, None, 1]),
            torch.hypot(x - vessels[..., 0], y - vessels[..., 1]),
        ],
        dim=1,
    )  # (N, J, T)
    radii, ok = discs.radii_all, discs.ok_all
    d = torch.where(ok[..., None], h + (r_pole_m - radii)[..., None], math.inf)
    hit = ok[..., None] & (h < (radii + half_beam_m)[..., None])
    if d.shape[1] == 0:
        return d.new_full((d.shape[0], d.shape[2]), math.inf), hit.any(dim=1)
    return d.amin(dim=1), hit.any(dim=1)


def judge_period_torch(
    x_n: torch.Tensor,
    y_e: torch.Tensor,
    t_s: torch.Tensor,
    discs: TorchDiscs,
    goal_ne: torch.Tensor,
    r_pole_m: float,
    half_beam_m: float,
    goal_radius_m: float,
) -> TorchJudgement:
    """One decision period of N boats judged from their true positions ``x_n``, ``y_e`` (N, T) m
    at episode times ``t_s`` (N, T) s, goals ``goal_ne`` (N, 2) m
    (:func:`usvsim.task.scene_distances.judge_period`): the end step is the first hit or goal
    sub-step, else T − 1; the nearest distance counts up to and including it."""
    d_min_t, hit = nearest_and_hits_torch(x_n, y_e, t_s, discs, r_pole_m, half_beam_m)
    steps = d_min_t.shape[1]
    dx, dy = x_n - goal_ne[:, 0:1], y_e - goal_ne[:, 1:2]
    inside = torch.hypot(dx, dy) <= goal_radius_m
    collision, reached = hit.any(dim=1), inside.any(dim=1)
    index = torch.arange(steps, device=x_n.device)[None, :]
    first_event = torch.where(hit | inside, index, steps).amin(dim=1)
    end = torch.where(reached | collision, first_event, steps - 1)
    upto = torch.where(index > end[:, None], math.inf, d_min_t)
    first_goal = torch.where(inside, index, steps).amin(dim=1)
    at_end = end[:, None]
    return TorchJudgement(
        nearest_m=upto.amin(dim=1),
        collision=collision,
        reached_goal=reached,
        end_step=end,
        first_goal_step=torch.where(reached, first_goal, 0),
        distance_to_obstacle_m=d_min_t.gather(1, at_end)[:, 0],
        distance_to_goal_m=torch.hypot(dx.gather(1, at_end)[:, 0], dy.gather(1, at_end)[:, 0]),
    )


def scene_observation_torch(
    pos_ne: torch.Tensor,
    psi_rad: torch.Tensor,
    velocity_ne: torch.Tensor,
    goal_ne: torch.Tensor,
    centres_ne: torch.Tensor,
    radii_m: torch.Tensor,
    obstacle_velocity_ne: torch.Tensor,
    valid: torch.Tensor,
    k: int = SCENE_K,
) -> torch.Tensor:
    """The ``scene`` observation (N, 4 + 6 k) in the inputs' dtype
    (:func:`usvsim.task.observations.scene_observation`): the goal's range and bearing, the own
    velocity over ground in the body frame (forward, starboard), then the k discs nearest by
    edge distance ``r − R`` (stable order), each ``[r, φ, R, v_fwd, v_stb, 1]`` with its
    velocity relative to the own boat in the body frame; empty slots all zeros.

    ``pos_ne``, ``velocity_ne``, ``goal_ne`` (N, 2); ``psi_rad`` (N,); ``centres_ne`` (N, J, 2),
    ``radii_m`` (N, J), ``obstacle_velocity_ne`` (N, J, 2), ``valid`` (N, J) bool."""
    n, j = radii_m.shape
    out = pos_ne.new_zeros((n, 4 + SCENE_FEATURES * k))
    r_all, b_all = relative_polar_torch(
        pos_ne, psi_rad, torch.cat([goal_ne[:, None, :], centres_ne], dim=1)
    )
    c, s = torch.cos(psi_rad), torch.sin(psi_rad)
    out[:, 0], out[:, 1] = r_all[:, 0], b_all[:, 0]
    out[:, 2] = c * velocity_ne[:, 0] + s * velocity_ne[:, 1]
    out[:, 3] = -s * velocity_ne[:, 0] + c * velocity_ne[:, 1]
    if j == 0:
        return out
    r, b = r_all[:, 1:], b_all[:, 1:]
    edge = torch.where(valid, r - radii_m, math.inf)
    order = torch.sort(edge, dim=1, stable=True).indices[:, :k]
    rel = obstacle_velocity_ne - velocity_ne[:, None, :]
    cc, ss = c[:, None], s[:, None]
    vx = cc * rel[..., 0] + ss * rel[..., 1]
    vy = -ss * rel[..., 0] + cc * rel[..., 1]
    table = torch.stack([r, b, radii_m, vx, vy, valid.to(r.dtype)], dim=-1)  # (N, J, 6)
    table = torch.where(valid[..., None], table, 0.0)
    feats = table.gather(1, order[..., None].expand(-1, -1, SCENE_FEATURES))
    m = order.shape[1]
    out[:, 4 : 4 + SCENE_FEATURES * m] = feats.reshape(n, -1)
    return out


def positional_torch(
    pos_ne: torch.Tensor,
    psi_rad: torch.Tensor,
    goal_ne: torch.Tensor,
    centres_ne: torch.Tensor,
    radii_m: torch.Tensor,
    valid: torch.Tensor,
) -> torch.Tensor:
    """The open-water ``positional`` observation (N, 4) ``[r_eq, φ, r_goal, φ_goal]``: the disc
    nearest by pole-equivalent range ``r − R + 1 m`` in the study's pole slot (the first such
    disc), a pole 1 km astern where no disc is valid (``observe_scene("positional", ...)``).
    Shapes as :func:`scene_observation_torch`; returns the inputs' dtype."""
    r, b = relative_polar_torch(pos_ne, psi_rad, centres_ne)
    r_eq = torch.where(valid, r + (1.0 - radii_m), math.inf)
    j = torch.argmin(r_eq, dim=1, keepdim=True)
    near_r, near_b = r_eq.gather(1, j)[:, 0], b.gather(1, j)[:, 0]
    none = ~torch.isfinite(near_r)
    r_g, b_g = relative_polar_torch(pos_ne, psi_rad, goal_ne[:, None, :])
    return torch.stack(
        [
            torch.where(none, NO_OBSTACLE_RANGE_M, near_r),
            torch.where(none, -math.pi, near_b),
            r_g[:, 0],
            b_g[:, 0],
        ],
        dim=1,
    )


def gaussian_reward_torch(
    pole_weight: float,
    pole_sigma_m: float,
    goal_weight: float,
    goal_sigma_m: float,
    d_pole_m: torch.Tensor,
    d_goal_m: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    """:class:`usvsim.task.reward.GaussianReward`'s terms (pole, goal) on tensors (N,): the same
    operations (Vedeler 2019, the corrected reward)."""
    q_pole, q_goal = d_pole_m / pole_sigma_m, d_goal_m / goal_sigma_m
    pole = -pole_weight * torch.exp(-0.5 * (q_pole * q_pole))
    goal = goal_weight * (torch.exp(-0.5 * (q_goal * q_goal)) - 1.0)
    return pole, goal


def fixed_horizon_torch(
    reward: torch.Tensor,
    terminated: torch.Tensor,
    truncated: torch.Tensor,
    out_of_area: torch.Tensor,
    time_s: torch.Tensor,
    limit_s: torch.Tensor,
    ref_decisions: int,
    decision_period_s: float,
    gamma: float,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """:func:`usvsim.task.horizon.apply_reward_horizon` ``"fixed"`` with each episode's own
    number of decisions K_i (from its time limit ``limit_s``) against ``ref_decisions`` K_ref, as
    ``OpenWaterVectorEnv``: leaving the area terminates, and a terminating step adds the
    discounted reward of staying until K_ref, the clock advanced by K_ref − K_i. Tensors (N,)."""
    dp, g = decision_period_s, gamma
    k_i = torch.ceil(limit_s / dp - 1e-9)
    shifted = time_s + (ref_decisions - k_i) * dp
    left = out_of_area & truncated
    terminated, truncated = terminated | left, truncated & ~left
    m = torch.clamp(ref_decisions - torch.round(shifted / dp), min=0.0)
    factor = 1.0 + g * (1.0 - g**m) / (1.0 - g)
    return torch.where(terminated, reward * factor, reward), terminated, truncated
