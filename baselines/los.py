"""The ``los`` helmsman: line-of-sight guidance from the start to the goal, as a Δψ action.

What the boat knows
-------------------
A helmsman sees only its observation (:mod:`usvsim.task.observations`), here the positional one,
``[r_pole, φ_pole, r_goal, φ_goal]`` of the navigation estimate, bearings relative to the
estimated heading (clockwise positive). Pole and goal are fixed landmarks, so the two vectors
fix the boat's estimated pose in a frame anchored on them (:func:`landmark_pose`): origin at the
goal, x axis from the goal towards the pole. That pose is the navigation estimate up to a rigid
motion — no true state and nothing beyond the observation is used. In the body frame (x ahead,
y starboard) the landmarks are g_b = r_goal (cos φ_goal, sin φ_goal) and p_b likewise; with
α = atan2 of p_b − g_b (the frame's x axis seen from the boat)::

    ψ_F = −α,      p_F = −R(ψ_F) g_b        (R(θ) the rotation by θ)

Guidance
--------
When the helmsman first sees a goal (after ``reset``, or when the landmarks change, as at a
waypoint switch in :mod:`usvsim.task.waypoints`) it lays a straight path from where the boat is to
the goal and follows it with :func:`guidance.los.los_step` (proportional LOS by default; Fossen
2021, §12.4.2). Every decision (2 s) the heading reference becomes the action::

    Δψ = clip(ssa(ψ_ref − ψ̂), −30°, +30°),    gaussian action a = Δψ / 30°

The environment sets ψ_ref = ψ̂ + Δψ, so the ±30° clip is the only reference rate limit; the LOS
observer is off by default because at h = 2 s its gain product h ω_f is not small (h ω_f = 1 at
the default ω_f = 0.5 rad/s is dead-beat with a one-step overshoot of the raw command).

In the pole task the start, the pole and the goal lie on one line, so plain LOS steers straight
into the pole: it is the baseline that must fail (issue 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from guidance.los import GuidanceOutput, LOSConfig, LOSGuidance
from guidance.waypoints import WaypointPath
from usvsim.common.angles import ssa
from usvsim.task.batch import ActionKind
from usvsim.task.observations import ObservationKind

__all__ = [
    "DEFAULT_LOS_CONFIG",
    "LOSHelmsman",
    "LandmarkPose",
    "heading_change_to_action",
    "landmark_pose",
]

FloatArray = NDArray[np.float64]

DEFAULT_LOS_CONFIG = LOSConfig(law="los", lookahead_m=20.0, observer_omega_radps=None)
"""Proportional LOS, Δ = 20 m, no observer (module docstring); R_switch = 10 m, the goal radius."""


@dataclass(frozen=True)
class LandmarkPose:
    """Pose of N boats in the goal-anchored frame (module docstring); all arrays (N,) or (N, 2).

    ``pair_distance_m`` is |pole − goal|, the same in every frame: it changes only when a
    landmark does (a new goal or another pole), which is how a helmsman notices a switch.
    """

    pos_m: FloatArray  # (N, 2) m, boat position, origin at the goal, x towards the pole
    psi_rad: FloatArray  # (N,) rad, boat heading in that frame
    goal_range_m: FloatArray  # (N,) m
    pair_distance_m: FloatArray  # (N,) m


def landmark_pose(observation: NDArray[np.generic]) -> LandmarkPose:
    """Pose of N boats from positional observations (N, 4) ``[r_p, φ_p, r_g, φ_g]``.

    >>> obs = np.array([[50.0, 0.0, 220.0, 0.0]])  # pole 50 m, goal 220 m dead ahead
    >>> pose = landmark_pose(obs)
    >>> (pose.pos_m.round(6) + 0.0).tolist(), float(pose.psi_rad[0]), float(pose.pair_distance_m[0])
    ([[220.0, 0.0]], -3.141592653589793, 170.0)
    """
    obs = np.asarray(observation, dtype=np.float64)
    if obs.ndim != 2 or obs.shape[1] != 4:
        raise ValueError(f"positional observations must have shape (N, 4), got {obs.shape}")
    r_p, b_p, r_g, b_g = obs.T
    goal_b = np.stack([r_g * np.cos(b_g), r_g * np.sin(b_g)], axis=-1)
    pole_b = np.stack([r_p * np.cos(b_p), r_p * np.sin(b_p)], axis=-1)
    axis_b = pole_b - goal_b
    psi = ssa(-np.arctan2(axis_b[:, 1], axis_b[:, 0]))
    c, s = np.cos(psi), np.sin(psi)
    pos = -np.stack([c * goal_b[:, 0] - s * goal_b[:, 1], s * goal_b[:, 0] + c * goal_b[:, 1]], -1)
    return LandmarkPose(
        pos_m=pos,
        psi_rad=psi,
        goal_range_m=r_g,
        pair_distance_m=np.hypot(axis_b[:, 0], axis_b[:, 1]),
    )


def heading_change_to_action(dpsi_rad: FloatArray, max_change_rad: float) -> NDArray[np.float32]:
    """Clip Δψ (N,) rad to ±``max_change_rad``; scale to the gaussian action (N, 1) in [-1, 1]."""
    a = np.clip(np.asarray(dpsi_rad, dtype=np.float64) / max_change_rad, -1.0, 1.0)
    return a.astype(np.float32)[:, None]


@dataclass
class LOSHelmsman:
    """Plain LOS from the boat's position when it first sees the goal to the goal.

    Parameters
    ----------
    config : LOSConfig
        Guidance law and parameters (default :data:`DEFAULT_LOS_CONFIG`).
    decision_period_s : float
        Time between ``act`` calls (s): the Euler step of the guidance states; the scenario's 2 s.
    max_heading_change_rad : float
        Action bound (rad): the scenario's 30°.
    switch_tolerance_m : float
        A change of the pole–goal distance above this (m) means a landmark changed (float32
        observations are exact to ~1e-4 m here; the estimate's noise does not move landmarks).
    goal_jump_m : float
        A jump of the goal range above this (m) in one period also means a new goal (the boat
        covers ~6 m per period).

    ``observation`` and ``action`` tell :func:`usvsim.evaluation.episodes.evaluate` what this
    helmsman needs.
    ``last_output`` holds the latest :class:`guidance.los.GuidanceOutput` (cross-track errors).
    """

    config: LOSConfig = DEFAULT_LOS_CONFIG
    decision_period_s: float = 2.0
    max_heading_change_rad: float = math.radians(30.0)
    switch_tolerance_m: float = 0.5
    goal_jump_m: float = 20.0
    observation: ObservationKind = field(default="positional", init=False)
    action: ActionKind = field(default="gaussian", init=False)
    last_output: GuidanceOutput | None = field(default=None, init=False, repr=False)

    def reset(self, n_boats: int) -> None:
        """Forget all paths; each boat lays a new one at its next observation."""
        self._n = int(n_boats)
        self._guidance: LOSGuidance | None = None
        self._pair = np.full(self._n, np.nan)
        self._goal_range = np.full(self._n, np.nan)
        self.last_output = None

    def heading_change(self, observation: NDArray[np.generic]) -> FloatArray:
        """The LOS heading change ssa(ψ_ref − ψ̂) (N,) rad, before clipping; advances guidance."""
        pose = landmark_pose(observation)
        if pose.pos_m.shape[0] != self._n:
            raise ValueError(f"reset({pose.pos_m.shape[0]}) first: this helmsman has {self._n}")
        new = ~(np.abs(pose.pair_distance_m - self._pair) <= self.switch_tolerance_m) | ~(
            np.abs(pose.goal_range_m - self._goal_range) <= self.goal_jump_m
        )  # NaN (first call) compares False, so it counts as new
        self._pair, self._goal_range = pose.pair_distance_m, pose.goal_range_m
        if new.any():
            path = self._path_from(pose)
            if self._guidance is None:
                self._guidance = LOSGuidance(path, self.config)
            else:
                self._guidance.reset(new, path)
        assert self._guidance is not None
        out = self._guidance.update(pose.pos_m, pose.psi_rad, self.decision_period_s)
        self.last_output = out
        return ssa(out.psi_ref_rad - pose.psi_rad)

    def act(self, observation: NDArray[np.generic]) -> NDArray[np.float32]:
        """Gaussian actions (N, 1): the clipped LOS heading change over 30°."""
        return heading_change_to_action(
            self.heading_change(observation), self.max_heading_change_rad
        )

    def _path_from(self, pose: LandmarkPose) -> WaypointPath:
        """Boat → goal (the origin) for every boat; a boat too close to its goal gets its start
        moved back along the same line so the segment is longer than twice R_switch."""
        goal = np.zeros_like(pose.pos_m)
        dist = np.hypot(pose.pos_m[:, 0], pose.pos_m[:, 1])
        min_len = 2.0 * self.config.switch_radius_m + 1.0
        heading = np.stack([np.cos(pose.psi_rad), np.sin(pose.psi_rad)], axis=-1)
        unit = np.where(
            (dist > 1e-6)[:, None], pose.pos_m / np.maximum(dist, 1e-6)[:, None], -heading
        )
        start = np.where((dist >= min_len)[:, None], pose.pos_m, unit * min_len)
        return WaypointPath(points_m=np.stack([start, goal], axis=1), counts=np.full(self._n, 2))
