"""The ``vo-radar`` helmsman: ``vo`` (:mod:`baselines.velocity_obstacle`) fed by a radar tracker.

Every decision the radar image of the ``radar+nav`` observation goes through the tracker of
:class:`baselines.radar_scene.RadarScene` (:mod:`usvsim.nav.tracker`), and the confirmed tracks
become the ``scene`` observation that the unchanged :class:`baselines.velocity_obstacle.VOHelmsman`
reads. ``vo`` reads the true scene (every obstacle, everywhere, exact); ``vo-radar`` only what its
radar has seen (:mod:`baselines.radar_scene`: range, sector, quantisation, the episode's radar
degradation, the tracker's lags, velocities passed on only where significant).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from baselines.radar_scene import TrackedSceneHelmsman, targets_to_scene
from baselines.velocity_obstacle import VOConfig, VOHelmsman

__all__ = ["VORadarHelmsman", "targets_to_scene"]


@dataclass
class VORadarHelmsman(TrackedSceneHelmsman):
    """``vo`` on tracked radar returns (module docstring), ``radar+nav`` input; the tracker and
    its settings as :class:`baselines.radar_scene.TrackedSceneHelmsman`."""

    config: VOConfig = field(default_factory=VOConfig)

    def make_scene_helmsman(self) -> VOHelmsman:
        return VOHelmsman(self.config)

    @property
    def last_avoiding(self) -> NDArray[np.bool_] | None:
        """Boats whose course to the goal was blocked at the last decision (as ``vo``'s)."""
        avoiding: NDArray[np.bool_] | None = self.scene_helmsman.last_avoiding
        return avoiding
