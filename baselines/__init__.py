"""Classical helmsmen with the interface of learned policies.

They satisfy the :class:`usvsim.helm.protocol.Helmsman` protocol.

:mod:`baselines.los` — ``los``: line-of-sight guidance from the start to the goal (it hits the
pole, as the reference study expects of a helmsman that does not look out).
:mod:`baselines.avoid` — ``los-avoid``: the same plus a collision-cone avoidance layer.
:mod:`baselines.velocity_obstacle` — ``vo``: LOS to the goal with velocity obstacles and COLREG
(Kuwata et al. 2014), for many and moving obstacles.

``los`` and ``los-avoid`` read only the positional observation (``observation = "positional"``),
``vo`` the k-nearest ``scene`` observation; all give gaussian actions (``action = "gaussian"``):
Δψ clipped to ±30° every 2 s.
"""

from baselines.avoid import AvoidHelmsman, CollisionCone, cone_heading_change
from baselines.los import (
    DEFAULT_LOS_CONFIG,
    LandmarkPose,
    LOSHelmsman,
    heading_change_to_action,
    landmark_pose,
)
from baselines.velocity_obstacle import VOConfig, VOHelmsman, vo_course

__all__ = [
    "DEFAULT_LOS_CONFIG",
    "AvoidHelmsman",
    "CollisionCone",
    "LOSHelmsman",
    "LandmarkPose",
    "VOConfig",
    "VOHelmsman",
    "cone_heading_change",
    "heading_change_to_action",
    "landmark_pose",
    "vo_course",
]
