"""Radar detections: connected returns above a threshold in N boats' polar images, in one pass.

The image is the radar stand-in of :mod:`usvsim.task.radar` (rows: range bins of Δr from the
boat, row 0 nearest; columns: bearing bins of Δb from −half_fov to +half_fov, relative to the
heading, clockwise positive). This module needs only its geometry (:class:`ImageGeometry`, which
:class:`usvsim.task.radar.RadarConfig` satisfies), so the navigation block stays below the task.

A *detection* is a connected set of pixels brighter than ``threshold`` (4-connected within one
image; :func:`scipy.ndimage.label` on the stacked images with a structure that joins no two
boats). Per detection, over its pixels' polar cells (cell area ρ Δr Δb at the centre range ρ):

=============  ==============================================================================
quantity       definition
=============  ==============================================================================
centroid       area-weighted mean of the cell centres in the body frame (x ahead, y starboard)
range, bearing of the centroid
radius         ``max(sqrt(A / π) − (Δr + ρ Δb) / 4, r_min)``: A the lit area; a disc's lit cells
               overhang its edge by about half a cell (the rendering lights every cell the disc
               meets), so half of the mean half-cell is taken off (measured on clean frames:
               see ``tests/usvsim/nav/test_tracker.py``)
NED position   the centroid rotated by the estimated heading ψ̂ and added to the estimated
               position p̂ (the navigation estimate, :mod:`usvsim.nav.filter`)
covariance     the cell's quantisation (σ_r = Δr/√12 along the line of sight, σ_c = ρ Δb/√12
               across it), rotated into NED, plus ``(σ_nav² + (k_R R)²) I``: the own position's
               error and, for an extended return, how far its visible centroid may sit from
               the centre
=============  ==============================================================================

Why the threshold of 96: the family's degradation (:mod:`usvsim.task.scene_radar`) keeps a return
at ≥ 255 (1 − s) ≥ 127 (speckle s ≤ 0.5) and the background at ≤ 40 (additive noise a ≤ 40);
96 lies between with a margin on both sides. Clutter pixels are lit at a uniform intensity, so
about 60 % of them pass: the tracker (:mod:`usvsim.nav.tracker`) removes them by M-of-N
confirmation, not the detector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from usvsim.common.errors import UserError

__all__ = ["Detections", "DetectorConfig", "ImageGeometry", "check_images", "detect"]

FloatArray = NDArray[np.float64]

# 4-connectivity inside an image plane (a disc's cells always are: each column's rows are one
# run, nested towards the centre's column), nothing across the stacked boats' axis; diagonal
# neighbours stay apart, so two near returns or a clutter pixel beside one are not joined
_STRUCTURE = np.zeros((3, 3, 3), dtype=bool)
_STRUCTURE[1] = ndimage.generate_binary_structure(2, 1)


class ImageGeometry(Protocol):
    """The polar image's geometry (:class:`usvsim.task.radar.RadarConfig` is one)."""

    @property
    def n_rows(self) -> int: ...  # range bins

    @property
    def n_cols(self) -> int: ...  # bearing bins

    @property
    def max_range_m(self) -> float: ...  # m, outer edge of the last row

    @property
    def half_fov_rad(self) -> float: ...  # rad, the columns span ±half_fov


@dataclass(frozen=True)
class DetectorConfig:
    """Detection parameters (module docstring). usvsim's choices, not fitted to the suite."""

    threshold: int = 96  # intensity 0-255: between the noise floor (≤ 40) and a return (≥ 127)
    max_detections: int = 48  # per boat and frame, the nearest kept (clutter ~6 per frame)
    min_radius_m: float = 0.5  # m, floor of the radius estimate
    nav_sigma_m: float = 1.5  # m, own position error added to every detection (GNSS ~1-3 m)
    extent_sigma_factor: float = 0.25  # -, k_R: centroid spread of an extended return per m of R

    def __post_init__(self) -> None:
        if not 0 <= self.threshold < 255 or self.max_detections < 1:
            raise ValueError("DetectorConfig needs 0 <= threshold < 255 and max_detections >= 1")


@dataclass(frozen=True)
class Detections:
    """The detections of N boats in one frame, padded to D per boat (arrays (N, D, ...)).

    ``valid`` (N, D) marks real ones, nearest first; ``range_m``, ``bearing_rad`` (relative to the
    heading), ``radius_m``; ``position_ne`` (N, D, 2) m and ``covariance`` (N, D, 2, 2) m² in NED.
    """

    valid: NDArray[np.bool_]
    range_m: FloatArray
    bearing_rad: FloatArray
    radius_m: FloatArray
    position_ne: FloatArray
    covariance: FloatArray


def _cell_geometry(geometry: ImageGeometry) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cell-centre range (rows,) m, bearing (cols,) rad and area (rows, 1) m² of the image."""
    dr = geometry.max_range_m / geometry.n_rows
    db = 2.0 * geometry.half_fov_rad / geometry.n_cols
    rho = np.asarray((np.arange(geometry.n_rows) + 0.5) * dr, dtype=np.float64)
    bearing = np.asarray(
        -geometry.half_fov_rad + (np.arange(geometry.n_cols) + 0.5) * db, dtype=np.float64
    )
    return rho, bearing, (rho * dr * db)[:, None]


def check_images(images: NDArray[np.generic], geometry: ImageGeometry) -> NDArray[np.generic]:
    """``images`` as (N, rows, cols); :class:`UserError` (one line) if the shape is not
    (N, 1, rows, cols) or (N, rows, cols) of ``geometry``."""
    arr = np.asarray(images)
    want = (geometry.n_rows, geometry.n_cols)
    if arr.ndim == 4 and arr.shape[1] == 1 and arr.shape[2:] == want:
        return arr[:, 0]
    if arr.ndim == 3 and arr.shape[1:] == want:
        return arr
    raise UserError(
        f"radar image of shape {arr.shape}: the tracker needs (N, 1, {want[0]}, {want[1]}) or "
        f"(N, {want[0]}, {want[1]}) (N boats; {want[0]} range rows × {want[1]} bearing columns)"
    )


def detect(
    images: NDArray[np.generic],
    geometry: ImageGeometry,
    own_pos_ne: FloatArray,
    own_psi_rad: FloatArray,
    cfg: DetectorConfig | None = None,
) -> Detections:
    """Detections (module docstring) in N boats' images (N, 1, rows, cols), placed in NED from
    the navigation estimate ``own_pos_ne`` (N, 2) m, ``own_psi_rad`` (N,) rad.

    Raises
    ------
    UserError
        If the images do not have the geometry's shape.
    """
    cfg = cfg or DetectorConfig()
    img: NDArray[Any] = check_images(images, geometry)
    n = img.shape[0]
    lit = img > cfg.threshold
    labels, count = ndimage.label(lit, structure=_STRUCTURE)
    rho_c, bear_c, area_c = _cell_geometry(geometry)
    boat_idx, row_idx, col_idx = np.nonzero(labels)
    lab = labels[boat_idx, row_idx, col_idx] - 1  # 0 .. count-1
    area = area_c[row_idx, 0]
    x = rho_c[row_idx] * np.cos(bear_c[col_idx])
    y = rho_c[row_idx] * np.sin(bear_c[col_idx])
    a_sum = np.bincount(lab, area, count)
    cx = np.bincount(lab, area * x, count) / np.maximum(a_sum, 1e-12)
    cy = np.bincount(lab, area * y, count) / np.maximum(a_sum, 1e-12)
    boat = np.zeros(count, dtype=np.intp)
    boat[lab] = boat_idx
    rng = np.hypot(cx, cy)
    bearing = np.arctan2(cy, cx)
    dr = geometry.max_range_m / geometry.n_rows
    db = 2.0 * geometry.half_fov_rad / geometry.n_cols
    radius = np.maximum(np.sqrt(a_sum / math.pi) - (dr + rng * db) / 4.0, cfg.min_radius_m)
    # per boat, nearest first, at most D: rank of each detection within its boat
    order = np.lexsort((rng, boat))
    boat_s = boat[order]
    first = np.searchsorted(boat_s, np.arange(n))
    rank = np.arange(count) - first[boat_s]
    keep = rank < cfg.max_detections
    d = int(min(cfg.max_detections, max(int(rank.max(initial=-1)) + 1, 1)))
    slot_boat, slot = boat_s[keep], rank[keep]
    src = order[keep]
    valid = np.zeros((n, d), dtype=bool)
    valid[slot_boat, slot] = True

    def padded(values: FloatArray) -> FloatArray:
        out = np.zeros((n, d), dtype=float)
        out[slot_boat, slot] = values[src]
        return out

    r_m, b_rad, rad_m = padded(rng), padded(bearing), padded(radius)
    psi = np.asarray(own_psi_rad, dtype=float)[:, None]
    course = psi + b_rad  # NED direction of the line of sight
    los = np.stack([np.cos(course), np.sin(course)], axis=-1)  # (N, D, 2)
    pos = np.asarray(own_pos_ne, dtype=float)[:, None, :] + r_m[..., None] * los
    across = np.stack([-los[..., 1], los[..., 0]], axis=-1)
    var_r = dr**2 / 12.0
    var_c = (np.maximum(r_m, dr) * db) ** 2 / 12.0
    iso = cfg.nav_sigma_m**2 + (cfg.extent_sigma_factor * rad_m) ** 2
    cov = (
        var_r * los[..., :, None] * los[..., None, :]
        + var_c[..., None, None] * across[..., :, None] * across[..., None, :]
        + iso[..., None, None] * np.eye(2)
    )
    cov[~valid] = np.eye(2)
    return Detections(valid, r_m, b_rad, rad_m, pos, cov)
