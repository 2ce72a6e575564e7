"""The ``sb-mpc-radar`` helmsman: ``sb-mpc`` (:mod:`baselines.sbmpc`) fed by a radar tracker.

The same pipeline as ``vo-radar`` (:mod:`baselines.vo_radar`): every decision the radar image of
the ``radar+nav`` observation goes through the tracker of :class:`baselines.radar_scene.
RadarScene` (:mod:`usvsim.nav.tracker`), and the confirmed tracks become the ``scene``
observation that the unchanged :class:`baselines.sbmpc.SBMPCHelmsman` reads (its behaviours,
costs and COLREG terms as on the true scene). ``sb-mpc`` sees every obstacle exactly;
``sb-mpc-radar`` only what its radar has seen (±120°, 200 m, quantised, degraded as the episode's
radar is), with the tracker's lags, and each target's velocity only once the tracker's estimate
of it is significant (:mod:`baselines.radar_scene`). SB-MPC's encounter classification (head-on,
crossing, overtaking) reads that estimated velocity, so a late or noisy velocity estimate moves
its COLREG decisions too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from baselines.radar_scene import TrackedSceneHelmsman
from baselines.sbmpc import SBMPCConfig, SBMPCHelmsman

__all__ = ["SBMPCRadarHelmsman"]


@dataclass
class SBMPCRadarHelmsman(TrackedSceneHelmsman):
    """``sb-mpc`` on tracked radar returns (module docstring), ``radar+nav`` input; the tracker
    and its settings as :class:`baselines.radar_scene.TrackedSceneHelmsman`."""

    config: SBMPCConfig = field(default_factory=SBMPCConfig)

    def make_scene_helmsman(self) -> SBMPCHelmsman:
        return SBMPCHelmsman(self.config)
