"""Open-water episodes packed as arrays for the torch open-water env.

:class:`usvsim.task.torch_openwater.TorchOpenWaterEnv` starts episodes on the device, for all
boats at once, at every step: it needs each boat's next episode as tensors. The episodes are the
CPU family's own (:func:`usvsim.task.openwater_env.draw_family_episode`, which draws scalar,
seeded, with rejection loops: host code), drawn once on the host and packed here
(:class:`OpenWaterTable`, NumPy arrays, one row per episode); the env copies the table to the
device and picks rows there.

:func:`family_table` draws what :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` draws with
the same seed: boat i's generator is seeded ``seed + i`` (gymnasium's ``seeding.np_random(s)``
is ``default_rng(s)``) and its k-th episode is row ``i · per_boat + k``. Same seed → the same
episodes on both envs. A boat that has used its ``per_boat`` episodes goes on with the next
boat's rows (the table cycles): equal to the CPU env only within the table.

Packing needs the CPU family (its module imports CasADi and SciPy); a packed table saves to and
loads from a ``.npz`` file (:meth:`OpenWaterTable.save`, :func:`load_table`), so a GPU machine
without CasADi runs the env on a table drawn elsewhere. Weather episodes are refused: the torch
plant has no wind or waves.

Table fields (E episodes, K static discs and M vessels at most per episode, padded):

================  ==========  ================================================================
field             shape       meaning
================  ==========  ================================================================
start_eta         (E, 3)      start pose [x_N m, y_E m, ψ0 rad] (``episode_geometry``)
speed_mps         (E,)        surge reference
current           (E, 2)      [V_c m/s, β_c rad] (the plant's where the episode has none)
gnss              (E, 6)      noise scale, outlier threshold Φ⁻¹(p) (−inf: none), outlier
                              scale, dropout start s, dropout end s, outlier probability
noise_seed        (E,)        the episode's sensor noise stream (``EpisodeSpec.noise_seed``)
outlier_seed      (E,)        the stream of its outlier draws (``EpisodeDisturbance.seed``)
goal_ne           (E, 2)      m
area              (E, 3)      [anchor x_N m, anchor y_E m, area radius m]
time_limit_s      (E,)        s
statics           (E, K, 3)   [x_N m, y_E m, radius m]; ``statics_ok`` (E, K)
vessels           (E, M, 6)   [x0_N m, y0_E m, course rad, speed m/s, turn rad/s, radius m];
                              ``vessels_ok`` (E, M)
radar             (E, 4)      [p_clutter, speckle, p_missed, noise amplitude] (``RadarQuality``)
radar_base        (E,)        ``mix64(radar_seed)`` as int64 bits: frame f's key is
                              ``base + G f 2²²`` (:class:`usvsim.task.scene_radar.RadarStreams`)
================  ==========  ================================================================
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["OpenWaterTable", "family_table", "load_table", "pack_episodes"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OpenWaterTable:
    """E open-water episodes as arrays (module docstring's table)."""

    start_eta: FloatArray
    speed_mps: FloatArray
    current: FloatArray
    gnss: FloatArray
    noise_seed: NDArray[np.int64]
    outlier_seed: NDArray[np.int64]
    goal_ne: FloatArray
    area: FloatArray
    time_limit_s: FloatArray
    statics: FloatArray
    statics_ok: NDArray[np.bool_]
    vessels: FloatArray
    vessels_ok: NDArray[np.bool_]
    radar: FloatArray
    radar_base: NDArray[np.int64]

    @property
    def n_episodes(self) -> int:
        return int(self.speed_mps.shape[0])

    def save(self, path: str | Path) -> None:
        """Write the table to ``path`` (``.npz``), atomically (a temporary file, then renamed)."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez_compressed(tmp, **{f.name: getattr(self, f.name) for f in fields(self)})
        tmp.replace(path)


def load_table(path: str | Path) -> OpenWaterTable:
    """A table written by :meth:`OpenWaterTable.save`."""
    with np.load(Path(path)) as data:
        return OpenWaterTable(**{f.name: data[f.name] for f in fields(OpenWaterTable)})


def pack_episodes(
    episodes: Sequence[Any],
    cruise_speed_mps: float = 3.0,
    plant_current: tuple[float, float] = (0.0, 0.0),
) -> OpenWaterTable:
    """Pack :class:`usvsim.task.openwater.OpenWaterEpisode` s (module docstring); the start pose
    from :func:`usvsim.task.scenario.episode_geometry` as ``OpenWaterBatch.reset`` computes it,
    an episode without a disturbance at ``cruise_speed_mps`` (the scenario's) in
    ``plant_current`` (the plant's [V_c m/s, β_c rad]). Loops over episodes: host code, once.

    Raises ``ValueError`` for an episode with weather (the torch plant has none)."""
    from scipy.special import ndtri  # the CPU batch's outlier threshold (task.disturbance)

    from usvsim.task.scenario import Scenario, episode_geometry
    from usvsim.task.scene_radar import mix64

    if not episodes:
        raise ValueError("pack_episodes needs at least one episode")
    e_n = len(episodes)
    if any(e.disturbance is not None and e.disturbance.weather is not None for e in episodes):
        raise ValueError(
            "the torch open-water env steps calm water only (the torch plant has no wind or "
            "waves): a weather episode was given; use the CPU env (device='cpu')"
        )
    scenario = replace(Scenario(), poles_ne=tuple(e.anchor_ne for e in episodes))
    geo = episode_geometry(
        scenario, [replace(e.start, pole_index=j) for j, e in enumerate(episodes)]
    )
    k = max(1, max(len(e.obstacles) for e in episodes))
    m = max(1, max(len(e.vessels) for e in episodes))
    t = OpenWaterTable(
        start_eta=np.asarray(geo.start_eta, dtype=np.float64),
        speed_mps=np.full(e_n, cruise_speed_mps),
        current=np.tile(np.asarray(plant_current, dtype=np.float64), (e_n, 1)),
        gnss=np.tile([1.0, -math.inf, 1.0, math.inf, math.inf, 0.0], (e_n, 1)),
        noise_seed=np.array([e.start.noise_seed for e in episodes], dtype=np.int64),
        outlier_seed=np.zeros(e_n, dtype=np.int64),
        goal_ne=np.array([e.goal_ne for e in episodes], dtype=np.float64),
        area=np.array([(*e.anchor_ne, e.area_radius_m) for e in episodes], dtype=np.float64),
        time_limit_s=np.array([e.time_limit_s for e in episodes], dtype=np.float64),
        statics=np.zeros((e_n, k, 3)),
        statics_ok=np.zeros((e_n, k), dtype=bool),
        vessels=np.zeros((e_n, m, 6)),
        vessels_ok=np.zeros((e_n, m), dtype=bool),
        radar=np.array(
            [
                (q.clutter_probability, q.speckle, q.missed_probability, q.noise_amplitude)
                for q in (e.radar for e in episodes)
            ],
            dtype=np.float64,
        ).reshape(e_n, 4),
        radar_base=mix64(np.array([int(e.radar_seed) for e in episodes], dtype=np.uint64)).view(
            np.int64
        ),
    )
    for i, e in enumerate(episodes):  # host packing, once per table
        obs = np.array(e.obstacles, dtype=np.float64).reshape(-1, 3)
        t.statics[i, : len(obs)], t.statics_ok[i, : len(obs)] = obs, True
        for j, v in enumerate(e.vessels):
            t.vessels[i, j] = (v.x0_n, v.y0_e, v.course_rad, v.speed_mps, v.turn_rate_radps,
                               v.radius_m)  # fmt: skip
            t.vessels_ok[i, j] = True
        d = e.disturbance
        if d is None:
            continue
        if d.speed_mps is not None:
            t.speed_mps[i] = d.speed_mps
        t.current[i] = (d.current_speed_mps, d.current_direction_rad)
        p = d.gnss_outlier_probability
        t.gnss[i] = (
            d.gnss_noise_scale, float(ndtri(p)) if p > 0 else -math.inf, d.gnss_outlier_scale,
            d.gnss_dropout_start_s, d.gnss_dropout_start_s + d.gnss_dropout_duration_s, p,
        )  # fmt: skip
        t.outlier_seed[i] = d.seed
    return t


def family_table(family: Any, seed: int, n_boats: int, per_boat: int) -> OpenWaterTable:
    """The first ``per_boat`` episodes of each of ``n_boats`` boats as
    :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` draws them after ``reset(seed=seed)``
    (boat i from ``default_rng(seed + i)``), packed; row ``i · per_boat + k`` is boat i's k-th.
    ``family``: a ``ScenarioMixture`` or an ``OpenWaterScenario`` (e.g. a stress set's)."""
    from usvsim.task.openwater_env import draw_family_episode

    if n_boats < 1 or per_boat < 1:
        raise ValueError(f"n_boats and per_boat must be >= 1, got {n_boats}, {per_boat}")
    episodes: list[Any] = []
    for i in range(n_boats):  # host draws, once: the CPU family's scalar, seeded code
        rng = np.random.default_rng(seed + i)
        episodes.extend(draw_family_episode(family, rng) for _ in range(per_boat))
    return pack_episodes(episodes)
