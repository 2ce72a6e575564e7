"""The scene of a demonstration on the open-water family: what ``usvsim-demo/2`` adds to ``/1``.

A ``usvsim-demo/1`` run is about one pole (``poles_ne[pole_index]``) and its goal is where the
run ended. A run on the open-water family (:mod:`usvsim.task.openwater`) passes several and
moving obstacles on its way to a goal anywhere, so its metadata carries the scene as the
helmsman met it, in the site's NED frame (SI units), under the key ``"scene"``::

    "scene": {
      "goal_ne": [x_N, y_E],                       m
      "episode_start_s": t0,                       s, the log time of the episode's t = 0
      "obstacles": [[x_N, y_E, R], ...],            m, static discs
      "vessels": [[x0_N, y0_E, χ, V, ω, R], ...],   m, rad, m/s, rad/s, m: moving discs
      "radar": {"clutter_probability": p, "speckle": s, "missed_probability": m,
                "noise_amplitude": a, "seed": k}    optional: the radar's degradation
    }

``radar`` (optional; without it the radar image is clean) says how degraded the helmsman's radar
was (:class:`usvsim.task.openwater.RadarQuality`; probabilities and speckle in [0, 1], noise
amplitude in [0, 255]) and the integer ``seed`` (0 <= k < 2⁶⁴) of its noise stream: the
radar observations of the run are then drawn as the simulator draws them for an episode with
that quality and radar seed (:mod:`usvsim.task.scene_radar`, frame k at decision k), so that a
discriminator compares like with like.

A vessel at log time t is where :func:`usvsim.task.openwater.vessel_motion` puts it at episode
time t − t0 (a constant or slowly turning course, as AIS tracks are usually summarised). Every
value must be a finite number; radii in (0, 100] m, positions within the site's
:attr:`learning.imitation.plausibility.Plausibility.max_distance_m` of the origin, vessel speeds
at most its ``max_speed_mps``. :meth:`DemoScene.from_meta` raises
:class:`learning.imitation.plausibility.DemoFormatError` naming the file and the entry.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from learning.imitation.plausibility import PLAUSIBLE, DemoFormatError, finite_number
from usvsim.task.openwater import OpenWaterEpisode, RadarQuality, vessel_motion

__all__ = ["FORMAT_SCENE", "POLE_RADIUS_M", "DemoScene"]

FloatArray = NDArray[np.float64]
FORMAT_SCENE = "usvsim-demo/2"
POLE_RADIUS_M = 1.0  # m, distances are pole-equivalent (usvsim.task.openwater)


@dataclass(frozen=True)
class DemoScene:
    """A run's goal and obstacles (module docstring): ``obstacles`` (J, 3), ``vessels`` (M, 6)."""

    goal_ne: FloatArray
    episode_start_s: float
    obstacles: FloatArray
    vessels: FloatArray
    radar: RadarQuality | None = None  # None: a clean radar image
    radar_seed: int = 0

    @classmethod
    def from_episode(cls, episode: OpenWaterEpisode, episode_start_s: float = 0.0) -> DemoScene:
        """The scene of a family episode."""
        v = [
            [x.x0_n, x.y0_e, x.course_rad, x.speed_mps, x.turn_rate_radps, x.radius_m]
            for x in episode.vessels
        ]
        return cls(
            np.asarray(episode.goal_ne, dtype=float),
            float(episode_start_s),
            np.asarray(episode.obstacles, dtype=float).reshape(-1, 3),
            np.asarray(v, dtype=float).reshape(-1, 6),
            episode.radar,
            episode.radar_seed,
        )

    def to_meta(self) -> dict[str, Any]:
        """The ``"scene"`` metadata object (JSON-ready)."""
        meta: dict[str, Any] = {
            "goal_ne": [float(v) for v in self.goal_ne],
            "episode_start_s": self.episode_start_s,
            "obstacles": self.obstacles.tolist(),
            "vessels": self.vessels.tolist(),
        }
        if self.radar is not None:
            meta["radar"] = {**dataclasses.asdict(self.radar), "seed": self.radar_seed}
        return meta

    @classmethod
    def from_meta(cls, path: str, meta: dict[str, Any]) -> DemoScene:
        """Read and check ``meta["scene"]`` (module docstring); :class:`DemoFormatError` if bad."""
        where = f"{path}, line 1: metadata scene"
        scene = meta.get("scene")
        if not isinstance(scene, dict):
            raise DemoFormatError(f"{where} must be an object with goal_ne, episode_start_s, "
                                  "obstacles and vessels")  # fmt: skip
        missing = [
            k for k in ("goal_ne", "episode_start_s", "obstacles", "vessels") if k not in scene
        ]
        if missing:
            raise DemoFormatError(f"{where} lacks {', '.join(missing)}")
        goal = _rows(where, "goal_ne", [scene["goal_ne"]], 2)[0]
        t0 = scene["episode_start_s"]
        if not finite_number(t0):
            raise DemoFormatError(f"{where}.episode_start_s must be a number (s), got {t0!r}")
        obstacles = _rows(where, "obstacles", scene["obstacles"], 3)
        vessels = _rows(where, "vessels", scene["vessels"], 6)
        limit = PLAUSIBLE.max_distance_m
        for name, rows, pos in (("goal_ne", goal[None], [0, 1]), ("obstacles", obstacles, [0, 1]),
                                ("vessels", vessels, [0, 1])):  # fmt: skip
            far = np.flatnonzero(np.hypot(rows[:, pos[0]], rows[:, pos[1]]) > limit)
            if far.size:
                raise DemoFormatError(
                    f"{where}.{name}[{int(far[0])}] lies more than {limit:g} m from the origin"
                )
        for name, radii in (("obstacles", obstacles[:, 2]), ("vessels", vessels[:, 5])):
            bad = np.flatnonzero(~((radii > 0) & (radii <= 100.0)))
            if bad.size:
                raise DemoFormatError(
                    f"{where}.{name}[{int(bad[0])}] radius {float(radii[bad[0]]):g} is not in "
                    "(0, 100] m"
                )
        fast = np.flatnonzero(np.abs(vessels[:, 3]) > PLAUSIBLE.max_speed_mps)
        if fast.size:
            raise DemoFormatError(
                f"{where}.vessels[{int(fast[0])}] speed {float(vessels[fast[0], 3]):g} m/s is over "
                f"{PLAUSIBLE.max_speed_mps:g} m/s"
            )
        radar, seed = _radar(where, scene["radar"]) if "radar" in scene else (None, 0)
        return cls(goal, float(t0), obstacles, vessels, radar, seed)

    @property
    def n_discs(self) -> int:
        return int(self.obstacles.shape[0] + self.vessels.shape[0])

    def radii_m(self) -> FloatArray:
        """Radii (J + M,) m: statics, then vessels."""
        return np.concatenate([self.obstacles[:, 2], self.vessels[:, 5]])

    def discs(self, t_s: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Centres (K, J + M, 2) m and velocities over ground (K, J + M, 2) m/s at log times
        ``t_s`` (K,): statics, then vessels (module docstring)."""
        t = np.asarray(t_s, dtype=float)
        k = t.size
        statics = np.broadcast_to(self.obstacles[None, :, :2], (k, self.obstacles.shape[0], 2))
        v = self.vessels
        pos, vel = vessel_motion(
            v[None, :, 0:2], v[None, :, 2], v[None, :, 3], v[None, :, 4],
            (t - self.episode_start_s)[:, None],
        )  # fmt: skip
        centres = np.concatenate([statics, pos], axis=1)
        velocity = np.concatenate([np.zeros_like(statics), vel], axis=1)
        return centres, velocity

    def distance_m(self, t_s: FloatArray, pos_ne: FloatArray) -> FloatArray:
        """Pole-equivalent distance (K,) m from positions ``pos_ne`` (K, 2) at log times ``t_s``
        to the nearest disc: |p − c| − R + 1 m (the task's safety measure); inf without discs."""
        centres, _ = self.discs(t_s)
        d = np.hypot(*np.moveaxis(centres - np.asarray(pos_ne)[:, None, :], -1, 0))
        return np.min(d - self.radii_m() + POLE_RADIUS_M, axis=1, initial=math.inf)


def _radar(where: str, value: Any) -> tuple[RadarQuality, int]:
    """The optional ``radar`` object (module docstring), or DemoFormatError."""
    names = [f.name for f in dataclasses.fields(RadarQuality)]
    if not isinstance(value, dict) or set(value) != {*names, "seed"}:
        raise DemoFormatError(
            f"{where}.radar must be an object with {', '.join(names)} and seed, got {value!r}"
        )
    for name in names:
        high = 255.0 if name == "noise_amplitude" else 1.0
        x = value[name]
        if not (finite_number(x) and 0.0 <= x <= high):
            raise DemoFormatError(
                f"{where}.radar.{name} must be a number in [0, {high:g}], got {x!r}"
            )
    seed = value["seed"]
    if not (isinstance(seed, int) and not isinstance(seed, bool) and 0 <= seed < 2**64):
        raise DemoFormatError(f"{where}.radar.seed must be an integer in [0, 2**64), got {seed!r}")
    return RadarQuality(**{name: float(value[name]) for name in names}), seed


def _rows(where: str, name: str, value: Any, width: int) -> FloatArray:
    """A list of ``width``-number lists as an (n, width) array, or DemoFormatError."""
    ok = isinstance(value, list) and all(
        isinstance(r, list) and len(r) == width and all(finite_number(x) for x in r) for r in value
    )
    if not ok:
        raise DemoFormatError(f"{where}.{name} must be a list of [{width} numbers], got {value!r}")
    return np.asarray(value, dtype=float).reshape(-1, width)
