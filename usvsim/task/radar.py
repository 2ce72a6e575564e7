"""Radar stand-in: a polar image of the obstacles around the boat, rendered for N boats at once.

The study's image (Vedeler 2019; ``shared/reference/table-4-1.md``): 50 rows × 119 columns, range
0-200 m along the rows (4 m per row), bearing -120°…+120° along the columns (240°/119 ≈ 2.02°
per column), black background, the pole drawn as a white box at its relative range and bearing.

Pixel layout (channel-first, ``(1, 50, 119)`` uint8, 0 = black, 255 = white):

=====  ==============================================================================
axis   pixel k covers
=====  ==============================================================================
row    range ``[k Δr, (k+1) Δr)``, ``Δr = 200/50 = 4 m``; row 0 is nearest the boat
col    bearing ``[-120° + k Δb, -120° + (k+1) Δb)``, ``Δb = 240°/119``; column 0 is the
       port edge (-120°), column 118 the starboard edge (+120°, included)
=====  ==============================================================================

Bearings are relative to the boat's (estimated) heading, clockwise positive (starboard), wrapped
by :func:`usvsim.common.angles.ssa`.

The pole's box is its polar bounding box: range ``[ρ - R, ρ + R]`` and bearing
``[φ - asin(R/ρ), φ + asin(R/ρ)]`` for a pole of radius R at range ρ and bearing φ. Every pixel
that box touches is white, so a pole smaller than a pixel (1 m against 4 m × ~3.5 m at 100 m)
still lights at least one pixel, and a near pole lights several columns. Parts outside the field
of view or beyond 200 m are not drawn.

Optional clutter (off by default): each pixel independently lit with probability
``clutter_probability`` at a uniform random intensity; and additive uniform intensity noise up to
``noise_amplitude``. Both draw from the per-boat noise streams.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from usvsim.common.angles import ssa

__all__ = ["RadarConfig", "UniformSource", "pixel_index", "render_radar"]


@dataclass(frozen=True)
class RadarConfig:
    """Geometry and (optional) clutter of the radar image; the study's geometry by default."""

    n_rows: int = 50  # range bins; study
    n_cols: int = 119  # bearing bins; study
    max_range_m: float = 200.0  # m; study
    half_fov_rad: float = math.radians(120.0)  # rad, ± field of view; study
    clutter_probability: float = 0.0  # per pixel and frame; usvsim extension, off by default
    noise_amplitude: float = 0.0  # intensity units (0-255), uniform additive; off by default

    def __post_init__(self) -> None:
        if self.n_rows < 1 or self.n_cols < 1:
            raise ValueError("RadarConfig needs at least one row and one column")
        if not (self.max_range_m > 0 and 0 < self.half_fov_rad <= math.pi):
            raise ValueError("RadarConfig needs max_range_m > 0 and half_fov_rad in (0, π]")
        if not 0.0 <= self.clutter_probability <= 1.0:
            raise ValueError(
                f"clutter_probability must be in [0, 1], got {self.clutter_probability}"
            )
        if not 0.0 <= self.noise_amplitude <= 255.0:
            raise ValueError(f"noise_amplitude must be in [0, 255], got {self.noise_amplitude}")

    @property
    def shape(self) -> tuple[int, int, int]:
        """Image shape, channel first: ``(1, n_rows, n_cols)``."""
        return (1, self.n_rows, self.n_cols)

    @property
    def range_edges_m(self) -> NDArray[np.float64]:
        """Row edges (n_rows + 1,) in m."""
        return np.linspace(0.0, self.max_range_m, self.n_rows + 1)

    @property
    def bearing_edges_rad(self) -> NDArray[np.float64]:
        """Column edges (n_cols + 1,) in rad."""
        return np.linspace(-self.half_fov_rad, self.half_fov_rad, self.n_cols + 1)


class UniformSource(Protocol):
    """Anything with ``random(size)`` -> uniform [0, 1) of that shape (boats first)."""

    def random(self, size: tuple[int, ...]) -> NDArray[np.float64]: ...


def pixel_index(
    range_m: ArrayLike, bearing_rad: ArrayLike, cfg: RadarConfig | None = None
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Row and column of the pixel holding the point at (range, bearing); -1 where not visible.

    >>> pixel_index(10.0, 0.0)
    (array(2), array(59))
    """
    cfg = cfg or RadarConfig()
    r = np.asarray(range_m, dtype=float)
    b = ssa(bearing_rad)
    row = np.floor(r / (cfg.max_range_m / cfg.n_rows)).astype(np.intp)
    col_width = 2.0 * cfg.half_fov_rad / cfg.n_cols
    col = np.minimum(np.floor((b + cfg.half_fov_rad) / col_width), cfg.n_cols - 1).astype(np.intp)
    visible = (r >= 0) & (row < cfg.n_rows) & (np.abs(b) <= cfg.half_fov_rad)
    return np.where(visible, row, -1), np.where(visible, col, -1)


def render_radar(
    range_m: ArrayLike,
    bearing_rad: ArrayLike,
    radius_m: float,
    cfg: RadarConfig | None = None,
    noise: UniformSource | None = None,
    out: NDArray[np.uint8] | None = None,
) -> NDArray[np.uint8]:
    """Radar images of N boats, each seeing K round obstacles.

    Parameters
    ----------
    range_m, bearing_rad : array, shape (N,) or (N, K)
        Relative range (m) and bearing (rad, relative to heading) of each obstacle's centre.
    radius_m : float
        Obstacle radius (m).
    cfg : RadarConfig, optional
    noise : UniformSource, optional
        Needed only when the config enables clutter or noise.
    out : uint8 array (N, 1, n_rows, n_cols), optional
        Written in place and returned.

    Returns
    -------
    uint8 array, shape (N, 1, n_rows, n_cols)
    """
    cfg = cfg or RadarConfig()
    rho = np.asarray(range_m, dtype=float)
    phi = ssa(bearing_rad)
    if rho.ndim == 1:
        rho, phi = rho[:, None], phi[:, None]
    n = rho.shape[0]
    # rows: [k Δr, (k+1) Δr) meets [ρ - R, ρ + R]
    r_edges = cfg.range_edges_m
    lo_r, hi_r = (rho - radius_m)[..., None], (rho + radius_m)[..., None]
    rows = (r_edges[1:] > lo_r) & (r_edges[:-1] <= hi_r)  # (N, K, rows)
    # columns: angular half-width of the disc; the last column includes +half_fov
    half = np.arcsin(np.minimum(radius_m / np.maximum(rho, 1e-12), 1.0))
    b_edges = cfg.bearing_edges_rad
    b_hi = b_edges[1:].copy()
    b_hi[-1] = np.nextafter(b_hi[-1], np.inf)
    lo_b, hi_b = (phi - half)[..., None], (phi + half)[..., None]
    cols = (b_hi > lo_b) & (b_edges[:-1] <= hi_b)
    if np.any(half > 0.5 * (math.pi - cfg.half_fov_rad)):  # a box wide enough to wrap past ±π
        for shift in (-2.0 * math.pi, 2.0 * math.pi):
            cols |= (b_hi > lo_b + shift) & (b_edges[:-1] <= hi_b + shift)
    if out is None:
        out = np.empty((n, *cfg.shape), dtype=np.uint8)
    img = out[:, 0]
    if rows.shape[1] == 1:  # one obstacle: one fused outer product, 255 × {0, 1}
        np.multiply(rows[:, 0, :, None].view(np.uint8), cols[:, 0, None, :].view(np.uint8), out=img)
        img *= 255
    else:
        lit = np.any(rows[..., :, None] & cols[..., None, :], axis=1)
        img[...] = lit.view(np.uint8) * np.uint8(255)
    if cfg.clutter_probability > 0 or cfg.noise_amplitude > 0:
        if noise is None:
            raise ValueError("radar clutter/noise is enabled: pass a noise source")
        _add_clutter(img, cfg, noise)
    return out


def _add_clutter(img: NDArray[np.uint8], cfg: RadarConfig, noise: UniformSource) -> None:
    """Clutter (random lit pixels) and additive uniform noise, in place (see module docstring)."""
    u = noise.random((img.shape[0], 2, *img.shape[1:]))
    level = img.astype(float)
    if cfg.clutter_probability > 0:
        clutter = u[:, 0] < cfg.clutter_probability
        # reuse the draw: given clutter, u / p is uniform [0, 1), an intensity
        level = np.where(
            clutter, np.maximum(level, 255.0 * u[:, 0] / cfg.clutter_probability), level
        )
    if cfg.noise_amplitude > 0:
        level = level + cfg.noise_amplitude * u[:, 1]
    img[...] = np.clip(level, 0.0, 255.0).astype(np.uint8)
