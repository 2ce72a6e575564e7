"""Waypoint paths of N boats and the waypoint manager (active straight-line segment per boat).

Each boat follows its own polyline of waypoints. Boats may have different numbers of waypoints, so
the paths are stored padded:

==================  ============  ===========================================================
name                shape         content
==================  ============  ===========================================================
points_m            (N, K, 2)     waypoints [x_N, y_E] (m); rows ``counts[i]..K-1`` are padding
counts              (N,)          number of valid waypoints of each boat (≥ 2)
segment             (N,)          active segment: boat i steers along points[i, s] → points[i, s+1]
pos_m               (N, 2)        boat positions [x_N, y_E] (m)
==================  ============  ===========================================================

Path-fixed errors (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion Control*,
2nd ed., §12.4, the straight-line path-following errors; MSS ``LOSchi``/``ILOSpsi``/``ALOSpsi``):
with the segment start p_k, its path-tangential angle π_p = atan2(Δy_E, Δx_N) and
R(π_p) the rotation from the path frame to NED,

    [x_e, y_e]ᵀ = R(π_p)ᵀ (p − p_k)
    x_e =  (x − x_k) cos π_p + (y − y_k) sin π_p      along-track distance (m)
    y_e = −(x − x_k) sin π_p + (y − y_k) cos π_p      cross-track error (m), > 0 starboard of path

Switching rule (MSS ``LOSchi``/``ILOSpsi``/``ALOSpsi``): a boat moves to the next segment when its
*along-track distance to the next waypoint*, ``d − x_e`` with d the segment length, is below the
switching radius R_switch. Every point inside the circle of acceptance of radius R_switch around
the next waypoint satisfies this, so the rule is the circle of acceptance widened to the whole
half-plane past the normal to the path R_switch before the waypoint: a boat that misses the
circle (large cross-track error) still switches when it comes abeam of the waypoint and never
turns back to hit it. Several segments may be passed in one update (long update intervals).

Last waypoint: the final segment is never left; beyond the last waypoint the boat keeps following
the extension of the final line (MSS extends it by a far-away virtual waypoint, same effect).
``finished`` reports boats whose along-track distance to the last waypoint is below R_switch.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "PathErrors",
    "WaypointManager",
    "WaypointPath",
    "advance_segments",
    "as_mask",
    "as_positions",
    "check_switch_radius",
    "path_errors",
]


@dataclass(frozen=True)
class WaypointPath:
    """Padded waypoint lists of N boats (see the module's shape table).

    Parameters
    ----------
    points_m : (N, K, 2) float
        Waypoints [x_N, y_E] (m). Entries at index ≥ ``counts[i]`` are padding and never read.
    counts : (N,) int
        Number of valid waypoints per boat, 2 ≤ counts ≤ K.

    Raises
    ------
    ValueError
        Wrong shapes, fewer than 2 waypoints, NaN/inf in a valid waypoint, or two consecutive
        valid waypoints closer than 1 mm (a segment without a direction).

    Examples
    --------
    >>> path = WaypointPath.from_lists([[(0, 0), (100, 0)], [(0, 0), (50, 50), (100, 0)]])
    >>> path.points_m.shape, path.counts.tolist()
    ((2, 3, 2), [2, 3])
    """

    points_m: NDArray[np.float64]
    counts: NDArray[np.int64]

    def __post_init__(self) -> None:
        points = np.asarray(self.points_m, dtype=float)
        counts = np.asarray(self.counts)
        if points.ndim != 3 or points.shape[2] != 2 or points.shape[0] < 1:
            raise ValueError(f"points_m must have shape (N, K, 2) with N ≥ 1, got {points.shape}")
        n, k, _ = points.shape
        if counts.shape != (n,) or not np.issubdtype(counts.dtype, np.integer):
            raise ValueError(
                f"counts must be integers of shape ({n},), got {counts.dtype} {counts.shape}"
            )
        if np.any(counts < 2) or np.any(counts > k):
            raise ValueError(
                f"each boat needs at least 2 waypoints (and at most K = {k}), "
                f"got counts {counts.tolist()}"
            )
        valid = np.arange(k)[None, :] < counts[:, None]  # (N, K)
        if not np.all(np.isfinite(points[valid])):
            raise ValueError("waypoints contain NaN or inf")
        seg_len = np.linalg.norm(np.diff(points, axis=1), axis=2)  # (N, K-1)
        seg_valid = valid[:, 1:]
        if np.any(seg_len[seg_valid] < 1e-3):
            raise ValueError(
                "consecutive waypoints must be at least 1 mm apart (a segment needs a direction)"
            )
        object.__setattr__(self, "points_m", points)
        object.__setattr__(self, "counts", counts.astype(np.int64))

    @classmethod
    def from_lists(cls, paths: Sequence[ArrayLike]) -> WaypointPath:
        """Pad one (K_i, 2) waypoint list per boat; padding repeats each boat's last waypoint."""
        arrays = [np.asarray(p, dtype=float) for p in paths]
        if not arrays:
            raise ValueError("need at least one boat's waypoint list")
        for i, a in enumerate(arrays):
            if a.ndim != 2 or a.shape[1] != 2:
                raise ValueError(f"waypoints of boat {i} must have shape (K, 2), got {a.shape}")
            if a.shape[0] < 2:
                raise ValueError(f"boat {i} has {a.shape[0]} waypoint(s); at least 2 are needed")
        k = max(a.shape[0] for a in arrays)
        points = np.stack(
            [np.concatenate([a, np.repeat(a[-1:], k - len(a), axis=0)]) for a in arrays]
        )
        return cls(points_m=points, counts=np.array([len(a) for a in arrays], dtype=np.int64))

    @property
    def n_boats(self) -> int:
        return int(self.points_m.shape[0])

    @property
    def max_points(self) -> int:
        return int(self.points_m.shape[1])

    def segment_lengths_m(self) -> NDArray[np.float64]:
        """Length (m) of every valid segment, NaN for padding: shape (N, K-1)."""
        lengths = np.linalg.norm(np.diff(self.points_m, axis=1), axis=2)
        valid = np.arange(1, self.max_points)[None, :] < self.counts[:, None]
        return np.where(valid, lengths, np.nan)

    def replace_rows(self, mask: NDArray[np.bool_], other: WaypointPath) -> WaypointPath:
        """A path with boats ``mask`` (N,) taken from ``other`` (same N, any K)."""
        if other.n_boats != self.n_boats:
            raise ValueError(f"new path has {other.n_boats} boats, expected {self.n_boats}")
        k = max(self.max_points, other.max_points)
        a, b = _pad_to(self.points_m, k), _pad_to(other.points_m, k)
        return WaypointPath(
            points_m=np.where(mask[:, None, None], b, a),
            counts=np.where(mask, other.counts, self.counts),
        )


def _pad_to(points: NDArray[np.float64], k: int) -> NDArray[np.float64]:
    extra = k - points.shape[1]
    return np.concatenate([points, np.repeat(points[:, -1:], extra, axis=1)], axis=1)


@dataclass(frozen=True)
class PathErrors:
    """Errors of N boats relative to their active segments; all arrays (N,)."""

    segment: NDArray[np.int64]  # -, active segment index (0-based)
    path_angle_rad: NDArray[np.float64]  # rad, π_p, path-tangential angle from north
    along_track_m: NDArray[np.float64]  # m, x_e from the segment's start
    cross_track_m: NDArray[np.float64]  # m, y_e, > 0 when the boat is starboard of the path
    to_go_m: NDArray[np.float64]  # m, d − x_e, along-track distance to the segment's end
    switched: NDArray[np.bool_]  # -, the segment advanced in this update
    finished: NDArray[np.bool_]  # -, on the last segment and within R_switch of its end


def as_positions(pos_m: ArrayLike, n: int) -> NDArray[np.float64]:
    """Check boat positions: shape (n, 2), finite; raises ValueError otherwise."""
    pos = np.asarray(pos_m, dtype=float)
    if pos.shape != (n, 2):
        raise ValueError(f"pos_m must have shape ({n}, 2), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        bad = np.flatnonzero(~np.isfinite(pos).all(axis=1)).tolist()
        raise ValueError(f"pos_m contains NaN or inf (boats {bad})")
    return pos


def path_errors(
    path: WaypointPath, segment: NDArray[np.int64], pos_m: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """π_p, x_e, y_e and d − x_e of each boat on segment ``segment`` (see module docstring)."""
    rows = np.arange(path.n_boats)
    start = path.points_m[rows, segment]
    end = path.points_m[rows, segment + 1]
    delta = end - start
    pi_p = np.arctan2(delta[:, 1], delta[:, 0])
    length = np.hypot(delta[:, 0], delta[:, 1])
    dx, dy = pos_m[:, 0] - start[:, 0], pos_m[:, 1] - start[:, 1]
    c, s = np.cos(pi_p), np.sin(pi_p)
    x_e = dx * c + dy * s
    y_e = -dx * s + dy * c
    return pi_p, x_e, y_e, length - x_e


def advance_segments(
    path: WaypointPath,
    segment: NDArray[np.int64],
    pos_m: NDArray[np.float64],
    switch_radius_m: float,
) -> PathErrors:
    """Advance each boat's segment while ``d − x_e < R_switch`` and a next segment exists.

    Loops over segments (at most K − 2 passes), never over boats. Returns the errors on the new
    active segments. ``pos_m`` must already be checked (:func:`as_positions`).
    """
    last = path.counts - 2
    seg = np.minimum(np.asarray(segment, dtype=np.int64), last)
    start_seg = seg.copy()
    for _ in range(path.max_points - 1):
        pi_p, x_e, y_e, to_go = path_errors(path, seg, pos_m)
        switch = (to_go < switch_radius_m) & (seg < last)
        if not np.any(switch):
            break
        seg = seg + switch
    return PathErrors(
        segment=seg,
        path_angle_rad=pi_p,
        along_track_m=x_e,
        cross_track_m=y_e,
        to_go_m=to_go,
        switched=seg != start_seg,
        finished=(seg == last) & (to_go < switch_radius_m),
    )


class WaypointManager:
    """Active segment of N boats with per-boat reset; a thin holder over :func:`advance_segments`.

    Parameters
    ----------
    path : WaypointPath
        The boats' waypoints.
    switch_radius_m : float
        R_switch (m), > 0 and shorter than every segment (as MSS requires).
    """

    def __init__(self, path: WaypointPath, switch_radius_m: float) -> None:
        check_switch_radius(path, switch_radius_m)
        self.path = path
        self.switch_radius_m = float(switch_radius_m)
        self.segment = np.zeros(path.n_boats, dtype=np.int64)

    def reset(self, mask: ArrayLike | None = None, path: WaypointPath | None = None) -> None:
        """Send boats ``mask`` (N,) bool (default all) back to segment 0, optionally new paths."""
        m = as_mask(mask, self.path.n_boats)
        if path is not None:
            new_path = self.path.replace_rows(m, path)
            check_switch_radius(new_path, self.switch_radius_m)
            self.path = new_path
        self.segment = np.where(m, 0, self.segment)

    def update(self, pos_m: ArrayLike) -> PathErrors:
        """Advance segments for positions ``pos_m`` (N, 2) [m] and return the path errors."""
        errors = advance_segments(
            self.path, self.segment, as_positions(pos_m, self.path.n_boats), self.switch_radius_m
        )
        self.segment = errors.segment
        return errors


def check_switch_radius(path: WaypointPath, switch_radius_m: float) -> None:
    """R_switch must be positive, finite and shorter than every segment (MSS ``ILOSpsi``)."""
    if not (np.isfinite(switch_radius_m) and switch_radius_m > 0):
        raise ValueError(f"switch_radius_m must be > 0 m, got {switch_radius_m}")
    shortest = float(np.nanmin(path.segment_lengths_m()))
    if switch_radius_m >= shortest:
        raise ValueError(
            f"switch_radius_m ({switch_radius_m} m) must be shorter than every "
            f"segment (shortest {shortest:.3g} m)"
        )


def as_mask(mask: ArrayLike | None, n: int) -> NDArray[np.bool_]:
    """A boolean (n,) boat mask; ``None`` means all boats."""
    if mask is None:
        return np.ones(n, dtype=bool)
    m = np.asarray(mask)
    if m.shape != (n,) or m.dtype != np.bool_:
        raise ValueError(f"mask must be a boolean array of shape ({n},), got {m.dtype} {m.shape}")
    return m
