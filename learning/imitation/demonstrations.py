"""Expert demonstrations as raw recordings: recorder, on-disk format, loader, quality filter.

The study (Vedeler 2019, Sect. 3.5) recorded 46 manual runs on a real USV and kept 35. Here the
person at the helm is :class:`baselines.expert.HumanExpert` driving the simulator, and
:func:`record_demonstrations` logs what the real boat logged: GPS fixes, compass headings and
radar sweeps, each at its own rate and phase, with jittered timestamps and sensor noise; plus
which pole the run was about.

==========  =========  ===================================================================
stream      rate       content (noise, 1σ)
==========  =========  ===================================================================
``gps``     1 Hz       latitude, longitude (deg, WGS-84) of the antenna; 1.5 m per axis
``compass`` 5 Hz       heading (deg, [0, 360), clockwise from north); 1°
``radar``   0.4 Hz     one sweep per 2.5 s (24 rpm): the pole's echo, range (m, σ 2 m) and
                       bearing relative to the bow (deg, σ 1.5°); no echo → empty cells
==========  =========  ===================================================================

Timestamps (s since the logger started) carry 10 ms of jitter, and each stream starts at its
own phase: no two streams are aligned. With probability 0.15 a run suffers a GPS outage of
4-10 s (the receiver loses its fix), as real logs do.

On-disk format ``usvsim-demo/1`` (one UTF-8 text file per run, ``demo_NNN.csv``)::

    # usvsim-demo/1 {"run": 3, "pole_index": 1, "poles_ne": [[0, 0], [500, 500]], ...}
    stream,t_s,lat_deg,lon_deg,heading_deg,range_m,bearing_deg
    compass,0.0713,,,166.21,,
    gps,0.4127,63.4380021,10.3980117,,,
    radar,1.1021,,,,98.3,-0.7

Line 1 is the magic ``# usvsim-demo/1`` and the run's metadata as one JSON object (keys:
:data:`REQUIRED_METADATA`; ``expert`` holds the helmsman's drawn traits, ground truth for
analysis that preprocessing never reads). Line 2 is the header; the columns may come in any
order, all of :data:`COLUMNS` must be there. ``usvsim-demo/2`` is the same with one more
metadata key, ``scene``: the goal, obstacles and vessels of a run on the open-water family
(:mod:`learning.imitation.demo_scene`; such a run's radar stream echoes the nearest obstacle).
Rows are sorted by time; per stream, times must be strictly increasing, and the cells a stream needs
must be finite numbers (radar range and bearing may both be empty: a sweep without an echo). A
reader of a later version must refuse ``/1`` files only if it changes these rules.

Physical plausibility (:class:`Plausibility`, checked by the loader too; a file breaking it is
refused like a malformed one, naming file and line): metadata origin latitude in [-90, 90]° and
longitude in [-180, 180]°, ``poles_ne`` pairs of finite metres within
:attr:`Plausibility.max_distance_m` of the origin, ``pole_radius_m`` in (0, 100] m; every GPS
fix within those latitude/longitude ranges and within ``max_distance_m`` (5 km) of the origin;
between consecutive fixes no more than ``max_speed_mps`` (15 m/s, five times the task's 3 m/s)
plus ``gps_allowance_m`` (10 m, several σ of GPS noise); compass headings in [-360, 360]°; radar
ranges in [-10 m, 10 km] (noise may push an echo close to the pole below 0).

:func:`load_recording` raises :class:`DemoFormatError` naming the file, line and column of the
first problem; :func:`load_recordings` loads a folder and collects such errors instead of
stopping. :func:`quality_check` is the documented filter (reasons for rejection, from the
recorded data only).

Why this module is long: the format is one idea, kept in one file: the recorder that writes it,
the reader that parses and validates it, and the filter that judges it (the plausibility limits
live in :mod:`learning.imitation.plausibility`).
"""

from __future__ import annotations

import csv
import gzip
import io
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.expert import ExpertParams, ExpertRun, run_expert
from learning.imitation.demo_scene import FORMAT_SCENE, DemoScene
from learning.imitation.plausibility import (
    PLAUSIBLE,
    DemoFormatError,
    Plausibility,
    check_fix,
    check_motion,
    check_site,
)
from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_open, atomic_write_text
from usvsim.nav.geo import GeoOrigin, geodetic_from_ned, ned_from_geodetic
from usvsim.task.scenario import Scenario, draw_episodes

__all__ = [
    "COLUMNS",
    "DEMOS_DIR",
    "DEMO_SEED",
    "FORMAT",
    "REQUIRED_METADATA",
    "SITE_ORIGIN",
    "DemoFormatError",
    "LoadReport",
    "Plausibility",
    "RecorderParams",
    "Recording",
    "demo_folder",
    "load_recording",
    "load_recordings",
    "log_run",
    "quality_check",
    "record_demonstrations",
    "recording_to_text",
    "save_recordings",
    "write_demo_set",
]

FloatArray = NDArray[np.float64]
FORMAT = "usvsim-demo/1"
COLUMNS = ("stream", "t_s", "lat_deg", "lon_deg", "heading_deg", "range_m", "bearing_deg")
STREAM_FIELDS = {"gps": ("lat_deg", "lon_deg"), "compass": ("heading_deg",), "radar": ()}
REQUIRED_METADATA = (
    "run",
    "pole_index",
    "poles_ne",
    "pole_radius_m",
    "origin_lat_deg",
    "origin_lon_deg",
)
DEMO_SEED = 20190046  # seeds the 46 recorded runs (episodes, expert, sensors)
DEMOS_DIR = Path(str(resources.files("usvsim"))) / "demos"
SITE_ORIGIN = GeoOrigin(63.4390, 10.3990)  # deg, a harbour basin near NTNU, Trondheim (usvsim's)


@dataclass(frozen=True)
class RecorderParams:
    """Sensor rates, noise and faults of the recorder (module table; usvsim's choices)."""

    gps_rate_hz: float = 1.0  # Hz, a common logging rate of a marine GPS (NMEA 0183 at 1 Hz)
    gps_sigma_m: float = 1.5  # m per axis (usvsim.nav.sensors.SensorConfig)
    compass_rate_hz: float = 5.0  # Hz
    compass_sigma_rad: float = math.radians(1.0)  # rad (usvsim.nav.sensors.SensorConfig)
    radar_period_s: float = 2.5  # s, one sweep at 24 rpm (typical small-craft radar)
    radar_range_sigma_m: float = 2.0  # m, about half a 4 m range cell
    radar_bearing_sigma_rad: float = math.radians(1.5)  # rad, about the beam width
    radar_max_range_m: float = 200.0  # m, the study's radar range
    jitter_s: float = 0.01  # s, 1σ timestamp jitter of the logger
    p_gps_outage: float = 0.15  # probability that a run has one GPS outage
    gps_outage_range_s: tuple[float, float] = (4.0, 10.0)  # s, its duration, uniform


@dataclass(frozen=True)
class Recording:
    """One run as logged: metadata and three unaligned streams (times in s, angles in rad).

    ``gps_t_s`` (G,), ``gps_latlon_deg`` (G, 2); ``compass_t_s`` (C,), ``compass_rad`` (C,);
    ``radar_t_s`` (S,), ``radar_range_m`` (S,), ``radar_bearing_rad`` (S,) (NaN: no echo).
    """

    meta: dict[str, Any]
    gps_t_s: FloatArray
    gps_latlon_deg: FloatArray
    compass_t_s: FloatArray
    compass_rad: FloatArray
    radar_t_s: FloatArray
    radar_range_m: FloatArray
    radar_bearing_rad: FloatArray
    source: str = field(default="", compare=False)  # file it came from, if any

    @property
    def origin(self) -> GeoOrigin:
        return GeoOrigin(float(self.meta["origin_lat_deg"]), float(self.meta["origin_lon_deg"]))

    @property
    def pole_ne(self) -> FloatArray:
        """The run's pole, (2,) m in the site's NED frame."""
        return np.asarray(self.meta["poles_ne"], dtype=float)[int(self.meta["pole_index"])]

    @property
    def scene(self) -> DemoScene | None:
        """The open-water scene of a ``usvsim-demo/2`` run (:mod:`learning.imitation.demo_scene`),
        None for a ``/1`` run (one pole)."""
        return DemoScene.from_meta(self.source, self.meta) if "scene" in self.meta else None

    @property
    def gps_ne(self) -> FloatArray:
        """GPS fixes in the site's NED frame, (G, 2) m."""
        return ned_from_geodetic(self.gps_latlon_deg[:, 0], self.gps_latlon_deg[:, 1], self.origin)


# ---------------------------------------------------------------------------------------------
# Recording
# ---------------------------------------------------------------------------------------------


def _sample_times(rng: np.random.Generator, rate_hz: float, t_end: float, jitter: float) -> Any:
    period = 1.0 / rate_hz
    t = rng.uniform(0.0, period) + np.arange(0.0, t_end, period)
    t = t + rng.normal(0.0, jitter, t.size)
    return np.sort(t[(t >= 0.0) & (t <= t_end)])


def _pose_at(tr: FloatArray, t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """True position (M, 2) and heading (M,) at times ``t`` on the path ``tr`` (K, 4), linear in
    time (heading unwrapped)."""
    pos = np.column_stack([np.interp(t, tr[:, 0], tr[:, 1]), np.interp(t, tr[:, 0], tr[:, 2])])
    return pos, np.asarray(ssa(np.interp(t, tr[:, 0], np.unwrap(tr[:, 3]))))


def _record_run(
    run: ExpertRun, k: int, rng: np.random.Generator, p: RecorderParams, scenario: Scenario
) -> Recording:
    meta = {
        "format": FORMAT,
        "run": k,
        "pole_index": run.spec.pole_index,
        "poles_ne": [list(map(float, q)) for q in scenario.poles_ne],
        "pole_radius_m": scenario.pole_radius_m,
        "origin_lat_deg": SITE_ORIGIN.lat_deg,
        "origin_lon_deg": SITE_ORIGIN.lon_deg,
        "speed_mps": scenario.speed_mps,
        "expert": run.traits,
    }
    return log_run(
        run.trajectory, meta, lambda t, pos: np.broadcast_to(run.pole_ne, pos.shape), rng, p
    )


def log_run(
    trajectory: FloatArray,
    meta: dict[str, Any],
    echo_ne: Callable[[FloatArray, FloatArray], FloatArray],
    rng: np.random.Generator,
    p: RecorderParams,
) -> Recording:
    """Log one run's true path ``trajectory`` (K, 4) = [t_s, x_N, y_E, ψ] as the recorder does
    (module table) with the metadata ``meta``; ``echo_ne(t, pos)`` gives the position (S, 2) m
    of the object whose radar echo a sweep at times ``t`` (S,) from positions ``pos`` (S, 2)
    records (the pole; on the open-water family the nearest obstacle)."""
    t_end = float(trajectory[-1, 0])
    t_gps = _sample_times(rng, p.gps_rate_hz, t_end, p.jitter_s)
    if rng.random() < p.p_gps_outage:
        start = rng.uniform(0.2 * t_end, 0.8 * t_end)
        t_gps = t_gps[(t_gps < start) | (t_gps > start + rng.uniform(*p.gps_outage_range_s))]
    pos, _ = _pose_at(trajectory, t_gps)
    pos = pos + rng.normal(0.0, p.gps_sigma_m, pos.shape)
    t_cmp = _sample_times(rng, p.compass_rate_hz, t_end, p.jitter_s)
    _, psi = _pose_at(trajectory, t_cmp)
    psi = np.mod(psi + rng.normal(0.0, p.compass_sigma_rad, psi.size), 2 * math.pi)
    t_rad = _sample_times(rng, 1.0 / p.radar_period_s, t_end, p.jitter_s)
    rpos, rpsi = _pose_at(trajectory, t_rad)
    d = echo_ne(t_rad, rpos) - rpos
    rng_m = np.hypot(d[:, 0], d[:, 1]) + rng.normal(0.0, p.radar_range_sigma_m, t_rad.size)
    brg = ssa(
        np.arctan2(d[:, 1], d[:, 0]) - rpsi + rng.normal(0, p.radar_bearing_sigma_rad, t_rad.size)
    )
    seen = rng_m <= p.radar_max_range_m
    return Recording(
        meta=meta,
        gps_t_s=t_gps,
        gps_latlon_deg=geodetic_from_ned(pos[:, 0], pos[:, 1], SITE_ORIGIN),
        compass_t_s=t_cmp,
        compass_rad=psi,
        radar_t_s=t_rad,
        radar_range_m=np.where(seen, rng_m, np.nan),
        radar_bearing_rad=np.where(seen, brg, np.nan),
    )


def record_demonstrations(
    n_runs: int = 46,
    *,
    seed: int = DEMO_SEED,
    scenario: Scenario | None = None,
    expert: ExpertParams | None = None,
    recorder: RecorderParams | None = None,
) -> list[Recording]:
    """Drive ``n_runs`` episodes (drawn from the scenario) with the expert and log them.

    Deterministic in ``seed``: episodes, the expert's traits and the sensor noise each come
    from their own stream spawned from it.
    """
    scenario = scenario or Scenario()
    ep_rng, expert_rng, sensor_rng = np.random.default_rng(seed).spawn(3)
    specs = draw_episodes(ep_rng, scenario, n_runs)
    runs = run_expert(specs, seed=int(expert_rng.integers(2**63)), scenario=scenario, params=expert)
    p = recorder or RecorderParams()
    return [_record_run(run, k, sensor_rng, p, scenario) for k, run in enumerate(runs)]


# ---------------------------------------------------------------------------------------------
# Writing and reading usvsim-demo/1
# ---------------------------------------------------------------------------------------------


def _num(x: float, digits: int) -> str:
    return "" if not math.isfinite(x) else f"{x:.{digits}f}"


def recording_to_text(rec: Recording) -> str:
    """The ``usvsim-demo/1`` text of one recording (module docstring)."""
    rows: list[tuple[float, list[str]]] = []
    for t, (lat, lon) in zip(rec.gps_t_s, rec.gps_latlon_deg, strict=True):
        rows.append((t, ["gps", f"{t:.4f}", f"{lat:.8f}", f"{lon:.8f}", "", "", ""]))
    for t, h in zip(rec.compass_t_s, rec.compass_rad, strict=True):
        rows.append((t, ["compass", f"{t:.4f}", "", "", f"{math.degrees(h):.2f}", "", ""]))
    for t, r, b in zip(rec.radar_t_s, rec.radar_range_m, rec.radar_bearing_rad, strict=True):
        deg = math.degrees(b)
        rows.append((t, ["radar", f"{t:.4f}", "", "", "", _num(r, 2), _num(deg, 2)]))
    rows.sort(key=lambda row: row[0])
    out = io.StringIO()
    magic = FORMAT_SCENE if "scene" in rec.meta else FORMAT
    out.write(f"# {magic} {json.dumps(rec.meta, sort_keys=True)}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(COLUMNS)
    writer.writerows(cells for _, cells in rows)
    return out.getvalue()


def save_recordings(
    recordings: Sequence[Recording], folder: str | Path, *, compress: bool = False
) -> list[Path]:
    """Write each recording to ``folder/demo_NNN.csv`` (``compress``: ``demo_NNN.csv.gz``, the
    same text gzipped), atomically; returns the paths."""
    paths = []
    for rec in recordings:
        path = Path(folder) / f"demo_{int(rec.meta['run']):03d}.csv{'.gz' if compress else ''}"
        text = recording_to_text(rec)
        if compress:
            with atomic_open(path, "wb") as handle:
                # mtime 0: the same recording gives the same bytes (reproducible files)
                handle.write(gzip.compress(text.encode("utf-8"), mtime=0))
        else:
            atomic_write_text(path, text)
        paths.append(path)
    return paths


def _parse_header(path: str, lines: list[str]) -> tuple[dict[str, Any], dict[str, int]]:
    if not lines or not lines[0].startswith("# "):
        raise DemoFormatError(f"{path}, line 1: missing the '# {FORMAT} {{...}}' metadata line")
    magic, _, payload = lines[0][2:].partition(" ")
    if magic not in (FORMAT, FORMAT_SCENE):
        raise DemoFormatError(
            f"{path}, line 1: format {magic!r} is not {FORMAT!r} or {FORMAT_SCENE!r}"
        )
    try:
        meta = json.loads(payload)
    except json.JSONDecodeError as exc:
        raise DemoFormatError(f"{path}, line 1: metadata is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise DemoFormatError(f"{path}, line 1: metadata must be a JSON object")
    missing = [k for k in REQUIRED_METADATA if k not in meta]
    if missing:
        raise DemoFormatError(f"{path}, line 1: metadata lacks {', '.join(missing)}")
    check_site(path, meta)
    if (magic == FORMAT_SCENE) != ("scene" in meta):
        raise DemoFormatError(
            f"{path}, line 1: a {FORMAT_SCENE} file needs the metadata scene, a {FORMAT} file "
            "has none"
        )
    if magic == FORMAT_SCENE:
        DemoScene.from_meta(path, meta)
    n_poles = len(meta["poles_ne"])
    if not (isinstance(meta["pole_index"], int) and 0 <= meta["pole_index"] < n_poles):
        raise DemoFormatError(
            f"{path}, line 1: pole_index {meta['pole_index']!r} is not one of the {n_poles} poles"
        )
    if len(lines) < 2:
        raise DemoFormatError(f"{path}, line 2: missing the column header")
    header = next(csv.reader([lines[1]]))
    absent = [c for c in COLUMNS if c not in header]
    if absent:
        raise DemoFormatError(f"{path}, line 2: missing column(s) {', '.join(absent)}")
    return meta, {c: header.index(c) for c in COLUMNS}


def _cell(path: str, line: int, row: list[str], col: dict[str, int], name: str) -> float:
    """A required finite number."""
    text = row[col[name]].strip() if col[name] < len(row) else ""
    if not text:
        raise DemoFormatError(f"{path}, line {line}, column {name}: empty")
    try:
        value = float(text)
    except ValueError:
        raise DemoFormatError(
            f"{path}, line {line}, column {name}: {text!r} is not a number"
        ) from None
    if not math.isfinite(value):
        raise DemoFormatError(f"{path}, line {line}, column {name}: {text} is not finite")
    return value


def _parse_rows(
    path: str, lines: list[str], col: dict[str, int]
) -> tuple[dict[str, list[list[float]]], list[int]]:
    """The samples of each stream, and the file line of each GPS fix."""
    streams: dict[str, list[list[float]]] = {s: [] for s in STREAM_FIELDS}
    gps_lines: list[int] = []
    for k, row in enumerate(csv.reader(lines[2:])):
        line = k + 3
        if not row:
            continue
        stream = row[col["stream"]] if col["stream"] < len(row) else ""
        if stream not in STREAM_FIELDS:
            raise DemoFormatError(f"{path}, line {line}, column stream: unknown stream {stream!r}")
        t = _cell(path, line, row, col, "t_s")
        values = [t] + [_cell(path, line, row, col, name) for name in STREAM_FIELDS[stream]]
        if stream == "radar":
            cells = [
                row[col[c]].strip() if col[c] < len(row) else "" for c in ("range_m", "bearing_deg")
            ]
            if any(cells) and not all(cells):
                empty = ("range_m", "bearing_deg")[cells.index("")]
                raise DemoFormatError(
                    f"{path}, line {line}, column {empty}: empty while the other echo cell is set"
                )
            values += (
                [_cell(path, line, row, col, "range_m"), _cell(path, line, row, col, "bearing_deg")]
                if all(cells)
                else [math.nan, math.nan]
            )
        if stream == "gps":
            check_fix(path, line, values[1], values[2])
            gps_lines.append(line)
        elif stream == "compass" and abs(values[1]) > 360.0:
            raise DemoFormatError(
                f"{path}, line {line}, column heading_deg: {values[1]} is not in [-360, 360]°"
            )
        elif stream == "radar" and not (
            PLAUSIBLE.min_radar_range_m <= values[1] <= PLAUSIBLE.max_radar_range_m
        ):
            if math.isfinite(values[1]):
                raise DemoFormatError(
                    f"{path}, line {line}, column range_m: {values[1]} is not in "
                    f"[{PLAUSIBLE.min_radar_range_m:g}, {PLAUSIBLE.max_radar_range_m:g}] m"
                )
        previous = streams[stream][-1][0] if streams[stream] else -math.inf
        if t <= previous:
            raise DemoFormatError(
                f"{path}, line {line}, column t_s: {stream} time {t} s is not after the "
                f"previous {stream} sample ({previous} s): time must increase"
            )
        streams[stream].append(values)
    for stream in ("gps", "compass"):
        if len(streams[stream]) < 2:
            raise DemoFormatError(f"{path}: fewer than 2 {stream} samples")
    return streams, gps_lines


def load_recording(path: str | Path) -> Recording:
    """Read and validate one ``usvsim-demo/1`` or ``/2`` file (``.gz``: gzipped);
    :class:`DemoFormatError` if it is bad."""
    name = str(path)
    try:
        raw = Path(path).read_bytes()
        if name.endswith(".gz"):
            raw = gzip.decompress(raw)
        lines = raw.decode("utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise DemoFormatError(f"{name}: not UTF-8 text ({exc.reason})") from None
    except (gzip.BadGzipFile, EOFError) as exc:
        raise DemoFormatError(f"{name}: not a gzip file ({exc})") from None
    except OSError as exc:
        raise DemoFormatError(f"{name}: cannot read ({exc.strerror})") from None
    meta, col = _parse_header(name, lines)
    s, gps_lines = _parse_rows(name, lines, col)
    gps, cmp_, rad = (
        np.array(s[k], dtype=float).reshape(-1, n)
        for k, n in (("gps", 3), ("compass", 2), ("radar", 3))
    )
    origin = GeoOrigin(float(meta["origin_lat_deg"]), float(meta["origin_lon_deg"]))
    check_motion(name, gps_lines, gps[:, 0], ned_from_geodetic(gps[:, 1], gps[:, 2], origin))
    return Recording(
        meta=meta,
        gps_t_s=gps[:, 0],
        gps_latlon_deg=gps[:, 1:3],
        compass_t_s=cmp_[:, 0],
        compass_rad=np.radians(cmp_[:, 1]),
        radar_t_s=rad[:, 0],
        radar_range_m=rad[:, 1],
        radar_bearing_rad=np.radians(rad[:, 2]),
        source=name,
    )


@dataclass(frozen=True)
class LoadReport:
    """Result of loading a folder: the good recordings and, per bad file, what is wrong."""

    recordings: list[Recording]
    errors: dict[str, str]


def load_recordings(folder: str | Path = DEMOS_DIR, pattern: str = "demo_*.csv") -> LoadReport:
    """Load every file matching ``pattern`` (or ``pattern`` + ``.gz``) in ``folder`` (sorted);
    bad files are reported in :attr:`LoadReport.errors` (file → message) and skipped, never
    raised."""
    good: list[Recording] = []
    errors: dict[str, str] = {}
    folder = Path(folder)
    for path in sorted({*folder.glob(pattern), *folder.glob(pattern + ".gz")}):
        try:
            good.append(load_recording(path))
        except (DemoFormatError, OSError) as exc:
            errors[str(path)] = str(exc)
    return LoadReport(good, errors)


# ---------------------------------------------------------------------------------------------
# Quality filter
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class QualityCriteria:
    """Thresholds of :func:`quality_check` (usvsim's, from the task's definitions)."""

    max_gps_gap_s: float = 3.0  # s, longer gaps leave decision periods without a position
    max_compass_gap_s: float = 1.0  # s
    min_pole_distance_m: float = 10.0  # m, the task's safety distance (GPS fixes)
    max_heading_change_rad: float = math.radians(30.0)  # rad per 2 s, the action bound
    min_past_pole_m: float = 40.0  # m, the run must end this far beyond the pole
    max_goal_distance_m: float = 20.0  # m, a /2 run's last fix this close to its goal (10 m
    # goal radius, up to 1 s between fixes at 5 m/s, GPS noise)


def quality_check(rec: Recording, criteria: QualityCriteria | None = None) -> list[str]:
    """Why ``rec`` is unfit as a demonstration (empty list: keep it). Recorded data only.

    Rejects: a GPS or compass gap longer than the limit; a GPS fix closer to the pole than the
    safety distance (an unsafe or lucky pass is not a behaviour to imitate); a heading change
    over any 2 s larger than the action bound (the policy could not reproduce it); a run that
    does not end well beyond the pole (aborted). A ``usvsim-demo/2`` run (a scene): a fix
    closer than the safety distance to any obstacle where it was at that time, and a run that
    does not end at its goal.
    """
    c = criteria or QualityCriteria()
    reasons = []
    for name, t, limit in (
        ("GPS", rec.gps_t_s, c.max_gps_gap_s),
        ("compass", rec.compass_t_s, c.max_compass_gap_s),
    ):
        gaps = np.diff(t)
        if gaps.size and gaps.max() > limit:
            k = int(np.argmax(gaps))
            reasons.append(f"{name} gap of {gaps[k]:.1f} s at t = {t[k]:.1f} s (> {limit} s)")
    ne = rec.gps_ne
    scene = rec.scene
    d_pole = np.hypot(*(ne - rec.pole_ne).T) if scene is None else scene.distance_m(rec.gps_t_s, ne)
    what = "the pole" if scene is None else "an obstacle (pole-equivalent)"
    if d_pole.min() < c.min_pole_distance_m:
        reasons.append(f"passed {d_pole.min():.1f} m from {what} (< {c.min_pole_distance_m} m)")
    grid = np.arange(rec.compass_t_s[0], rec.compass_t_s[-1] - 2.0, 0.2)
    psi = np.interp(grid, rec.compass_t_s, np.unwrap(rec.compass_rad))
    psi_later = np.interp(grid + 2.0, rec.compass_t_s, np.unwrap(rec.compass_rad))
    if grid.size and np.abs(psi_later - psi).max() > c.max_heading_change_rad:
        reasons.append(
            f"heading changed {math.degrees(np.abs(psi_later - psi).max()):.0f}° within 2 s "
            f"(> {math.degrees(c.max_heading_change_rad):.0f}°)"
        )
    if scene is not None:
        d_goal = float(np.hypot(*(ne[-1] - scene.goal_ne)))
        if d_goal > c.max_goal_distance_m:
            reasons.append(f"ended {d_goal:.0f} m from the goal (> {c.max_goal_distance_m} m)")
        return reasons
    course = ne[-1] - ne[0]
    past = float((ne[-1] - rec.pole_ne) @ course / max(float(np.linalg.norm(course)), 1e-9))
    if past < c.min_past_pole_m:
        reasons.append(f"ended {past:.0f} m past the pole (< {c.min_past_pole_m} m)")
    return reasons


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m learning.imitation.demonstrations FOLDER``: record the 46 runs into FOLDER.

    FOLDER is required: nothing is ever written into the installed package unasked (to
    regenerate the shipped ones, name ``usvsim/demos`` of a source checkout). Exit status 2
    with a one-line message when FOLDER is missing or cannot be written.
    """
    folder = demo_folder(
        argv,
        "learning.imitation.demonstrations",
        "records the 46 expert runs into FOLDER/demo_NNN.csv",
    )
    if folder is None:
        return 2
    write_demo_set(record_demonstrations(), folder)
    return 0


def demo_folder(argv: Sequence[str] | None, prog: str, what: str) -> Path | None:
    """The one FOLDER argument of a recorder's command line (``argv``, default ``sys.argv``),
    writable and cleared of a killed earlier run's temporaries; None after printing a one-line
    usage or error to stderr (exit status 2)."""
    import sys

    from usvsim.common.fileio import check_writable_dir, remove_stale_temporaries

    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 1 or args[0].startswith("-"):
        print(f"usage: python -m {prog} FOLDER  ({what}; FOLDER is required)", file=sys.stderr)
        return None
    try:
        folder = check_writable_dir(args[0], "FOLDER")
    except UserError as err:
        print(f"{prog}: {err}", file=sys.stderr)
        return None
    remove_stale_temporaries(folder)  # what a killed earlier run left
    return folder


def write_demo_set(recs: Sequence[Recording], folder: Path, *, compress: bool = False) -> None:
    """Write ``recs`` into ``folder`` as one set (a kill leaves the previous set, never a mix of
    two; every earlier ``demo_*`` file goes) and print what the quality filter says of each."""
    from usvsim.common.fileio import staged_dir

    with staged_dir(folder, "demos", replaces=["demo_*.csv", "demo_*.csv.gz"]) as staging:
        save_recordings(recs, staging, compress=compress)
    kept = [r for r in recs if not quality_check(r)]
    print(f"recorded {len(recs)} runs into {folder}; {len(kept)} pass the quality filter")
    for r in recs:
        for why in quality_check(r):
            print(f"  run {r.meta['run']:3d}: {why}")


if __name__ == "__main__":
    raise SystemExit(main())
