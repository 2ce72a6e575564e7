"""From raw recordings to (observation, action) pairs: the study's Sect. 3.5.1, and tlog import.

Steps (Vedeler 2019, Sect. 3.5.1; ``shared/reference/table-4-1.md``, "Expert demonstrations"):

1. **Match by timestamp.** GPS and compass run at their own rates; both are interpolated onto a
   common clock (:func:`interpolate_position`, :func:`interpolate_heading`: linear in time, the
   heading unwrapped first so that 359° → 1° is a 2° step).
2. **Down-sample** to the decision period (2 s): decision times ``t_k = t_0 + 2k`` over the span
   covered by both sensors (:func:`decision_track`).
3. **Action** ``Δψ_k = ssa(ψ_{k+1} − ψ_k)`` (next heading − current heading, wrapped), clipped to
   the ±30° action bound (the quality filter already rejects runs that exceed it).
4. **Goal** = the run's last position (the last GPS fix); the pole = the metadata's pole. A run
   on the open-water family (``usvsim-demo/2``, :mod:`learning.imitation.demo_scene`): the
   scene's goal, and its obstacles and vessels where they were at t_k.
5. **Observations regenerated** by the environment's own builder
   (:func:`usvsim.task.observations.build_observation`) from (p_k, ψ_k, pole, goal): ``positional``,
   ``radar`` or ``radar+goal`` exactly as a policy sees them in the simulator. For a scene run,
   the open-water step's builder (:func:`usvsim.task.openwater_batch.observe_scene`, also
   ``scene``) with the velocity over ground v_k the least-squares slope of the GPS fixes within
   ±2 s of t_k (about 0.5 m/s of noise per axis from 1.5 m fixes at 1 Hz); its radar image is
   degraded as the scene's ``radar`` entry says (frame k at decision k, the simulator's draws
   for that radar seed), clean where the run has none.
6. **Actions in the env's format** (:func:`encode_actions`): Gaussian ``a = Δψ / 30°`` in
   [-1, 1]; categorical ``k = round(Δψ / 1.5°) + 20`` in 0..40 (the study's 41 bins).

Shapes (M decision steps over all runs, E runs):

==================  ============================  ==============================================
field               shape                         meaning
==================  ============================  ==============================================
obs                 (M, ...) or dict              observations, raw (as the env returns them)
actions             (M, 1) float32 / (M,) int64   env actions (gaussian / categorical)
heading_change_rad  (M,)                          Δψ_k before encoding
episode             (M,) int                      index of the run
last                (M,) bool                     the run's last decision (its next state is
                                                  the end of the demonstration)
==================  ============================  ==============================================

:func:`recording_from_tlog` turns a MAVLink telemetry log (``.tlog``, read by
:func:`usvsim.mavlink.link.read_tlog`) into a :class:`learning.imitation.demonstrations.Recording`:
GLOBAL_POSITION_INT gives the GPS stream, ATTITUDE yaw the compass stream (VFR_HUD heading when a
log has no ATTITUDE), all on the vehicle's boot clock (``time_boot_ms``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from learning.imitation.demo_scene import DemoScene
from learning.imitation.demonstrations import FORMAT, DemoFormatError, Recording
from usvsim.common.angles import ssa
from usvsim.mavlink.link import read_tlog
from usvsim.mavlink.messages import Attitude, GlobalPosition, VfrHud
from usvsim.nav.geo import GeoOrigin
from usvsim.task.batch import N_CATEGORIES, ActionKind
from usvsim.task.observations import ObservationKind, build_observation, observation_space
from usvsim.task.openwater import RadarQuality
from usvsim.task.openwater_batch import SceneDiscs, observe_scene
from usvsim.task.openwater_env import RADAR_RANGES, harsh_radar_family
from usvsim.task.radar import RadarConfig
from usvsim.task.scene_radar import RadarDegradation, stream_keys

__all__ = [
    "DecisionTrack",
    "ExpertData",
    "check_observations",
    "decision_track",
    "encode_actions",
    "expert_data",
    "harsh_radar_runs",
    "interpolate_heading",
    "interpolate_position",
    "recording_from_tlog",
    "with_radar",
]

FloatArray = NDArray[np.float64]
MAX_CHANGE_RAD = math.radians(30.0)  # rad, the action bound (study)
VELOCITY_WINDOW_S = 2.0  # s, half-width of the GPS fit that gives a scene run's velocity


def interpolate_position(t_s: FloatArray, fix_t_s: FloatArray, fix_ne: FloatArray) -> FloatArray:
    """Positions (M, 2) at times ``t_s`` (M,), linear between fixes ``fix_ne`` (G, 2) at
    ``fix_t_s`` (G,) (strictly increasing). Times outside the fixes' span raise."""
    _check_span(t_s, fix_t_s, "GPS")
    return np.column_stack(
        [np.interp(t_s, fix_t_s, fix_ne[:, 0]), np.interp(t_s, fix_t_s, fix_ne[:, 1])]
    )


def interpolate_heading(t_s: FloatArray, sample_t_s: FloatArray, psi_rad: FloatArray) -> FloatArray:
    """Headings (M,) rad in [-π, π) at ``t_s``, linear in time on the unwrapped compass samples.

    >>> t = np.array([0.0, 1.0]); psi = np.radians([359.0, 1.0])
    >>> round(float(np.degrees(interpolate_heading(np.array([0.5]), t, psi))[0]), 6)
    0.0
    """
    _check_span(t_s, sample_t_s, "compass")
    return np.asarray(ssa(np.interp(t_s, sample_t_s, np.unwrap(psi_rad))))


def _check_span(t_s: FloatArray, src_t_s: FloatArray, name: str) -> None:
    if t_s.size and (t_s.min() < src_t_s[0] - 1e-9 or t_s.max() > src_t_s[-1] + 1e-9):
        raise ValueError(
            f"times [{t_s.min():.2f}, {t_s.max():.2f}] s outside the {name} span "
            f"[{src_t_s[0]:.2f}, {src_t_s[-1]:.2f}] s"
        )


@dataclass(frozen=True)
class DecisionTrack:
    """One run down-sampled to the decision period: times (K,), positions (K, 2) m, headings
    (K,) rad, actions Δψ (K − 1,) rad, the goal and pole (2,) m."""

    t_s: FloatArray
    pos_ne: FloatArray
    psi_rad: FloatArray
    heading_change_rad: FloatArray
    goal_ne: FloatArray
    pole_ne: FloatArray
    pole_radius_m: float
    source: str = ""  # the recording's file, if any


def decision_track(rec: Recording, period_s: float = 2.0) -> DecisionTrack:
    """Steps 1-4 of the module docstring for one recording."""
    gps_ne = rec.gps_ne
    t0 = max(rec.gps_t_s[0], rec.compass_t_s[0])
    t1 = min(rec.gps_t_s[-1], rec.compass_t_s[-1])
    if t1 - t0 < 2 * period_s:
        raise ValueError(f"{rec.source or 'recording'}: GPS and compass overlap < 2 periods")
    t = t0 + period_s * np.arange(math.floor((t1 - t0) / period_s + 1e-9) + 1)
    psi = interpolate_heading(t, rec.compass_t_s, rec.compass_rad)
    dpsi = np.clip(ssa(np.diff(np.unwrap(psi))), -MAX_CHANGE_RAD, MAX_CHANGE_RAD)
    return DecisionTrack(
        t_s=t,
        pos_ne=interpolate_position(t, rec.gps_t_s, gps_ne),
        psi_rad=psi,
        heading_change_rad=dpsi,
        goal_ne=gps_ne[-1].copy(),
        pole_ne=rec.pole_ne,
        pole_radius_m=float(rec.meta["pole_radius_m"]),
        source=rec.source,
    )


def encode_actions(heading_change_rad: FloatArray, action: ActionKind) -> NDArray[Any]:
    """Δψ (M,) rad → env actions: gaussian (M, 1) float32 ``Δψ / 30°``; categorical (M,) int64
    ``round(Δψ / 1.5°) + 20`` clipped to 0..40 (step 6 of the module docstring)."""
    x = np.clip(np.asarray(heading_change_rad, dtype=float) / MAX_CHANGE_RAD, -1.0, 1.0)
    if action == "gaussian":
        return x[:, None].astype(np.float32)
    if action == "categorical":
        half = (N_CATEGORIES - 1) // 2
        return np.clip(np.round(x * half) + half, 0, N_CATEGORIES - 1).astype(np.int64)
    raise ValueError(f"action must be 'gaussian' or 'categorical', got {action!r}")


@dataclass(frozen=True)
class ExpertData:
    """Expert (observation, action) pairs of many runs (module table)."""

    obs: NDArray[Any] | dict[str, NDArray[Any]]
    actions: NDArray[Any]
    heading_change_rad: FloatArray
    episode: NDArray[np.int64]
    last: NDArray[np.bool_]
    tracks: tuple[DecisionTrack, ...]
    # the same pairs' observations in a second form, for a discriminator that sees more than the
    # policy (GAILConfig.disc_observation; learning.experiments.train_il.expert_pairs)
    disc_obs: NDArray[Any] | dict[str, NDArray[Any]] | None = None

    def __len__(self) -> int:
        return int(self.heading_change_rad.size)


def expert_data(
    recordings: Sequence[Recording],
    observation: ObservationKind,
    action: ActionKind,
    *,
    period_s: float = 2.0,
    radar: RadarConfig | None = None,
) -> ExpertData:
    """Steps 1-6 for every recording: the expert dataset of one setup.

    Raises ``ValueError`` if ``recordings`` mix one-pole (``/1``) and scene (``/2``) runs, or
    ask one-pole runs for the ``scene`` observation."""
    scenes = [r.scene for r in recordings]
    with_scene = [s for s in scenes if s is not None]
    if with_scene and len(with_scene) != len(scenes):
        raise ValueError("demonstrations mix one-pole (usvsim-demo/1) and scene (/2) runs")
    tracks = tuple(decision_track(r, period_s) for r in recordings)
    if with_scene:
        tracks = tuple(
            dataclasses.replace(tr, goal_ne=s.goal_ne)
            for tr, s in zip(tracks, with_scene, strict=True)
        )
    pos = np.concatenate([tr.pos_ne[:-1] for tr in tracks])
    psi = np.concatenate([tr.psi_rad[:-1] for tr in tracks])
    n = [tr.heading_change_rad.size for tr in tracks]
    pole = np.repeat(np.stack([tr.pole_ne for tr in tracks]), n, axis=0)
    goal = np.repeat(np.stack([tr.goal_ne for tr in tracks]), n, axis=0)
    radius = tracks[0].pole_radius_m if tracks else 1.0
    if with_scene:
        degradation, keys = _scene_radar(with_scene, n)
        obs = observe_scene(
            observation, pos, psi, _velocities(recordings, tracks), goal,
            _scene_discs(with_scene, tracks), radar, degradation, keys,
        )  # fmt: skip
    elif observation == "scene":
        raise ValueError("the scene observation needs scene demonstrations (usvsim-demo/2)")
    else:
        obs = build_observation(observation, pos, psi, pole, goal, radius, radar)
    dpsi = np.concatenate([tr.heading_change_rad for tr in tracks])
    episode = np.repeat(np.arange(len(tracks)), n)
    last = np.zeros(dpsi.size, dtype=bool)
    last[np.cumsum(n) - 1] = True
    return ExpertData(obs, encode_actions(dpsi, action), dpsi, episode, last, tracks)


def _velocities(recordings: Sequence[Recording], tracks: Sequence[DecisionTrack]) -> FloatArray:
    """Velocity over ground (M, 2) m/s at every decision: the least-squares slope of the GPS
    fixes within ±:data:`VELOCITY_WINDOW_S` of it (step 5 of the module docstring); 0 where the
    window holds fewer than two fixes (an outage)."""
    out = []
    for rec, tr in zip(recordings, tracks, strict=True):
        dt = rec.gps_t_s[None, :] - tr.t_s[:-1, None]  # (K, G) s
        w = (np.abs(dt) <= VELOCITY_WINDOW_S).astype(float)
        count = w.sum(axis=1, keepdims=True)
        mean_t = (w * dt).sum(axis=1, keepdims=True) / np.maximum(count, 1.0)
        x = w * (dt - mean_t)
        ne = rec.gps_ne
        sxx = (x * (dt - mean_t)).sum(axis=1)
        out.append(
            np.where((count[:, 0] >= 2)[:, None], (x @ ne) / np.maximum(sxx, 1e-9)[:, None], 0.0)
        )
    return np.concatenate(out) if out else np.zeros((0, 2))


def _scene_radar(
    scenes: Sequence[DemoScene], n_decisions: Sequence[int]
) -> tuple[RadarDegradation | None, NDArray[np.uint64] | None]:
    """Each decision's radar degradation (M,) and frame key (M,): run r's quality at each of its
    ``n_decisions[r]`` decisions, frame k at decision k of its radar seed (step 5 of the module
    docstring); (None, None) where no run has a ``radar`` entry."""
    if all(s.radar is None for s in scenes):
        return None, None
    quality = [s.radar or RadarQuality() for s in scenes]
    fields = [
        np.repeat([getattr(q, name) for q in quality], n_decisions).astype(float)
        for name in ("clutter_probability", "speckle", "missed_probability", "noise_amplitude")
    ]
    # uint64: a seed may be any integer below 2⁶⁴, and a list holding one above 2⁶³ - 1 would
    # otherwise become float64 and round every seed in it to 53 bits
    own = np.array([s.radar_seed for s in scenes], dtype=np.uint64)
    seeds = np.repeat(own, n_decisions).tolist()
    frames = np.concatenate([np.arange(k, dtype=np.int64) for k in n_decisions])
    return RadarDegradation(*fields), stream_keys(seeds, frames)


def _scene_discs(scenes: Sequence[DemoScene], tracks: Sequence[DecisionTrack]) -> SceneDiscs:
    """Every run's discs at its decisions, padded to the most discs of any run (M, J, ...)."""
    j = max((s.n_discs for s in scenes), default=0)
    parts: list[tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]] = []
    for s, tr in zip(scenes, tracks, strict=True):
        k, m = tr.t_s.size - 1, s.n_discs
        centres, velocity = s.discs(tr.t_s[:-1])
        pad = ((0, 0), (0, j - m), (0, 0))
        parts.append((
            np.pad(centres, pad),
            np.pad(np.broadcast_to(s.radii_m(), (k, m)), ((0, 0), (0, j - m))),
            np.pad(velocity, pad), np.arange(j)[None, :].repeat(k, 0) < m,
        ))  # fmt: skip
    return SceneDiscs(*(np.concatenate(p) for p in zip(*parts, strict=True)))


def check_observations(data: ExpertData, observation: ObservationKind) -> None:
    """Every observation of ``data`` finite and inside the observation space's bounds
    (:func:`usvsim.task.observations.observation_space`): a demonstration whose pairs a policy
    could never see is refused rather than fed to the discriminator.

    Raises
    ------
    DemoFormatError
        Naming the recording's file, the decision time and the first element out of bounds.
    """
    space = observation_space(observation)
    parts = data.obs if isinstance(data.obs, dict) else {"": data.obs}
    boxes = dict(space.spaces) if hasattr(space, "spaces") else {"": space}
    for key, values in parts.items():
        box: Any = boxes[key]  # a Box (the observation spaces are Boxes or Dicts of Boxes)
        x = np.asarray(values, dtype=np.float64).reshape(len(data), -1)
        low = np.broadcast_to(np.asarray(box.low, dtype=np.float64).reshape(-1), x.shape[1:])
        high = np.broadcast_to(np.asarray(box.high, dtype=np.float64).reshape(-1), x.shape[1:])
        bad = ~np.isfinite(x) | (x < low) | (x > high)
        rows = np.flatnonzero(bad.any(axis=1))
        if rows.size == 0:
            continue
        row = int(rows[0])
        col = int(np.flatnonzero(bad[row])[0])
        episode = int(data.episode[row])
        track = data.tracks[episode]
        first = int(np.flatnonzero(data.episode == episode)[0])
        t = float(track.t_s[row - first])
        name = f"{key}[{col}]" if key else f"[{col}]"
        raise DemoFormatError(
            f"{track.source or 'recording'}: decision at t = {t:.1f} s: {observation} "
            f"observation{name} = {x[row, col]:.6g} outside [{low[col]:g}, {high[col]:g}]"
        )


def recording_from_tlog(
    path: str | Path,
    *,
    origin: GeoOrigin,
    poles_ne: Sequence[tuple[float, float]],
    pole_index: int,
    pole_radius_m: float = 1.0,
    system_id: int | None = None,
) -> Recording:
    """A :class:`Recording` from a MAVLink ``.tlog`` (module docstring).

    ``origin`` is the site's NED origin and ``poles_ne`` its poles (m) in that frame;
    ``system_id`` keeps the packets of one vehicle (default: the sender of the first
    GLOBAL_POSITION_INT). Duplicate or out-of-order boot times are dropped. Raises
    ``ValueError`` if the log has fewer than two positions or headings.
    """
    packets = read_tlog(path)
    if system_id is None:
        senders = [r.src_system for _, r in packets if isinstance(r.message, GlobalPosition)]
        system_id = senders[0] if senders else -1
    mine = [(stamp, r.message) for stamp, r in packets if r.src_system == system_id]
    gps = [
        (m.time_boot_ms / 1e3, m.lat_deg, m.lon_deg)
        for _, m in mine
        if isinstance(m, GlobalPosition)
    ]
    heading = [(m.time_boot_ms / 1e3, m.yaw_rad) for _, m in mine if isinstance(m, Attitude)]
    if not heading and gps:
        # VFR_HUD carries no boot time: map tlog stamps onto the boot clock through the
        # median offset between GLOBAL_POSITION_INT's boot times and their tlog stamps
        stamps = [s for s, m in mine if isinstance(m, GlobalPosition)]
        offset = float(np.median(np.array(stamps) - np.array([g[0] for g in gps])))
        heading = [
            (s - offset, math.radians(m.heading_deg)) for s, m in mine if isinstance(m, VfrHud)
        ]
    g, h = _increasing(np.array(gps, dtype=float)), _increasing(np.array(heading, dtype=float))
    if g.shape[0] < 2 or h.shape[0] < 2:
        raise ValueError(f"{path}: needs ≥ 2 GLOBAL_POSITION_INT and ≥ 2 ATTITUDE/VFR_HUD")
    meta = {
        "format": FORMAT,
        "run": 0,
        "pole_index": pole_index,
        "poles_ne": [list(map(float, q)) for q in poles_ne],
        "pole_radius_m": pole_radius_m,
        "origin_lat_deg": origin.lat_deg,
        "origin_lon_deg": origin.lon_deg,
        "source": "tlog",
    }
    empty = np.zeros(0)
    return Recording(
        meta,
        g[:, 0],
        g[:, 1:3],
        h[:, 0],
        np.asarray(ssa(h[:, 1])),
        empty,
        empty,
        empty,
        source=str(path),
    )


def _increasing(rows: FloatArray) -> FloatArray:
    """Rows whose first column (time) is strictly increasing, in log order."""
    if rows.size == 0:
        return rows.reshape(0, 3)
    keep = rows[:, 0] > np.maximum.accumulate(np.concatenate([[-np.inf], rows[:-1, 0]]))
    return rows[keep]


def with_radar(recording: Recording, quality: RadarQuality, copy: int) -> Recording:
    """``recording`` (a ``usvsim-demo/2`` run) as if its helmsman's radar had been of
    ``quality``: the same streams and scene, the ``radar`` entry replaced, its noise seed drawn
    from the run's own radar seed and ``copy`` (>= 1), so that copies of one run, and copies of
    different runs, see different noise. Its ``source`` names the copy.

    Used to add demonstrations at the family's harshest radar level
    (:attr:`learning.experiments.il_setups.ILSetup.harsh_radar_copies`): the expert's heading
    changes depend on the true scene, not on the image, so the pairs stay the expert's."""
    if "scene" not in recording.meta:
        raise ValueError(f"{recording.source or 'recording'}: not a scene run (usvsim-demo/2)")
    if copy < 1:
        raise ValueError(f"with_radar: copy must be >= 1, got {copy!r}")
    scene = dict(recording.meta["scene"])
    own = int(scene.get("radar", {}).get("seed", 0))
    seed = int(np.random.SeedSequence([own, copy, _COPY_TAG]).generate_state(1, np.uint64)[0])
    scene["radar"] = {**dataclasses.asdict(quality), "seed": seed}
    meta = {**recording.meta, "scene": scene}
    source = f"{recording.source}#radar{copy}" if recording.source else ""
    return dataclasses.replace(recording, meta=meta, source=source)


def harsh_radar_runs(runs: Sequence[Recording], copies: int) -> list[Recording]:
    """``copies`` copies of every scene run in ``runs`` with its radar at the open-water family's
    harshest level (:func:`usvsim.task.openwater_env.harsh_radar_family`; its own noise per copy,
    :func:`with_radar`), copy by copy."""
    member = harsh_radar_family().members[0]
    quality = RadarQuality(*(getattr(member, name)[0] for name in RADAR_RANGES))
    return [with_radar(r, quality, c) for c in range(1, copies + 1) for r in runs]


_COPY_TAG = 0x68617273  # "hars": keeps the copies' seeds apart from [own, copy] draws elsewhere
