"""Line-of-sight guidance for straight-line path following of N boats through waypoints.

:mod:`guidance.waypoints` holds the padded waypoint lists and the segment switching;
:mod:`guidance.los` the LOS, ILOS and ALOS laws and the LOS observer.
"""

from guidance.los import (
    GuidanceLaw,
    GuidanceOutput,
    GuidanceState,
    LOSConfig,
    LOSGuidance,
    initial_guidance_state,
    los_step,
    reset_guidance_state,
)
from guidance.waypoints import PathErrors, WaypointManager, WaypointPath, advance_segments

__all__ = [
    "GuidanceLaw",
    "GuidanceOutput",
    "GuidanceState",
    "LOSConfig",
    "LOSGuidance",
    "PathErrors",
    "WaypointManager",
    "WaypointPath",
    "advance_segments",
    "initial_guidance_state",
    "los_step",
    "reset_guidance_state",
]
