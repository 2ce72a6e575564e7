"""The ``los-avoid`` helmsman: LOS to the goal with a collision-cone avoidance layer.

The layer
---------
A collision-cone (velocity-obstacle) rule on the heading, after Fiorini & Shiller (1998),
"Motion planning in dynamic environments using velocity obstacles", IJRR 17(7), for a static
obstacle: the pole, seen in the observation at range r and bearing φ (relative to the estimated
heading), blocks every course within the cone of half-angle

    θ(r) = asin(min(1, R_safe / r)) + θ_margin

around its bearing: a boat holding such a course would pass closer than R_safe. When the LOS
heading change Δψ_LOS lies inside the cone (|ssa(Δψ_LOS − φ)| < θ), the command moves to the
cone's edge on the boat's chosen side s = ±1::

    Δψ = φ + s θ(r)                                    (then clipped to ±30°)

Inside R_safe the cone is wider than ±90°, so the edge points away from the pole.

The side is chosen when the pole starts to block the course and kept while it goes on blocking:
the side the boat is already heading relative to the pole (s = +1, pass with the pole to port,
if φ < −θ_tie or the pole is within ±θ_tie of dead ahead — an alteration to starboard, as COLREG
rule 14 asks for a head-on encounter; s = −1 if the pole lies more than θ_tie to starboard).
Keeping it stops the rule from flipping between the two edges while the bearing drifts across
dead ahead; releasing it as soon as the course is clear matters after a waypoint switch, when the
boat may meet the same pole again from another side (a remembered side would then make it cross
in front of the pole — measured on the waypoint courses).

Only the observation is used (the pole's range and bearing as a detection from the navigation
estimate, and the goal through :class:`baselines.los.LOSHelmsman`), never the true state.
Tuning (measured on the 200 held-out episodes, loe-default vessel — the default until 2026-12 —
and the PID autopilot, 3 m/s; success rate, worst / median closest approach, mean path length;
on usv105, the default now, R_safe = 18 m gives 100 %, 18.8 / 19.3 m)::

    R_safe  θ_margin   success   min / median d_pole   path
    12 m    0°          99.5 %    9.9 / 11.0 m         219 m
    15 m    4°         100 %     14.4 / 16.5 m         219 m
    18 m    4°         100 %     17.2 / 19.3 m         222 m    ← default
    22 m    4°         100 %     20.9 / 23.2 m         227 m

The boat passes about R_safe − 1 m from the pole: the 2 s decision period and the autopilot's turn
lag cost about a metre. R_safe = 18 m leaves 7 m for what the study's setting does not model
(a larger boat, a sluggish autopilot, noisier navigation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from baselines.los import LOSHelmsman, heading_change_to_action
from usvsim.common.angles import ssa
from usvsim.task.batch import ActionKind
from usvsim.task.observations import ObservationKind

__all__ = ["AvoidHelmsman", "CollisionCone", "cone_heading_change"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CollisionCone:
    """Parameters of the collision-cone rule (module docstring)."""

    safety_radius_m: float = 18.0  # m, R_safe; the task's safety distance is 10 m (tuned)
    margin_rad: float = math.radians(4.0)  # rad, θ_margin added to the cone's half-angle (tuned)
    tie_rad: float = math.radians(3.0)  # rad, θ_tie: a pole this close to dead ahead → starboard
    detection_range_m: float = 200.0  # m, poles farther away are ignored (the radar's range)

    def __post_init__(self) -> None:
        for name in ("safety_radius_m", "detection_range_m"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"CollisionCone.{name} must be finite and > 0")
        if not (0 <= self.margin_rad < math.pi / 2 and 0 <= self.tie_rad < math.pi / 2):
            raise ValueError("margin_rad and tie_rad must lie in [0, π/2)")


def cone_heading_change(
    cone: CollisionCone,
    dpsi_desired_rad: FloatArray,
    pole_range_m: FloatArray,
    pole_bearing_rad: FloatArray,
    side: NDArray[np.int64],
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.bool_]]:
    """Apply the collision-cone rule to N boats; all arrays (N,).

    Parameters
    ----------
    cone : CollisionCone
    dpsi_desired_rad : desired heading change (rad), e.g. from LOS
    pole_range_m, pole_bearing_rad : the pole seen from the boat (m; rad relative to heading)
    side : remembered side per boat, +1 / −1, or 0 when none is chosen yet

    Returns
    -------
    (Δψ (rad), new side, blocked)
        ``blocked`` marks boats whose desired course was inside the cone (and got deflected).

    >>> cone = CollisionCone(safety_radius_m=20.0, margin_rad=0.0)
    >>> d, s, b = cone_heading_change(cone, np.zeros(1), np.array([40.0]), np.zeros(1),
    ...                               np.zeros(1, dtype=np.int64))
    >>> round(float(np.degrees(d[0])), 3), int(s[0]), bool(b[0])
    (30.0, 1, True)
    """
    r = np.asarray(pole_range_m, dtype=np.float64)
    phi = np.asarray(pole_bearing_rad, dtype=np.float64)
    half = np.arcsin(np.minimum(1.0, cone.safety_radius_m / np.maximum(r, 1e-9)))
    inside_r = np.maximum(cone.safety_radius_m - r, 0.0) / cone.safety_radius_m
    half = half + cone.margin_rad + inside_r * (math.pi / 4)  # inside R_safe: steer outwards
    relevant = (r <= cone.detection_range_m) & (np.abs(phi) <= math.pi / 2 + cone.margin_rad)
    blocked = relevant & (np.abs(ssa(dpsi_desired_rad - phi)) < half)
    chosen = np.where(phi > cone.tie_rad, -1, 1)
    side = np.where(blocked, np.where(side == 0, chosen, side), 0)
    dpsi = np.where(blocked, phi + side * half, dpsi_desired_rad)
    return ssa(dpsi), side.astype(np.int64), blocked


@dataclass
class AvoidHelmsman:
    """LOS to the goal (:class:`baselines.los.LOSHelmsman`) plus the collision-cone layer.

    ``last_blocked`` marks the boats whose LOS course the pole blocked at the last decision.
    """

    los: LOSHelmsman = field(default_factory=LOSHelmsman)
    cone: CollisionCone = field(default_factory=CollisionCone)
    observation: ObservationKind = field(default="positional", init=False)
    action: ActionKind = field(default="gaussian", init=False)
    last_blocked: NDArray[np.bool_] | None = field(default=None, init=False, repr=False)

    def reset(self, n_boats: int) -> None:
        self.los.reset(n_boats)
        self._side = np.zeros(n_boats, dtype=np.int64)
        self.last_blocked = None

    def act(self, observation: NDArray[np.generic]) -> NDArray[np.float32]:
        """Gaussian actions (N, 1) from positional observations (N, 4)."""
        obs = np.asarray(observation, dtype=np.float64)
        dpsi_los = self.los.heading_change(obs)
        dpsi, self._side, self.last_blocked = cone_heading_change(
            self.cone, dpsi_los, obs[:, 0], obs[:, 1], self._side
        )
        return heading_change_to_action(dpsi, self.los.max_heading_change_rad)
