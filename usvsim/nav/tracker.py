"""Multi-target tracking of radar returns for N boats at once: the classical radar → tracks chain.

Every decision (one radar frame, period ``dt``) :meth:`RadarTracker.update` takes the frame's
detections (:mod:`usvsim.nav.tracker_detections`, placed in NED with the navigation estimate)
and runs, for all boats and all track slots together (arrays (N, M, ...), M = ``max_tracks``):

1. **Predict** every track with the constant-velocity model, state ``[n, e, v_n, v_e]`` (m, m/s)::

       F = [[I, dt I], [0, I]],   Q = Q_discrete_white_noise(2, dt, q, block_size=2)

   (filterpy's piecewise white-noise acceleration Q, variance ``q`` in (m/s²)²; Bar-Shalom, Li &
   Kirubarajan 2001, *Estimation with Applications to Tracking and Navigation*, §6.3.3).
2. **Gate** each (track, detection) pair by the Mahalanobis distance d² = yᵀ S⁻¹ y,
   S = H P Hᵀ + R (R the detection's covariance): pairs with d² > ``gate`` (χ²₂ at 99.9 %:
   13.8) cannot be associated.
3. **Associate** by global nearest neighbour, greedily: the cheapest remaining pair
   (cost d² + ln |S|, Blackman & Popoli 1999, §6.4; tentative tracks ``tentative_cost`` more)
   of every boat at once, its track and detection struck out, repeated until no gated pair is
   left (at most M rounds, each over all boats).
4. **Update** associated tracks (Kalman update in Joseph form, as filterpy's ``KalmanFilter``;
   tested equal to it on one track), their radius as an exponential mean of the detections'.
5. **Manage**: the last ``n_window`` frames' hits are kept as bits; a tentative track is
   *confirmed* once ``m_hits`` of them are hits (M of N), and dropped once it can no longer get
   there. A track whose second frame repeats its first detection's position (χ² of the
   difference ≤ ``static_confirm_gate``: a static return; clutter seldom lights the same spot
   twice) is confirmed at once, on probation: it is dropped if its first N frames do not hold
   M hits. A boat that starts 30 m from a pole has no time for three frames. A confirmed track
   is dropped after ``max_misses`` consecutive misses while its
   predicted position lies in the radar's view; out of view (astern, beyond range) it coasts
   on its model for up to ``max_coast`` frames. An unassociated detection starts a tentative
   track in a free slot (position the detection, velocity 0 with σ = ``init_speed_sigma_mps``).

:meth:`RadarTracker.targets` gives the confirmed tracks as the ``scene`` observation's obstacle
list holds them (position, velocity over ground, radius), with their covariance.

No Python loop over boats, tracks or detections: the loops are over association rounds (≤ M).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from filterpy.common import Q_discrete_white_noise
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.nav.tracker_detections import (
    Detections,
    DetectorConfig,
    ImageGeometry,
    detect,
)

__all__ = [
    "RadarTracker",
    "TrackTargets",
    "TrackerConfig",
    "cv_model",
    "greedy_pairs",
    "inv2",
    "kf_predict",
    "kf_update",
]

FloatArray = NDArray[np.float64]
_H = np.hstack([np.eye(2), np.zeros((2, 2))])  # position is measured
_EMPTY, _TENTATIVE, _CONFIRMED = 0, 1, 2


@dataclass(frozen=True)
class TrackerConfig:
    """Tracker parameters (module docstring); usvsim's choices, checked on clean and degraded
    frames by ``benchmarks/tracker_quality.py``, not tuned on the stress suite's episodes."""

    dt_s: float = 2.0  # s, frame period: one radar frame per decision (the study's 2 s)
    accel_variance: float = 0.05  # (m/s²)², q: vessels turn slowly; the own-pose error moves
    max_tracks: int = 24  # M, track slots per boat
    gate: float = 13.8  # χ²₂ at 99.9 %
    tentative_cost: float = 4.0  # added to a tentative track's pairs: confirmed ones pick first
    m_hits: int = 3  # M of N confirmation
    n_window: int = 4
    # χ²₂ gate of a second hit that repeats the first one's position (a static return): such a
    # track is confirmed at once, on probation until its N-th frame (0: M of N only)
    static_confirm_gate: float = 9.21
    # m: a new detection nearer than this is confirmed at once, on probation (0: off)
    immediate_range_m: float = 0.0
    # the first frame after a reset confirms its detections at once, on probation: the radar
    # of a boat at sea has been tracking before an episode starts
    confirm_first_frame: bool = True
    max_misses: int = 3  # consecutive misses in view that drop a confirmed track
    max_coast: int = 15  # frames a confirmed track coasts out of view (30 s)
    init_speed_sigma_mps: float = 3.0  # m/s, σ of a new track's velocity (vessels ≤ 4 m/s)
    radius_smoothing: float = 0.3  # -, weight of a new detection's radius
    detector: DetectorConfig = field(default_factory=DetectorConfig)

    def __post_init__(self) -> None:
        if not (1 <= self.m_hits <= self.n_window <= 8):
            raise ValueError("TrackerConfig needs 1 <= m_hits <= n_window <= 8")
        if self.dt_s <= 0 or self.max_tracks < 1 or self.gate <= 0:
            raise ValueError("TrackerConfig needs dt_s > 0, max_tracks >= 1 and gate > 0")


def cv_model(dt_s: float, accel_variance: float) -> tuple[FloatArray, FloatArray]:
    """F and Q (4×4) of the constant-velocity model, state ``[n, e, v_n, v_e]`` (filterpy's Q)."""
    f = np.eye(4)
    f[0, 2] = f[1, 3] = dt_s
    q = Q_discrete_white_noise(dim=2, dt=dt_s, var=accel_variance, block_size=2, order_by_dim=False)
    return f, np.asarray(q, dtype=float)


def kf_predict(
    x: FloatArray, p: FloatArray, f: FloatArray, q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Kalman prediction of states ``x`` (..., 4) and covariances ``p`` (..., 4, 4)."""
    return x @ f.T, f @ p @ f.T + q


def kf_update(
    x: FloatArray, p: FloatArray, z: FloatArray, r: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Kalman update (Joseph form, as filterpy) of ``x`` (..., 4), ``p`` (..., 4, 4) with
    position measurements ``z`` (..., 2) of covariance ``r`` (..., 2, 2)."""
    s = p[..., :2, :2] + r  # H P Hᵀ + R
    k = p[..., :, :2] @ inv2(s)  # P Hᵀ S⁻¹ (..., 4, 2)
    y = z - x[..., :2]
    x_new = x + np.einsum("...ij,...j->...i", k, y)
    i_kh = np.eye(4) - k @ _H
    p_new = i_kh @ p @ np.swapaxes(i_kh, -1, -2) + k @ r @ np.swapaxes(k, -1, -2)
    return x_new, p_new


def greedy_pairs(cost: FloatArray) -> NDArray[np.intp]:
    """Greedy assignment of each boat's rows to columns by increasing ``cost`` (N, A, B), inf
    where a pair may not be made: (N, A) the column of each row, -1 for none. The cheapest
    remaining pair of every boat at once, its row and column struck out, until none is left
    (at most min(A, B) rounds over all boats)."""
    n, a, b = cost.shape
    work = cost.reshape(n, a * b).copy()
    pair = np.full((n, a), -1, dtype=np.intp)
    rows = np.arange(n)
    for _ in range(min(a, b)):
        best = np.argmin(work, axis=1)
        found = np.isfinite(work[rows, best])
        if not found.any():
            break
        boat, flat = rows[found], best[found]
        i, j = flat // b, flat % b
        pair[boat, i] = j
        grid = work.reshape(n, a, b)
        grid[boat, i, :] = np.inf
        grid[boat, :, j] = np.inf
    return pair


def inv2(s: FloatArray) -> FloatArray:
    """Inverses of 2×2 matrices ``s`` (..., 2, 2), written out (no LAPACK call per matrix)."""
    det = s[..., 0, 0] * s[..., 1, 1] - s[..., 0, 1] * s[..., 1, 0]
    out = np.empty_like(s)
    out[..., 0, 0], out[..., 1, 1] = s[..., 1, 1] / det, s[..., 0, 0] / det
    out[..., 0, 1], out[..., 1, 0] = -s[..., 0, 1] / det, -s[..., 1, 0] / det
    return out


@dataclass(frozen=True)
class TrackTargets:
    """Confirmed tracks of N boats as a target list (arrays (N, M, ...)); ``valid`` (N, M)."""

    valid: NDArray[np.bool_]
    position_ne: FloatArray  # m
    velocity_ne: FloatArray  # m/s over ground
    radius_m: FloatArray  # m
    covariance: FloatArray  # (N, M, 4, 4), [n, e, v_n, v_e]
    track_id: NDArray[np.int64]  # unique per boat over an episode


class RadarTracker:
    """Detections and tracks of N boats' radar frames (module docstring)."""

    def __init__(self, geometry: ImageGeometry, config: TrackerConfig | None = None) -> None:
        self.geometry = geometry
        self.config = config or TrackerConfig()
        self._f, self._q = cv_model(self.config.dt_s, self.config.accel_variance)
        self.reset(0)

    def reset(self, n_boats: int) -> None:
        """Forget every track; ``n_boats`` boats from now on."""
        m = self.config.max_tracks
        self.x = np.zeros((n_boats, m, 4))
        self.p = np.broadcast_to(np.eye(4), (n_boats, m, 4, 4)).copy()
        self.radius = np.zeros((n_boats, m))
        self.status = np.zeros((n_boats, m), dtype=np.int8)
        self.hits = np.zeros((n_boats, m), dtype=np.uint8)  # bit 0: this frame
        self.age = np.zeros((n_boats, m), dtype=np.int64)  # frames since the track started
        self.misses = np.zeros((n_boats, m), dtype=np.int64)  # consecutive
        self.coast = np.zeros((n_boats, m), dtype=np.int64)  # frames out of view, no hit
        self.track_id = np.full((n_boats, m), -1, dtype=np.int64)
        self.origin = np.zeros((n_boats, m, 2))  # m, a track's first detection
        self.origin_cov = np.broadcast_to(np.eye(2), (n_boats, m, 2, 2)).copy()
        self._next_id = np.zeros(n_boats, dtype=np.int64)
        self.frames = np.zeros(n_boats, dtype=np.int64)  # frames since the reset
        self.last_detections: Detections | None = None

    @property
    def n_boats(self) -> int:
        return self.x.shape[0]

    def update(
        self, images: NDArray[np.generic], own_pos_ne: FloatArray, own_psi_rad: FloatArray
    ) -> TrackTargets:
        """One frame of every boat: images (N, 1, rows, cols) and the navigation estimate
        (N, 2) m, (N,) rad; returns :meth:`targets`. ``UserError`` for a wrongly shaped image."""
        det = detect(images, self.geometry, own_pos_ne, own_psi_rad, self.config.detector)
        if det.valid.shape[0] != self.n_boats:
            raise ValueError(f"reset({det.valid.shape[0]}) first: the tracker has {self.n_boats}")
        self.last_detections = det
        active = self.status != _EMPTY
        x, p = kf_predict(self.x, self.p, self._f, self._q)
        self.x = np.where(active[..., None], x, self.x)
        self.p = np.where(active[..., None, None], p, self.p)
        pair = self._associate(det)  # (N, M) detection index or -1
        hit = pair >= 0
        fast = self._static_second_hit(det, pair, hit)
        self._update_tracks(det, pair, hit)
        self._manage(hit, active, fast, own_pos_ne, own_psi_rad)
        self._start_tracks(det, pair)
        self.frames += 1
        return self.targets()

    def _associate(self, det: Detections) -> NDArray[np.intp]:
        """Greedy global-nearest-neighbour pairs (module docstring): (N, M) detection or -1."""
        cfg = self.config
        s = self.p[:, :, None, :2, :2] + det.covariance[:, None]  # (N, M, D, 2, 2)
        y = det.position_ne[:, None] - self.x[:, :, None, :2]
        det_s = s[..., 0, 0] * s[..., 1, 1] - s[..., 0, 1] * s[..., 1, 0]
        # yᵀ S⁻¹ y of a symmetric 2×2 S, written out
        d2 = (
            s[..., 1, 1] * y[..., 0] ** 2
            - 2.0 * s[..., 0, 1] * y[..., 0] * y[..., 1]
            + s[..., 0, 0] * y[..., 1] ** 2
        ) / det_s
        cost = d2 + np.log(det_s)
        cost = cost + np.where(self.status == _TENTATIVE, cfg.tentative_cost, 0.0)[..., None]
        ok = (self.status != _EMPTY)[..., None] & det.valid[:, None, :] & (d2 <= cfg.gate)
        return greedy_pairs(np.where(ok, cost, np.inf))

    def _static_second_hit(
        self, det: Detections, pair: NDArray[np.intp], hit: NDArray[np.bool_]
    ) -> NDArray[np.bool_]:
        """Tentative tracks whose second frame's detection repeats the first one's position
        within ``static_confirm_gate`` (χ² of the difference under both covariances)."""
        gate = self.config.static_confirm_gate
        if gate <= 0:
            return np.zeros_like(hit)
        rows = np.arange(self.n_boats)[:, None]
        j = np.maximum(pair, 0)
        diff = det.position_ne[rows, j] - self.origin
        d2 = np.einsum(
            "...i,...ij,...j->...", diff, inv2(det.covariance[rows, j] + self.origin_cov), diff
        )
        return hit & (self.status == _TENTATIVE) & (self.age == 1) & (d2 <= gate)

    def _update_tracks(
        self, det: Detections, pair: NDArray[np.intp], hit: NDArray[np.bool_]
    ) -> None:
        rows = np.arange(self.n_boats)[:, None]
        j = np.maximum(pair, 0)
        z, r = det.position_ne[rows, j], det.covariance[rows, j]
        x, p = kf_update(self.x, self.p, z, r)
        self.x = np.where(hit[..., None], x, self.x)
        self.p = np.where(hit[..., None, None], p, self.p)
        a = self.config.radius_smoothing
        self.radius = np.where(hit, (1 - a) * self.radius + a * det.radius_m[rows, j], self.radius)

    def _in_view(self, own_pos_ne: FloatArray, own_psi_rad: FloatArray) -> NDArray[np.bool_]:
        """Whether each track's predicted position lies in the radar's view (N, M)."""
        g = self.geometry
        rel = self.x[..., :2] - np.asarray(own_pos_ne, dtype=float)[:, None, :]
        rng = np.hypot(rel[..., 0], rel[..., 1])
        bearing = ssa(np.arctan2(rel[..., 1], rel[..., 0]) - np.asarray(own_psi_rad)[:, None])
        return (rng < g.max_range_m) & (np.abs(bearing) <= g.half_fov_rad)

    def _manage(
        self,
        hit: NDArray[np.bool_],
        active: NDArray[np.bool_],
        fast: NDArray[np.bool_],
        own_pos_ne: FloatArray,
        own_psi_rad: FloatArray,
    ) -> None:
        cfg = self.config
        window = np.uint8((1 << cfg.n_window) - 1)
        self.hits = np.where(active, ((self.hits << 1) | hit) & window, self.hits).astype(np.uint8)
        self.age = np.where(active, self.age + 1, self.age)
        in_view = self._in_view(own_pos_ne, own_psi_rad)
        self.misses = np.where(hit, 0, np.where(active & in_view, self.misses + 1, self.misses))
        self.coast = np.where(hit | ~active, 0, self.coast + (~in_view))
        n_hits = _popcount(self.hits)
        frames = np.minimum(self.age, cfg.n_window)
        tentative = self.status == _TENTATIVE
        confirm = tentative & ((n_hits >= cfg.m_hits) | fast)
        # tentative and young (within their first N frames) tracks that cannot reach M of N
        young = tentative | ((self.status == _CONFIRMED) & (self.age <= cfg.n_window))
        hopeless = young & (n_hits + (cfg.n_window - frames) < cfg.m_hits)
        hopeless |= tentative & (self.age >= cfg.n_window) & ~confirm
        lost = (self.status == _CONFIRMED) & (
            (self.misses >= cfg.max_misses) | (self.coast > cfg.max_coast)
        )
        self.status = np.where(confirm, _CONFIRMED, self.status).astype(np.int8)
        drop = hopeless | lost
        self.status[drop] = _EMPTY
        self.track_id[drop] = -1

    def _start_tracks(self, det: Detections, pair: NDArray[np.intp]) -> None:
        """Tentative tracks from unassociated detections, nearest first, into free slots."""
        cfg = self.config
        n, d = det.valid.shape
        used = np.zeros((n, d), dtype=bool)
        b_idx, t_idx = np.nonzero(pair >= 0)
        used[b_idx, pair[b_idx, t_idx]] = True
        new = det.valid & ~used  # (N, D), nearest first
        free = self.status == _EMPTY  # (N, M)
        new_rank = np.cumsum(new, axis=1) - 1  # k-th new detection of its boat
        n_free = free.sum(axis=1)
        take = new & (new_rank < n_free[:, None])
        b, j = np.nonzero(take)
        k = new_rank[b, j]
        # the k-th free slot of boat b: slots sorted by (not free, position)
        free_order = np.argsort(~free, axis=1, kind="stable")
        t = free_order[b, k]
        self.x[b, t] = 0.0
        self.x[b, t, :2] = det.position_ne[b, j]
        p0 = np.zeros((b.size, 4, 4))
        p0[:, :2, :2] = det.covariance[b, j]
        p0[:, 2, 2] = p0[:, 3, 3] = cfg.init_speed_sigma_mps**2
        self.p[b, t] = p0
        self.radius[b, t] = det.radius_m[b, j]
        self.origin[b, t], self.origin_cov[b, t] = det.position_ne[b, j], det.covariance[b, j]
        near = det.range_m[b, j] < cfg.immediate_range_m
        near |= cfg.confirm_first_frame & (self.frames[b] == 0)
        self.status[b, t] = np.where(near, _CONFIRMED, _TENTATIVE)
        self.hits[b, t] = 1
        self.age[b, t] = 1
        self.misses[b, t] = 0
        self.coast[b, t] = 0
        # ids: each boat counts its tracks
        order_in_boat = np.cumsum(take, axis=1)[b, j] - 1
        self.track_id[b, t] = self._next_id[b] + order_in_boat
        self._next_id += take.sum(axis=1)

    def targets(self) -> TrackTargets:
        """The confirmed tracks (module docstring)."""
        ok = self.status == _CONFIRMED
        return TrackTargets(
            valid=ok,
            position_ne=self.x[..., :2].copy(),
            velocity_ne=self.x[..., 2:].copy(),
            radius_m=self.radius.copy(),
            covariance=self.p.copy(),
            track_id=np.where(ok, self.track_id, -1),
        )


def _popcount(bits: NDArray[np.uint8]) -> NDArray[np.int64]:
    """Number of set bits of each uint8."""
    return np.unpackbits(bits[..., None], axis=-1).sum(axis=-1).astype(np.int64)
