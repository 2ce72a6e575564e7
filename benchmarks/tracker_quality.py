"""Quality of the radar tracker (:mod:`usvsim.nav.tracker`) on the stress sets, against the truth.

Each open-water stress set (:mod:`usvsim.evaluation.stress`; ``waypoints`` has no scene of discs
and is left out) is run with the ``vo-radar`` helmsman (:mod:`baselines.vo_radar`: the tracker's
tracks steer the boat, so the geometry is the one the tracker meets in use). After every
decision its confirmed tracks are compared with the true discs at that time
(:meth:`usvsim.task.openwater_batch.OpenWaterBatch.scene_at`), while the episode runs::

    python benchmarks/tracker_quality.py                     # 30 episodes per set
    python benchmarks/tracker_quality.py --episodes 100 --sets radar-noise,moving-vessels
    python benchmarks/tracker_quality.py --image frame.npy   # the detections in one saved frame
    python benchmarks/tracker_quality.py --compare stress.json more.json --reference vo-radar

``--compare`` reads stress-suite JSON files (``usvsim bench --suite stress --json``) and names,
for every helmsman against ``--reference``, the sets where its success rate differs from the
reference's by more than both Wilson 95 % intervals (each rate outside the other's interval).

==========================  ===================================================================
figure                      definition
==========================  ===================================================================
in view                     a disc wholly inside the image: ρ + R < max range, |φ| + asin(R/ρ)
                            < half field of view (ρ, φ from the true own position and heading)
matched                     a confirmed track within R + 10 m of a disc's centre (greedy, the
                            nearest pairs first; one track per disc)
position error (m)          |track position − disc centre| of the matched pairs, discs in view
                            (a coasting track astern, or the visible part of an islet cut by
                            the image's edge, is not a measure of the tracker's accuracy)
velocity error (m/s)        |track velocity − disc velocity| of the same pairs
missed targets / episode    discs in view for ≥ 3 consecutive decisions that were never matched
                            in the episode
miss share (%)              (disc, decision) pairs in view for ≥ 3 decisions without a match
false tracks / episode      confirmed tracks (distinct ids) never within R + 10 m of any disc
==========================  ===================================================================

Writes ``tracker_quality.json`` and ``tracker_quality.md`` to ``--out`` (default
``tracker-quality/``) and prints the Markdown. Bad input (``--image`` of the wrong shape, an
unknown set) is one line on stderr and exit status 2 (:class:`usvsim.common.errors.UserError`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.vo_radar import VORadarHelmsman
from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_write_text, json_safe
from usvsim.evaluation.stress import select_sets, stress_episodes
from usvsim.nav.tracker import greedy_pairs
from usvsim.nav.tracker_detections import detect
from usvsim.task.observations import relative_polar
from usvsim.task.openwater_batch import OpenWaterBatch
from usvsim.task.radar import RadarConfig

FloatArray = NDArray[np.float64]
MATCH_MARGIN_M = 10.0  # m beyond the disc's edge: a track that close belongs to it
GRACE_DECISIONS = 3  # decisions in view before a disc must be tracked (issue 37)


@dataclass(frozen=True)
class SetQuality:
    """The figures of one set (module docstring)."""

    set: str
    episodes: int
    decisions: int
    matched_pairs: int
    position_error_median_m: float
    position_error_p95_m: float
    velocity_error_median_mps: float
    velocity_error_p95_mps: float
    missed_targets_per_episode: float
    miss_share_percent: float
    false_tracks_per_episode: float
    success_percent: float
    wall_s: float


def in_view(rho: FloatArray, phi: FloatArray, radius: FloatArray, radar: RadarConfig) -> Any:
    """Whether each disc lies wholly inside the image (module docstring)."""
    half = np.arcsin(np.minimum(radius / np.maximum(rho, 1e-9), 1.0))
    return (
        (rho > radius)
        & (rho + radius < radar.max_range_m)
        & (np.abs(phi) + half < radar.half_fov_rad)
    )


def run_set(stress_set: Any, n: int, radar: RadarConfig) -> SetQuality:
    """The figures of ``n`` episodes of one set (module docstring)."""
    t0 = time.perf_counter()
    episodes = list(stress_episodes(stress_set, n))
    sim = OpenWaterBatch(n, observation="radar+nav", radar=radar)
    helm = VORadarHelmsman(radar=radar)
    obs = sim.reset(None, episodes)
    helm.reset(n)
    dp = sim.base.decision_period_s
    k_max = max(math.ceil(e.time_limit_s / dp - 1e-9) for e in episodes)
    active = np.ones(n, dtype=bool)
    success = np.zeros(n, dtype=bool)
    pos_err: list[FloatArray] = []
    vel_err: list[FloatArray] = []
    streak: NDArray[np.int64] | None = None
    ever_due: NDArray[np.bool_] | None = None
    ever_matched: NDArray[np.bool_] | None = None
    due_pairs = due_missed = decisions = 0
    true_ids: list[set[int]] = [set() for _ in range(n)]
    all_ids: list[set[int]] = [set() for _ in range(n)]
    for k in range(k_max):
        actions = helm.act(obs)
        tg = helm.tracker.targets()
        centres, radii, velocity, ok = sim.scene_at(np.full(n, k * dp))
        eta = sim.inner.state.eta
        rho, phi = relative_polar(eta[:, 0:2], eta[:, 2], centres)
        view = ok & in_view(rho, phi, radii, radar) & active[:, None]
        if streak is None:
            streak = np.zeros(ok.shape, dtype=np.int64)
            ever_due = np.zeros(ok.shape, dtype=bool)
            ever_matched = np.zeros(ok.shape, dtype=bool)
        assert ever_due is not None and ever_matched is not None
        streak = np.where(view, streak + 1, 0)
        dist = np.linalg.norm(centres[:, :, None] - tg.position_ne[:, None], axis=-1)  # (N,J,M)
        near = ok[..., None] & tg.valid[:, None] & (dist <= radii[..., None] + MATCH_MARGIN_M)
        pair = greedy_pairs(np.where(near & active[:, None, None], dist, np.inf))
        matched = pair >= 0
        b, d = np.nonzero(matched & view)  # errors of wholly visible discs
        t = pair[b, d]
        pos_err.append(dist[b, d, t])
        vel_err.append(np.linalg.norm(tg.velocity_ne[b, t] - velocity[b, d], axis=-1))
        due = view & (streak >= GRACE_DECISIONS)
        due_pairs += int(due.sum())
        due_missed += int((due & ~matched).sum())
        ever_due |= due
        ever_matched |= matched
        near_any = near.any(axis=1)  # (N, M): the track is near some disc
        for bi, ti in zip(*np.nonzero(tg.valid & active[:, None]), strict=True):
            tid = int(tg.track_id[bi, ti])
            all_ids[bi].add(tid)
            if near_any[bi, ti]:
                true_ids[bi].add(tid)
        decisions += int(active.sum())
        res = sim.step(actions)
        ended = active & (res.terminated | res.truncated)
        success[ended] = res.is_success[ended]
        active &= ~ended
        if not active.any():
            break
        obs = res.observation
    assert ever_due is not None and ever_matched is not None
    pe, ve = np.concatenate(pos_err), np.concatenate(vel_err)
    false_tracks = sum(len(a - t) for a, t in zip(all_ids, true_ids, strict=True))

    def pct(x: FloatArray, q: float) -> float:
        return float(np.percentile(x, q)) if x.size else math.nan

    return SetQuality(
        set=stress_set.name,
        episodes=n,
        decisions=decisions,
        matched_pairs=int(pe.size),
        position_error_median_m=pct(pe, 50),
        position_error_p95_m=pct(pe, 95),
        velocity_error_median_mps=pct(ve, 50),
        velocity_error_p95_mps=pct(ve, 95),
        missed_targets_per_episode=float((ever_due & ~ever_matched).sum()) / n,
        miss_share_percent=100.0 * due_missed / max(due_pairs, 1),
        false_tracks_per_episode=false_tracks / n,
        success_percent=100.0 * float(success.mean()),
        wall_s=time.perf_counter() - t0,
    )


def markdown(rows: Sequence[SetQuality], command: str) -> str:
    """The table of the figures (module docstring), one row per set."""
    lines = [
        "# Radar tracker quality on the stress sets",
        "",
        f"{rows[0].episodes if rows else 0} episodes per set, `vo-radar` steering; errors of "
        "confirmed tracks matched to true discs (benchmarks/tracker_quality.py docstring). "
        f"Reproduce: `{command}`.",
        "",
        "| set | pos. err. median / p95 (m) | vel. err. median / p95 (m/s) | missed targets / ep. "
        "| miss share (%) | false tracks / ep. | vo-radar success (%) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r.set} | {r.position_error_median_m:.2f} / {r.position_error_p95_m:.2f} "
            f"| {r.velocity_error_median_mps:.2f} / {r.velocity_error_p95_mps:.2f} "
            f"| {r.missed_targets_per_episode:.2f} | {r.miss_share_percent:.1f} "
            f"| {r.false_tracks_per_episode:.2f} | {r.success_percent:.0f} |"
        )
    return "\n".join(lines) + "\n"


def separated(a: dict[str, Any], b: dict[str, Any]) -> int:
    """+1 if row ``a``'s success is above ``b``'s by more than both Wilson intervals (each rate
    outside the other's interval), -1 if below by as much, else 0."""
    ra, rb = a["success_rate"], b["success_rate"]
    if ra > b["success_ci95_high"] and rb < a["success_ci95_low"]:
        return 1
    if ra < b["success_ci95_low"] and rb > a["success_ci95_high"]:
        return -1
    return 0


def compare_stress(paths: Sequence[str], reference: str) -> str:
    """Markdown: per helmsman of the stress JSON files, the sets better / worse than
    ``reference`` outside both intervals (``--compare``)."""
    rows: dict[tuple[str, str], dict[str, Any]] = {}
    for path in paths:
        try:
            payload = json.loads(Path(path).read_text())
            for r in payload["rows"]:
                rows[(r["helmsman"], r["episode_set"])] = r
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise UserError(f"--compare {path}: not a stress-suite JSON file ({err})") from None
    helmsmen = sorted({h for h, _ in rows} - {reference})
    sets = [s for h, s in rows if h == reference]
    if not sets:
        raise UserError(f"--reference {reference}: no rows of it in the files")
    lines = [
        f"| helmsman | better than {reference} | worse than {reference} |",
        "|---|---|---|",
    ]
    for h in helmsmen:
        verdict: dict[int, list[str]] = {1: [], -1: []}
        for s in sets:
            if (h, s) in rows:
                v = separated(rows[(h, s)], rows[(reference, s)])
                if v:
                    pa, pb = rows[(h, s)]["success_rate"], rows[(reference, s)]["success_rate"]
                    verdict[v].append(f"{s} ({100 * pa:.0f} vs {100 * pb:.0f})")
        lines.append(f"| {h} | {', '.join(verdict[1]) or '–'} | {', '.join(verdict[-1]) or '–'} |")
    return "\n".join(lines) + "\n"


def show_image(path: str, radar: RadarConfig) -> None:
    """Print the detections of a saved frame (.npy, (N, 1, rows, cols) or (N, rows, cols))."""
    try:
        images = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as err:
        raise UserError(f"--image {path}: not a readable .npy array ({err})") from None
    if images.ndim == 2:  # one frame, rows × cols
        images = images[None]
    n = images.shape[0] if images.ndim >= 3 else 1
    det = detect(images, radar, np.zeros((n, 2)), np.zeros(n))
    for i in range(n):
        for j in np.flatnonzero(det.valid[i]):
            print(
                f"image {i}: range {det.range_m[i, j]:.1f} m, bearing "
                f"{math.degrees(det.bearing_rad[i, j]):.1f} deg, radius {det.radius_m[i, j]:.1f} m"
            )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=30, help="episodes per set")
    parser.add_argument("--sets", default="", help="comma-separated stress sets (default: all)")
    parser.add_argument("--out", default="tracker-quality", help="output folder")
    parser.add_argument("--image", default=None, help="a saved radar frame (.npy) to detect in")
    parser.add_argument("--compare", nargs="+", default=None, help="stress-suite JSON files")
    parser.add_argument("--reference", default="vo-radar", help="--compare: the reference")
    args = parser.parse_args(argv)
    radar = RadarConfig()
    try:
        if args.compare is not None:
            print(compare_stress(args.compare, args.reference), end="")
            return 0
        if args.image is not None:
            show_image(args.image, radar)
            return 0
        if args.episodes < 1:
            raise UserError(f"--episodes must be >= 1, got {args.episodes}")
        sets = [
            s for s in select_sets([x.strip() for x in args.sets.split(",") if x.strip()])
            if s.kind != "waypoints"
        ]  # fmt: skip
        rows = []
        for s in sets:
            rows.append(run_set(s, args.episodes, radar))
            print(f"{s.name}: {rows[-1].wall_s:.0f} s", file=sys.stderr, flush=True)
    except UserError as err:
        print(f"tracker_quality: {err}", file=sys.stderr)
        return 2
    command = "python benchmarks/tracker_quality.py " + " ".join(
        argv if argv is not None else sys.argv[1:]
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    payload = {"episodes_per_set": args.episodes, "command": command.strip(),
               "sets": [asdict(r) for r in rows]}  # fmt: skip
    text = json.dumps(json_safe(payload), indent=2, allow_nan=False)
    atomic_write_text(out / "tracker_quality.json", text)
    md = markdown(rows, command.strip())
    atomic_write_text(out / "tracker_quality.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
