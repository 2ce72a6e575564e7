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
times U[1 − s, 1]) and uniform additive noise (+ a · U[0, 1) on every pixel), applied in that
order and clipped to 0..255 (truncated to an integer).

Random draws are counter-based: draw i of a boat's frame is ``mix64(key + G (i + 1))``, the
SplitMix64 sequence (Steele, Lea & Flood 2014, G = 0x9E3779B97F4A7C15) started at the frame's
key, so a boat's image depends on its own key only (a batch of N boats equals N single boats),
and every pixel's draws are computed independently of the others (vectorised, in C or NumPy).
:class:`RadarStreams` gives frame f of a boat seeded with s the key ``mix64(s) + G f 2²²``: the
frames tile one SplitMix64 sequence per boat without overlap. Draws ``0 .. P − 1`` are the P
pixels', one 64-bit number each, split into independent uniforms: bits 0–19 the clutter trial
(clutter where ``u < p_clutter``; p is thus rounded up to a multiple of 2⁻²⁰), bits 20–35 the
noise value (16 bits), 36–49 the clutter intensity and 50–63 the speckle factor (14 bits each;
the image keeps 8). Draw ``P + m`` (top 24 bits) decides the missed return of the boat's m-th
valid disc, its valid discs counted in order from 0: a slot that is not valid (padding) takes no
draw, so a boat's image does not depend on how its discs are padded, e.g. to the widest scene of
the boats batched with it.

:func:`render_scene` runs the compiled kernel (:mod:`usvsim.task.scene_radar_kernel`, the same
arithmetic in C, OpenMP over boats) where it builds, else this module's NumPy path.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.radar import RadarConfig
from usvsim.task.scene_radar_kernel import load_kernel

__all__ = [
    "FRAME_DRAWS",
    "GOLDEN",
    "MAX_DISCS",
    "RadarDegradation",
    "RadarStreams",
    "frame_draws",
    "mix64",
    "render_scene",
    "stream_keys",
]

FloatArray = NDArray[np.float64]
MAX_DISCS = 32  # valid discs a boat may see (missed-return draws per frame)
GOLDEN = np.uint64(0x9E3779B97F4A7C15)  # SplitMix64's increment
FRAME_DRAWS = 1 << 22  # draws reserved per frame: pixels + MAX_DISCS must fit


def mix64(z: NDArray[np.uint64]) -> NDArray[np.uint64]:
    """SplitMix64's output function of each uint64 (Steele, Lea & Flood 2014; wraps mod 2⁶⁴)."""
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def frame_draws(keys: NDArray[np.uint64], start: int, count: int) -> NDArray[np.uint64]:
    """Draws ``start .. start + count − 1`` of each frame key (N,): (N, count) uint64."""
    i = np.arange(start + 1, start + count + 1, dtype=np.uint64)
    return mix64(np.asarray(keys, dtype=np.uint64)[:, None] + GOLDEN * i[None, :])


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


def stream_keys(seeds: Sequence[int], frames: NDArray[np.integer]) -> NDArray[np.uint64]:
    """The frame keys ``mix64(seed) + G frame 2²²`` (module docstring) of streams seeded with
    ``seeds`` (0 <= seed < 2⁶⁴) at ``frames`` (same length): what :class:`RadarStreams` gives a
    boat seeded with ``seed`` at its frame ``frame``."""
    base = mix64(np.array([int(x) for x in seeds], dtype=np.uint64))
    return base + GOLDEN * (np.asarray(frames, dtype=np.uint64) * np.uint64(FRAME_DRAWS))


class RadarStreams:
    """The radar frame keys of N boats: boat i, seeded with s, frame f has the key
    ``mix64(s) + G f 2²²`` (module docstring); each :meth:`frame_keys` call is the next frame."""

    def __init__(self, n_boats: int) -> None:
        self._base = np.zeros(n_boats, dtype=np.uint64)
        self._frame = np.zeros(n_boats, dtype=np.uint64)

    def seed(self, boats: Sequence[int], seeds: Sequence[int]) -> None:
        """Restart the streams of ``boats`` from ``seeds`` (one per boat, 0 <= seed < 2⁶⁴)."""
        idx = np.asarray(boats, dtype=np.intp)
        self._base[idx] = mix64(np.array([int(x) for x in seeds], dtype=np.uint64))
        self._frame[idx] = 0

    def frame_keys(self, boats: NDArray[np.intp] | slice) -> NDArray[np.uint64]:
        """The next frame's keys of ``boats`` (in that order); their frame counters advance."""
        keys = self._base[boats] + GOLDEN * (self._frame[boats] * np.uint64(FRAME_DRAWS))
        self._frame[boats] += np.uint64(1)
        return keys


Backend = Literal["auto", "compiled", "numpy"]


@dataclass(frozen=True)
class _PolarDiscs:
    """N boats' J discs in polar form, each (N, J): range, bearing (wrapped), radius, half the
    bearing span (rad; π for a boat inside a disc larger than a pole) and flags."""

    rho: FloatArray
    phi: FloatArray
    r: FloatArray
    half: FloatArray
    valid: NDArray[np.bool_]
    inside: NDArray[np.bool_]
    box: NDArray[np.bool_]


def render_scene(
    range_m: FloatArray,
    bearing_rad: FloatArray,
    radius_m: FloatArray,
    valid: NDArray[np.bool_],
    cfg: RadarConfig | None = None,
    degradation: RadarDegradation | None = None,
    keys: NDArray[np.uint64] | None = None,
    box_radius_m: float = 1.0,
    backend: Backend = "auto",
) -> NDArray[np.uint8]:
    """Radar images (N, 1, rows, cols) uint8 of N boats, each seeing J discs.

    ``range_m``, ``bearing_rad`` (relative to heading), ``radius_m``, ``valid`` all (N, J); at
    most :data:`MAX_DISCS` valid discs per boat. ``keys`` (N,) uint64: each boat's frame key
    (:meth:`RadarStreams.frame_keys`), needed where ``degradation`` degrades a boat. Discs no
    larger than ``box_radius_m`` (the study's 1 m pole) are drawn as the study draws its pole, as
    their polar box (:func:`usvsim.task.radar.render_radar`, the same pixels). ``backend``:
    ``auto`` the compiled kernel where it builds, else NumPy; ``compiled`` or ``numpy`` only.

    Raises
    ------
    ValueError
        If a boat has more than :data:`MAX_DISCS` valid discs, a boat is degraded without
        ``keys``, the image has more than 2²² − 32 pixels, or ``compiled`` is asked for where no
        C compiler builds the kernel.
    """
    cfg = cfg or RadarConfig()
    rho = np.ascontiguousarray(range_m, dtype=float)
    n, j = rho.shape
    valid = np.asarray(valid, dtype=bool)
    most = int(valid.sum(axis=1).max(initial=0))
    if most > MAX_DISCS:
        raise ValueError(f"a boat sees at most {MAX_DISCS} valid discs, got {most}")
    if cfg.n_rows * cfg.n_cols + MAX_DISCS > FRAME_DRAWS:
        raise ValueError(f"a radar image holds at most {FRAME_DRAWS - MAX_DISCS} pixels")
    degraded = degradation is not None and bool(degradation.degraded.any())
    if degraded and keys is None:
        raise ValueError(
            "radar degradation is enabled: pass a noise source (the boats' frame keys)"
        )
    kernel = load_kernel() if backend != "numpy" else None  # built once, on first use
    if backend == "compiled" and kernel is None:
        raise ValueError("backend 'compiled': the radar kernel did not build (no C compiler?)")
    if backend not in ("auto", "compiled", "numpy"):
        raise ValueError(f"backend must be auto, compiled or numpy; got {backend!r}")
    phi = ssa(np.asarray(bearing_rad, dtype=float))
    r = np.ascontiguousarray(radius_m, dtype=float)
    inside = rho < r
    box = r <= box_radius_m  # the study's pole: its polar box
    half = np.arcsin(np.minimum(r / np.maximum(rho, 1e-12), 1.0))
    half = np.where(inside & ~box, math.pi, half)
    discs = _PolarDiscs(rho, phi, r, half, valid, inside, box)
    if kernel is not None:
        return _render_compiled(kernel, discs, cfg, degradation, keys)
    if degraded:
        assert degradation is not None and keys is not None
        rank = np.maximum(np.cumsum(valid, axis=1) - 1, 0)  # place among the valid discs
        draws = frame_draws(keys, cfg.n_rows * cfg.n_cols, j)
        u_miss = np.take_along_axis(draws, rank, axis=1) >> np.uint64(40)
        p_miss = np.where(degradation.degraded, degradation.missed_probability, 0.0)
        discs = replace(discs, valid=valid & (u_miss.astype(float) * 2.0**-24 >= p_miss[:, None]))
    lit = _lit_pixels(discs, cfg)
    out = np.empty((n, *cfg.shape), dtype=np.uint8)
    np.multiply(lit.view(np.uint8), np.uint8(255), out=out[:, 0])
    if degraded:
        assert degradation is not None and keys is not None
        boats = np.flatnonzero(degradation.degraded)
        out[boats, 0] = _degrade(lit[boats], np.asarray(keys)[boats], degradation, boats)
    return out


def _render_compiled(
    kernel: Callable[..., None],
    d: _PolarDiscs,
    cfg: RadarConfig,
    q: RadarDegradation | None,
    keys: NDArray[np.uint64] | None,
) -> NDArray[np.uint8]:
    """:func:`render_scene` by the compiled kernel (the same arithmetic)."""
    n, j = d.rho.shape
    flags = (
        d.valid.astype(np.uint8) | (d.inside.astype(np.uint8) << 1) | (d.box.astype(np.uint8) << 2)
    )
    edges = cfg.bearing_edges_rad
    b_hi = edges[1:].copy()
    b_hi[-1] = np.nextafter(b_hi[-1], np.inf)
    out = np.empty((n, *cfg.shape), dtype=np.uint8)
    arrays = [edges, b_hi, *(np.ascontiguousarray(a) for a in (d.rho, d.phi, d.r, d.half, flags))]
    if q is not None and keys is not None:
        key_arr = np.ascontiguousarray(keys, dtype=np.uint64)
        fields = [
            np.ascontiguousarray(a, dtype=float)
            for a in (q.clutter_probability, q.speckle, q.missed_probability, q.noise_amplitude)
        ]
        ptrs: list[int | None] = [key_arr.ctypes.data, *(a.ctypes.data for a in fields)]
    else:
        ptrs = [None] * 5
    kernel(
        n, j, cfg.n_rows, cfg.n_cols, cfg.max_range_m / cfg.n_rows,
        *(a.ctypes.data for a in arrays), *ptrs, out.ctypes.data,
    )  # fmt: skip
    return out


def _lit_pixels(
    d: _PolarDiscs,
    cfg: RadarConfig,
) -> NDArray[np.bool_]:
    """The lit pixels (N, rows, cols) of the valid discs (module docstring), in NumPy."""
    rho, phi, r, half, valid, inside, box = (d.rho, d.phi, d.r, d.half, d.valid, d.inside, d.box)
    n = rho.shape[0]
    b_edges = cfg.bearing_edges_rad
    b_lo, b_hi = b_edges[:-1], b_edges[1:].copy()
    b_hi[-1] = np.nextafter(b_hi[-1], np.inf)
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
    # rows k_lo..k_hi marked +1 / -1 in a difference array laid out (boat, range, column) and
    # summed along range (contiguous rows of columns: the fast axis for cumsum): no
    # (N, J, rows, cols) array
    dr = cfg.max_range_m / cfg.n_rows
    k_lo = np.floor(np.maximum(near, 0.0) / dr)
    k_hi = np.minimum(np.floor(far / dr), cfg.n_rows - 1)
    keep = (k_lo <= k_hi) & (k_lo < cfg.n_rows) & (far >= 0)
    row_len = cfg.n_cols
    base = boat[keep] * ((cfg.n_rows + 1) * row_len) + col[keep]
    diff = np.zeros(n * (cfg.n_rows + 1) * row_len, dtype=np.int8)  # J <= 32: no overflow
    np.add.at(diff, base + k_lo[keep].astype(np.intp) * row_len, 1)
    np.add.at(diff, base + (k_hi[keep].astype(np.intp) + 1) * row_len, -1)
    depth = np.cumsum(diff.reshape(n, cfg.n_rows + 1, row_len), axis=1, dtype=np.int8)
    return depth[:, : cfg.n_rows] > 0


def _degrade(
    lit: NDArray[np.bool_],
    keys: NDArray[np.uint64],
    q: RadarDegradation,
    boats: NDArray[np.intp],
) -> NDArray[np.uint8]:
    """The degraded images (B, rows, cols) of B boats from their lit pixels and frame keys
    (module docstring): speckle, clutter (the brighter of the return and the clutter), additive
    noise, clipped to 0..255; float32 as the compiled kernel. ``q``'s fields at ``boats``."""
    b_count, rows, cols = lit.shape
    h = frame_draws(keys, 0, rows * cols)  # (B, P)
    level = lit.reshape(b_count, -1).astype(np.float32) * np.float32(255.0)

    def bits(shift: int, width: int) -> NDArray[np.float32]:
        field = (h >> np.uint64(shift)) & np.uint64((1 << width) - 1)
        return field.astype(np.float32) * np.float32(2.0**-width)

    speckle = q.speckle[boats].astype(np.float32)[:, None]
    level = np.where(speckle > 0, level * (np.float32(1.0) - speckle * bits(50, 14)), level).astype(
        np.float32
    )
    trial = (h & np.uint64(0xFFFFF)).astype(float) * 2.0**-20
    clutter = trial < q.clutter_probability[boats][:, None]
    level = np.where(clutter, np.maximum(level, np.float32(255.0) * bits(36, 14)), level)
    noise = q.noise_amplitude[boats].astype(np.float32)[:, None]
    level = np.where(noise > 0, level + noise * bits(20, 16), level).astype(np.float32)
    np.clip(level, 0.0, 255.0, out=level)
    return level.astype(np.uint8).reshape(b_count, rows, cols)
