"""Radar images of a whole scene on tensors: the twin of ``scene_radar.render_scene``.

Every disc at its true extent (a disc no larger than the study's 1 m pole as its polar box), the
per-boat degradation (missed returns, clutter, speckle, additive noise) drawn from the same
counter-based SplitMix64 draws of each boat's frame key (Steele, Lea & Flood 2014), so an image
equals the CPU one pixel for pixel (tested in ``tests/usvsim/task/test_torch_openwater.py``).
No loop over boats, discs or pixels: a disc's rows in each column are marked in a difference
array (+1 at its first row, −1 past its last) summed along range, as the NumPy path does.

The 64-bit arithmetic runs on int64 tensors: additions and products wrap modulo 2⁶⁴ as uint64's
do (two's complement), and a right shift is made logical by masking the sign's copies.
"""

from __future__ import annotations

import math

import numpy as np
import torch

from usvsim.nav.torch_nav import torch_ssa
from usvsim.task.radar import RadarConfig

__all__ = ["SceneRadarGrid", "frame_draws_torch", "mix64_torch", "render_scene_torch", "to_int64"]


def to_int64(value: int) -> int:
    """The int64 with the same 64 bits as the unsigned ``value`` (0 <= value < 2⁶⁴)."""
    return value - (1 << 64) if value >= 1 << 63 else value


GOLDEN = to_int64(0x9E3779B97F4A7C15)  # SplitMix64's increment (usvsim.task.scene_radar.GOLDEN)
_M1, _M2 = to_int64(0xBF58476D1CE4E5B9), to_int64(0x94D049BB133111EB)
FRAME_DRAWS = 1 << 22  # usvsim.task.scene_radar.FRAME_DRAWS (draws reserved per frame)


def _shr(z: torch.Tensor, s: int) -> torch.Tensor:
    """Logical right shift of int64 bits by ``s`` (0 < s < 64)."""
    return (z >> s) & ((1 << (64 - s)) - 1)


def mix64_torch(z: torch.Tensor) -> torch.Tensor:
    """:func:`usvsim.task.scene_radar.mix64` on int64 tensors (the same 64 bits)."""
    z = (z ^ _shr(z, 30)) * _M1
    z = (z ^ _shr(z, 27)) * _M2
    return z ^ _shr(z, 31)


def frame_draws_torch(keys: torch.Tensor, start: int, count: int) -> torch.Tensor:
    """Draws ``start .. start + count − 1`` of each frame key (N,) int64: (N, count) int64
    (:func:`usvsim.task.scene_radar.frame_draws`)."""
    i = torch.arange(start + 1, start + count + 1, dtype=torch.int64, device=keys.device)
    return mix64_torch(keys[:, None] + GOLDEN * i[None, :])


class SceneRadarGrid:
    """The image's column edges and sizes on the device, built once."""

    def __init__(self, cfg: RadarConfig, dtype: torch.dtype, device: torch.device) -> None:
        edges = cfg.bearing_edges_rad
        b_hi = edges[1:].copy()
        b_hi[-1] = np.nextafter(b_hi[-1], np.inf)  # the last column includes +half_fov
        self.b_lo = torch.as_tensor(edges[:-1], dtype=dtype, device=device)
        self.b_hi = torch.as_tensor(b_hi, dtype=dtype, device=device)
        self.b_edge_hi = torch.as_tensor(edges[1:], dtype=dtype, device=device)
        self.rows, self.cols = cfg.n_rows, cfg.n_cols
        self.dr = cfg.max_range_m / cfg.n_rows


def _lit(
    rho: torch.Tensor,
    phi: torch.Tensor,
    r: torch.Tensor,
    valid: torch.Tensor,
    g: SceneRadarGrid,
    box_radius_m: float,
) -> torch.Tensor:
    """Lit pixels (N, rows, cols) bool of the valid discs (``scene_radar._lit_pixels``)."""
    n = rho.shape[0]
    inside, box = rho < r, r <= box_radius_m
    half = torch.asin(torch.clamp(r / torch.clamp(rho, min=1e-12), max=1.0))
    half = torch.where(inside & ~box, math.pi, half)
    lo_b, hi_b = (phi - half)[..., None], (phi + half)[..., None]
    cols = (g.b_hi > lo_b) & (g.b_lo <= hi_b)  # (N, J, cols)
    for shift in (-2.0 * math.pi, 2.0 * math.pi):  # a disc whose bearing span wraps past ±π
        cols |= (g.b_hi > lo_b + shift) & (g.b_lo <= hi_b + shift)
    rho_c, phi_c, r_c = rho[..., None], phi[..., None], r[..., None]
    delta = torch_ssa(torch.clamp(phi_c, g.b_lo, g.b_edge_hi) - phi_c)
    along, across = rho_c * torch.cos(delta), rho_c * torch.sin(delta)
    chord = torch.sqrt(torch.clamp(r_c**2 - across**2, min=0.0))
    near = torch.where(inside[..., None], 0.0, along - chord)
    far = along + chord
    in_box = box[..., None]
    near, far = torch.where(in_box, rho_c - r_c, near), torch.where(in_box, rho_c + r_c, far)
    k_lo = torch.floor(torch.clamp(near, min=0.0) / g.dr)
    k_hi = torch.clamp(torch.floor(far / g.dr), max=g.rows - 1)
    keep = cols & valid[..., None] & (k_lo <= k_hi) & (k_lo < g.rows) & (far >= 0)
    lo = torch.where(keep, k_lo, 0.0).to(torch.int64)
    hi = torch.where(keep, k_hi + 1, 0.0).to(torch.int64)
    stride = (g.rows + 1) * g.cols
    base = torch.arange(n, device=rho.device)[:, None, None] * stride + torch.arange(
        g.cols, device=rho.device
    )
    mark = keep.to(torch.int32)
    diff = torch.zeros(n * stride, dtype=torch.int32, device=rho.device)
    diff.index_add_(0, (base + lo * g.cols).reshape(-1), mark.reshape(-1))
    diff.index_add_(0, (base + hi * g.cols).reshape(-1), -mark.reshape(-1))
    depth = torch.cumsum(diff.view(n, g.rows + 1, g.cols), dim=1)
    return depth[:, : g.rows] > 0


def render_scene_torch(
    range_m: torch.Tensor,
    bearing_rad: torch.Tensor,
    radius_m: torch.Tensor,
    valid: torch.Tensor,
    grid: SceneRadarGrid,
    degradation: torch.Tensor | None = None,
    keys: torch.Tensor | None = None,
    box_radius_m: float = 1.0,
) -> torch.Tensor:
    """Radar images (N, 1, rows, cols) uint8 of N boats, each seeing J discs (``range_m``,
    ``bearing_rad`` relative to the heading, ``radius_m``, ``valid``: (N, J)).

    ``degradation`` (N, 4) float64 [p_clutter, speckle, p_missed, noise amplitude] and ``keys``
    (N,) int64 (each boat's frame key, the bits of :meth:`usvsim.task.scene_radar.RadarStreams.
    frame_keys`): with them, each boat's image is degraded as :func:`render_scene` degrades it
    (a boat with all four zero is left clean); without, every image is clean. A disc's missed
    return is decided by the frame draw of its place among the boat's valid discs, as
    ``render_scene`` numbers them: padding slots take no draw."""
    g = grid
    phi = torch_ssa(bearing_rad)
    n, j = range_m.shape
    pixels = g.rows * g.cols
    if degradation is not None and keys is not None:
        degraded = (degradation > 0).any(dim=1)
        rank = torch.clamp(torch.cumsum(valid.to(torch.int64), dim=1) - 1, min=0)
        draws = frame_draws_torch(keys, pixels, j).gather(1, rank)
        u_miss = _shr(draws, 40).to(torch.float64) * 2.0**-24
        p_miss = torch.where(degraded, degradation[:, 2].to(torch.float64), 0.0)
        valid = valid & (u_miss >= p_miss[:, None])
    lit = _lit(range_m, phi, radius_m, valid, g, box_radius_m)
    clean = lit.to(torch.uint8) * 255
    if degradation is None or keys is None:
        return clean[:, None]
    h = frame_draws_torch(keys, 0, pixels)  # (N, P)
    level = lit.reshape(n, -1).to(torch.float32) * 255.0

    def bits(shift: int, width: int) -> torch.Tensor:
        return (_shr(h, shift) & ((1 << width) - 1)).to(torch.float32) * 2.0**-width

    q = degradation
    speckle = q[:, 1].to(torch.float32)[:, None]
    level = torch.where(speckle > 0, level * (1.0 - speckle * bits(50, 14)), level)
    trial = (h & 0xFFFFF).to(torch.float64) * 2.0**-20
    clutter = trial < q[:, 0].to(torch.float64)[:, None]
    level = torch.where(clutter, torch.maximum(level, 255.0 * bits(36, 14)), level)
    noise = q[:, 3].to(torch.float32)[:, None]
    level = torch.where(noise > 0, level + noise * bits(20, 16), level)
    image = torch.clamp(level, 0.0, 255.0).to(torch.uint8).view(n, g.rows, g.cols)
    return torch.where(degraded[:, None, None], image, clean)[:, None]
