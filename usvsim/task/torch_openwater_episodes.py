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
without CasADi runs the env on a table drawn elsewhere. Where an episode has weather, the table
gains three fields: each episode's weather plant inputs, computed on the host as the CPU batch
computes them at the episode's start (:func:`usvsim.vessel.weather_plant.weather_inputs`: wave
response at the start heading and speed, filter gains, PID wave design), the scales of its
stationary start draws and its ``windy`` flag; a table without weather has them ``None`` (the
env then steps the calm plant, as the CPU batch does).

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
weather           (E, 33)     the weather plant's per-episode inputs
                              (:data:`usvsim.vessel.weather_plant.WEATHER_INPUTS` from
                              ``wind_mean``; an episode without weather: the calm row), or None
weather_start     (E, 3)      standard deviations of the start's gust (m/s) and wave motion
                              states (stationary; 0 without weather), or None
windy             (E,)        the episode has a weather (it draws the weather's normals from
                              its noise stream, as ``BoatDisturbances.weather_active``), or None
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
    weather: FloatArray | None = None
    weather_start: FloatArray | None = None
    windy: NDArray[np.bool_] | None = None

    @property
    def in_weather(self) -> bool:
        """True where the episodes step in the weather plant (some episode has weather)."""
        return self.weather is not None

    @property
    def n_episodes(self) -> int:
        return int(self.speed_mps.shape[0])

    def on_device(self, device: Any, dtype: Any) -> dict[str, Any]:
        """Every field present as a torch tensor on ``device``: booleans and int64 as they
        are, floats in ``dtype``."""
        import torch  # here: packing a table needs no torch

        def put(a: np.ndarray) -> Any:
            if a.dtype == np.bool_ or a.dtype == np.int64:
                return torch.as_tensor(a, device=device)
            return torch.as_tensor(a, dtype=dtype, device=device)

        return {f.name: put(v) for f in fields(self) if (v := getattr(self, f.name)) is not None}

    def save(self, path: str | Path) -> None:
        """Write the table to ``path`` (``.npz``), atomically (a temporary file, then renamed)."""
        path = Path(path)
        tmp = path.with_name(path.name + ".tmp.npz")
        arrays = {f.name: getattr(self, f.name) for f in fields(self)}
        np.savez_compressed(tmp, **{k: v for k, v in arrays.items() if v is not None})
        tmp.replace(path)


def load_table(path: str | Path) -> OpenWaterTable:
    """A table written by :meth:`OpenWaterTable.save` (a calm table has no weather fields)."""
    with np.load(Path(path)) as data:
        return OpenWaterTable(
            **{f.name: data[f.name] for f in fields(OpenWaterTable) if f.name in data.files}
        )


def pack_episodes(
    episodes: Sequence[Any],
    cruise_speed_mps: float = 3.0,
    plant_current: tuple[float, float] = (0.0, 0.0),
) -> OpenWaterTable:
    """Pack :class:`usvsim.task.openwater.OpenWaterEpisode` s (module docstring); the start pose
    from :func:`usvsim.task.scenario.episode_geometry` as ``OpenWaterBatch.reset`` computes it,
    an episode without a disturbance at ``cruise_speed_mps`` (the scenario's) in
    ``plant_current`` (the plant's [V_c m/s, β_c rad]). Loops over episodes: host code, once.

    Episodes with weather: their weather plant inputs and start scales (:func:`_weather_fields`,
    the default plant's; CasADi needed)."""
    from scipy.special import ndtri  # the CPU batch's outlier threshold (task.disturbance)

    from usvsim.task.scenario import Scenario, episode_geometry
    from usvsim.task.scene_radar import mix64

    if not episodes:
        raise ValueError("pack_episodes needs at least one episode")
    e_n = len(episodes)
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
    weathers = [None if e.disturbance is None else e.disturbance.weather for e in episodes]
    if all(w is None for w in weathers):
        return t
    heading = np.angle(np.exp(1j * t.start_eta[:, 2]))  # ssa, as Plant.initial_state
    return replace(t, **_weather_fields(weathers, heading, t.speed_mps))


def _weather_fields(
    weathers: Sequence[Any], heading_rad: FloatArray, speed_mps: FloatArray
) -> dict[str, Any]:
    """The table's weather fields of episodes with ``weathers`` (a ``Weather`` or None each)
    starting at ``heading_rad`` and ``speed_mps`` (E,): what
    ``BoatDisturbances.start_weather`` computes at their start with the default plant
    (``WeatherPlant(Plant(), innovations="normal")``, as ``PoleAvoidanceBatch``)."""
    from usvsim.task.weather_draw import CALM, sea_conditions
    from usvsim.vessel.plant import Plant
    from usvsim.vessel.weather.waves import wave_motion_std
    from usvsim.vessel.weather_plant import WeatherPlant, weather_inputs

    plant = WeatherPlant(Plant(), innovations="normal")
    cond = sea_conditions([CALM if w is None else w for w in weathers])
    cond.check(len(weathers))
    rows, resp = weather_inputs(
        cond, speed_mps, heading_rad, plant.plant.dt_s, plant.gusts, plant.wave_filter,
        plant.yaw_model, autopilot=plant.plant.design,
    )  # fmt: skip
    start = np.column_stack([cond.gust_intensity * cond.wind_speed_mps, wave_motion_std(resp)])
    if not np.isfinite(start).all():
        raise ValueError("a weather start scale is not finite (wave response of a calm sea?)")
    return {
        "weather": rows,
        "weather_start": start,
        "windy": np.array([w is not None for w in weathers], dtype=bool),
    }


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
