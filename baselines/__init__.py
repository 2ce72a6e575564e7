"""Classical helmsmen with the interface of learned policies.

They satisfy the :class:`usvsim.helm.protocol.Helmsman` protocol.

:mod:`baselines.los` — ``los``: line-of-sight guidance from the start to the goal (it hits the
pole, as the reference study expects of a helmsman that does not look out).
:mod:`baselines.avoid` — ``los-avoid``: the same plus a collision-cone avoidance layer.

Both read only the positional observation (``observation = "positional"``) and give gaussian
actions (``action = "gaussian"``): Δψ clipped to ±30° every 2 s.
"""

from baselines.avoid import AvoidHelmsman, CollisionCone, cone_heading_change
from baselines.los import (
    DEFAULT_LOS_CONFIG,
    LandmarkPose,
    LOSHelmsman,
    heading_change_to_action,
    landmark_pose,
)

__all__ = [
    "DEFAULT_LOS_CONFIG",
    "AvoidHelmsman",
    "CollisionCone",
    "LOSHelmsman",
    "LandmarkPose",
    "cone_heading_change",
    "heading_change_to_action",
    "landmark_pose",
]
