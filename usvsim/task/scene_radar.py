"""Radar images of a whole scene: every disc (pole, islet, vessel) at its true extent, N boats.

The image geometry is the study's (:class:`usvsim.task.radar.RadarConfig`: 50 range rows of 4 m,
119 bearing columns over ±120°). :func:`usvsim.task.radar.render_radar` (the pole task's image,
unchanged) lights a disc's polar bounding box; here a pixel is lit where its polar cell meets the
disc itself, so an islet near the boat has its true, curved outline.

Discs no larger than the study's pole (1 m) are drawn as the study draws it, as their polar
bounding box, so a study episode gives the pole task's image pixel for pixel; larger ones:

Exact extent of a disc (centre at range ρ, bearing φ, radius R) in one column, bearings
[b0, b1): a ray at bearing θ, Δ = θ − φ, crosses the disc over ranges
``ρ cos Δ ∓ sqrt(R² − ρ² sin² Δ)`` (where ``ρ |sin Δ| ≤ R``); both ends move away from each other
as |Δ| shrinks, so the union over the column's rays is the interval at the column's bearing
closest to φ, Δ* = clamp(φ, b0, b1) − φ. Inside the disc (ρ < R) the interval starts at 0. The
column set itself is the bounding-box one (half-width asin(R/ρ), exact for a disc).

Per-boat degradation (:class:`usvsim.task.openwater.RadarQuality` as arrays, each (N,)):
missed returns (each disc's return missing in a frame with probability p_miss), clutter (a pixel
lit at a uniform random intensity with probability p_clutter), speckle (a lit pixel's intensity
times U[1 − s, 1]) and uniform additive noise. Draws come from each boat's own stream, a fixed
number per frame (:data:`MAX_DISCS` for the misses), so a boat's image does not depend on its
neighbours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.radar import RadarConfig, UniformSource

__all__ = ["MAX_DISCS", "RadarDegradation", "render_scene"]

FloatArray = NDArray[np.float64]
MAX_DISCS = 32  # discs a scene may hold (missed-return draws per frame)


@dataclass(frozen=True)
class RadarDegradation:
    """Per-boat radar degradation, each (N,) (module docstring)."""

    clutter_probability: FloatArray
    speckle: FloatArray
    missed_probability: FloatArray
    noise_amplitude: FloatArray

    @property
    def degraded(self) -> NDArray[np.bool_]:
        """Boats whose image needs random draws."""
        return (
            (self.clutter_probability > 0)
            | (self.speckle > 0)
            | (self.missed_probability > 0)
            | (self.noise_amplitude > 0)
        )


def render_scene(
    range_m: FloatArray,
    bearing_rad: FloatArray,
    radius_m: FloatArray,
    valid: NDArray[np.bool_],
    cfg: RadarConfig | None = None,
    degradation: RadarDegradation | None = None,
    noise: UniformSource | None = None,
    box_radius_m: float = 1.0,
) -> NDArray[np.uint8]:
    """Radar images (N, 1, rows, cols) uint8 of N boats, each seeing J discs.

    ``range_m``, ``bearing_rad`` (relative to heading), ``radius_m``, ``valid`` all (N, J);
    J ≤ :data:`MAX_DISCS`. ``noise`` serves the degraded boats' draws (``for_boats`` protocol of
    :class:`usvsim.task.scenario.BoatNoise`) and is needed only when some boat is degraded.
    Discs no larger than ``box_radius_m`` (the study's 1 m pole) are drawn as the study draws its
    pole, as their polar box (:func:`usvsim.task.radar.render_radar`, the same pixels).
    """
    cfg = cfg or RadarConfig()
    rho = np.asarray(range_m, dtype=float)
    n, j = rho.shape
    if j > MAX_DISCS:
        raise ValueError(f"a scene holds at most {MAX_DISCS} discs, got {j}")
    valid = np.asarray(valid, dtype=bool).copy()
    u_pix = None
    if degradation is not None and degradation.degraded.any():
        if noise is None:
            raise ValueError("radar degradation is enabled: pass a noise source")
        boats = np.flatnonzero(degradation.degraded)
        draws = noise.for_boats(boats).random((boats.size, MAX_DISCS + 3 * cfg.n_rows * cfg.n_cols))  # type: ignore[attr-defined]
        noise.for_boats(None)  # type: ignore[attr-defined]
        u_miss = np.ones((n, MAX_DISCS))
        u_miss[boats] = draws[:, :MAX_DISCS]
        valid &= u_miss[:, :j] >= degradation.missed_probability[:, None]
        u_pix = np.zeros((n, 3, cfg.n_rows, cfg.n_cols))
        u_pix[boats] = draws[:, MAX_DISCS:].reshape(boats.size, 3, cfg.n_rows, cfg.n_cols)
    phi = ssa(np.asarray(bearing_rad, dtype=float))
    r = np.asarray(radius_m, dtype=float)
    b_edges = cfg.bearing_edges_rad
    b_lo, b_hi = b_edges[:-1], b_edges[1:].copy()
    b_hi[-1] = np.nextafter(b_hi[-1], np.inf)
    inside = rho < r
    box = r <= box_radius_m  # the study's pole: its polar box
    half = np.arcsin(np.minimum(r / np.maximum(rho, 1e-12), 1.0))
    half = np.where(inside & ~box, math.pi, half)
    lo_b, hi_b = (phi - half)[..., None], (phi + half)[..., None]
    cols = (b_hi > lo_b) & (b_lo <= hi_b)  # (N, J, cols)
    for shift in (-2.0 * math.pi, 2.0 * math.pi):  # a disc whose bearing span wraps past ±π
        cols |= (b_hi > lo_b + shift) & (b_lo <= hi_b + shift)
    # range interval of each lit (boat, disc, column) at the column bearing nearest the centre's
    boat, disc, col = np.nonzero(cols & valid[..., None])
    rho_c, phi_c, r_c = rho[boat, disc], phi[boat, disc], r[boat, disc]
    delta = ssa(np.clip(phi_c, b_lo[col], b_edges[1:][col]) - phi_c)
    along, across = rho_c * np.cos(delta), rho_c * np.sin(delta)
    chord = np.sqrt(np.maximum(r_c**2 - across**2, 0.0))
    near = np.where(inside[boat, disc], 0.0, along - chord)
    far = along + chord
    in_box = box[boat, disc]
    near, far = np.where(in_box, rho_c - r_c, near), np.where(in_box, rho_c + r_c, far)
    # rows k_lo..k_hi marked +1 / -1 in a difference array laid out (boat, column, range) and
    # summed along range: no (N, J, rows, cols) array
    dr = cfg.max_range_m / cfg.n_rows
    k_lo = np.floor(np.maximum(near, 0.0) / dr)
    k_hi = np.minimum(np.floor(far / dr), cfg.n_rows - 1)
    keep = (k_lo <= k_hi) & (k_lo < cfg.n_rows) & (far >= 0)
    stride = cfg.n_rows + 1
    base = (boat[keep] * cfg.n_cols + col[keep]) * stride
    diff = np.zeros(n * cfg.n_cols * stride, dtype=np.int16)  # J <= 32 discs: no overflow
    np.add.at(diff, base + k_lo[keep].astype(np.intp), 1)
    np.add.at(diff, base + k_hi[keep].astype(np.intp) + 1, -1)
    depth = np.cumsum(diff.reshape(n, cfg.n_cols, stride), axis=2, dtype=np.int16)
    lit = (depth[:, :, : cfg.n_rows] > 0).transpose(0, 2, 1)  # (N, rows, cols)
    out = np.empty((n, *cfg.shape), dtype=np.uint8)
    if u_pix is None or degradation is None:
        np.multiply(lit.view(np.uint8), np.uint8(255), out=out[:, 0])
        return out
    level = lit.astype(np.float64) * 255.0
    level *= 1.0 - degradation.speckle[:, None, None] * u_pix[:, 2]
    p = degradation.clutter_probability[:, None, None]
    clutter = u_pix[:, 0] < p
    level = np.where(clutter, np.maximum(level, 255.0 * u_pix[:, 0] / np.maximum(p, 1e-12)), level)
    level += degradation.noise_amplitude[:, None, None] * u_pix[:, 1]
    out[:, 0] = np.clip(level, 0.0, 255.0).astype(np.uint8)
    return out
