"""Radar tracks as a ``scene`` observation: the perception of ``vo-radar`` and ``sb-mpc-radar``.

The classical pipeline radar → detections → tracks → collision avoidance: every decision the
radar image of the ``radar+nav`` observation (:mod:`usvsim.task.observations`) goes through
:class:`usvsim.nav.tracker.RadarTracker` (detections placed in NED with the own navigation
estimate, one constant-velocity Kalman filter per track, M-of-N confirmation), and the confirmed
tracks become the obstacle list of a ``scene`` observation
(:func:`usvsim.task.observations.scene_observation`: the k = 8 nearest by edge distance) that an
unchanged ``scene`` helmsman (``vo``, ``sb-mpc``) reads. The ``scene`` helmsmen read the true
scene (every obstacle, everywhere, exact); their radar twins only what the radar has seen: ±120°
and 200 m, quantised to 4 m × 2°, degraded as the episode's radar is, with the tracker's lags.

One choice of the conversion: a track's velocity is passed on only where it is significant,
``vᵀ P_vv⁻¹ v > moving_chi2`` (χ²₂, 99 %): a pole's track jitters by a few tenths of a m/s,
which ``vo`` and ``sb-mpc`` would read as a moving vessel (their threshold 0.3 m/s), with the
vessel margin, a predicted motion and COLREG costs; an insignificant velocity is reported as 0
(a static obstacle).

The goal comes from the observation's standardised goal (range, bearing; inverted exactly up to
float32) and the navigation estimate, as the ``scene`` helmsmen get it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.nav.tracker import RadarTracker, TrackerConfig, TrackTargets, inv2
from usvsim.task.batch import ActionKind
from usvsim.task.observations import GOAL_STANDARDIZATION, ObservationKind, scene_observation
from usvsim.task.radar import RadarConfig

__all__ = ["MOVING_CHI2", "RadarScene", "TrackedSceneHelmsman", "targets_to_scene"]

FloatArray = NDArray[np.float64]
MOVING_CHI2 = 9.21  # χ²₂ at 99 %: a velocity significantly different from 0


def targets_to_scene(
    targets: TrackTargets,
    nav: NDArray[np.floating],
    goal_standardized: NDArray[np.floating],
    moving_chi2: float,
) -> NDArray[np.float32]:
    """The ``scene`` observation (N, 52) of the tracks ``targets`` as seen from the navigation
    estimate ``nav`` (N, 5) = [x_N, y_E, ψ, v_N, v_E] with the goal ``goal_standardized`` (N, 2)
    (module docstring)."""
    nav64: FloatArray = np.asarray(nav, dtype=np.float64)
    pos, psi, vel = nav64[:, 0:2], nav64[:, 2], nav64[:, 3:5]
    g = np.asarray(goal_standardized, dtype=np.float64)
    mean, std = np.asarray(GOAL_STANDARDIZATION.mean), np.asarray(GOAL_STANDARDIZATION.std)
    r_g, b_g = (g * std + mean).T
    goal_ne = pos + r_g[:, None] * np.stack([np.cos(psi + b_g), np.sin(psi + b_g)], axis=-1)
    v = targets.velocity_ne
    p_vv = targets.covariance[..., 2:, 2:]
    significance = np.einsum("...i,...ij,...j->...", v, inv2(p_vv), v)
    v_reported = np.where((significance > moving_chi2)[..., None], v, 0.0)
    return scene_observation(
        pos, psi, vel, goal_ne, targets.position_ne, targets.radius_m, v_reported, targets.valid
    )


@dataclass
class RadarScene:
    """``radar+nav`` observations → ``scene`` observations through one tracker per batch
    (module docstring); N boats at once.

    ``tracker`` holds the tracks after each call (for inspection and the tracker benchmark);
    ``last_scene`` the ``scene`` observation it returned last.
    """

    tracker_config: TrackerConfig = field(default_factory=TrackerConfig)
    radar: RadarConfig = field(default_factory=RadarConfig)
    moving_chi2: float = MOVING_CHI2

    def __post_init__(self) -> None:
        self.tracker = RadarTracker(self.radar, self.tracker_config)
        self.last_scene: NDArray[np.float32] | None = None

    def reset(self, n_boats: int) -> None:
        self.tracker.reset(n_boats)
        self.last_scene = None

    def __call__(self, observation: dict[str, Any]) -> NDArray[np.float32]:
        """The ``scene`` observation (N, 52) of ``radar+nav`` observations (dict of N-row
        arrays: radar, nav, goal), after the tracker's update with this radar image."""
        nav = np.asarray(observation["nav"], dtype=np.float64)
        targets = self.tracker.update(observation["radar"], nav[:, 0:2], nav[:, 2])
        self.last_scene = targets_to_scene(targets, nav, observation["goal"], self.moving_chi2)
        return self.last_scene


@dataclass
class TrackedSceneHelmsman(ABC):
    """A ``scene`` helmsman on tracked radar returns, ``radar+nav`` input (module docstring).

    A subclass names the ``scene`` helmsman (:meth:`make_scene_helmsman`, from its own config
    field); this class owns the perception. ``tracker`` holds the tracks after each decision
    (for inspection and the tracker benchmark); ``last_scene`` the ``scene`` observation the
    ``scene`` helmsman was given.
    """

    tracker_config: TrackerConfig = field(default_factory=TrackerConfig)
    radar: RadarConfig = field(default_factory=RadarConfig)
    moving_chi2: float = MOVING_CHI2  # χ²₂ at 99 %: a velocity significantly different from 0
    observation: ObservationKind = field(default="radar+nav", init=False)
    action: ActionKind = field(default="gaussian", init=False)

    def __post_init__(self) -> None:
        self.perception = RadarScene(self.tracker_config, self.radar, self.moving_chi2)
        self.scene_helmsman = self.make_scene_helmsman()

    @abstractmethod
    def make_scene_helmsman(self) -> Any:
        """The ``scene`` helmsman (``reset(n)``, ``act(scene) -> actions``) that steers."""

    @property
    def tracker(self) -> RadarTracker:
        """The radar tracker (its tracks after the last decision)."""
        return self.perception.tracker

    @property
    def last_scene(self) -> NDArray[np.float32] | None:
        """The ``scene`` observation of the last decision."""
        return self.perception.last_scene

    def reset(self, n_boats: int) -> None:
        self.perception.reset(n_boats)
        self.scene_helmsman.reset(n_boats)

    def act(self, observation: dict[str, Any]) -> NDArray[np.float32]:
        """Gaussian actions (N, 1) from ``radar+nav`` observations (dict of N-row arrays)."""
        actions: NDArray[np.float32] = self.scene_helmsman.act(self.perception(observation))
        return actions
