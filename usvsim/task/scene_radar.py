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
times U[1 − s, 1]) and uniform additive noise (+ a · U[0, 1) on every pixel). Draws come from each
boat's own generator (:class:`RadarStreams`), so a boat's image does not depend on its
neighbours, and only as many as the frame needs: :data:`MAX_DISCS` uniforms for the misses; for
clutter the positions of P Bernoulli(p_clutter) trials drawn as their geometric gaps
(:func:`bernoulli_positions`) and one intensity per clutter pixel; one speckle factor per lit
pixel; P noise values only where a > 0. A frame with ~6 clutter pixels thus needs ~50 numbers, not
the 3 P + 32 = 17,882 of one uniform per pixel and effect.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.radar import RadarConfig

__all__ = ["MAX_DISCS", "RadarDegradation", "RadarStreams", "bernoulli_positions", "render_scene"]

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


class RadarStreams:
    """One radar random generator per boat (PCG64), restarted from each episode's radar seed.

    A boat's draws depend on its own frames only, so a batch of N boats equals N single boats
    and the count of draws may vary from frame to frame (module docstring).
    """

    def __init__(self, n_boats: int) -> None:
        self._gens: list[np.random.Generator | None] = [None] * n_boats

    def seed(self, boats: Sequence[int], seeds: Sequence[int]) -> None:
        """Restart the streams of ``boats`` from ``seeds`` (one per boat)."""
        for i, s in zip(boats, seeds, strict=True):
            self._gens[int(i)] = np.random.default_rng(int(s))

    def rows(self, boats: NDArray[np.intp]) -> list[np.random.Generator | None]:
        """The generators of ``boats``, in that order (None for a boat never seeded)."""
        return [self._gens[i] for i in boats.tolist()]


def render_scene(
    range_m: FloatArray,
    bearing_rad: FloatArray,
    radius_m: FloatArray,
    valid: NDArray[np.bool_],
    cfg: RadarConfig | None = None,
    degradation: RadarDegradation | None = None,
    rngs: Sequence[np.random.Generator | None] | None = None,
    box_radius_m: float = 1.0,
) -> NDArray[np.uint8]:
    """Radar images (N, 1, rows, cols) uint8 of N boats, each seeing J discs.

    ``range_m``, ``bearing_rad`` (relative to heading), ``radius_m``, ``valid`` all (N, J);
    J ≤ :data:`MAX_DISCS`. ``rngs[k]`` is boat k's radar generator (:class:`RadarStreams`), needed
    only for the boats that ``degradation`` degrades. Discs no larger than ``box_radius_m`` (the
    study's 1 m pole) are drawn as the study draws its pole, as their polar box
    (:func:`usvsim.task.radar.render_radar`, the same pixels).

    Raises
    ------
    ValueError
        If J > :data:`MAX_DISCS`, or a degraded boat has no generator.
    """
    cfg = cfg or RadarConfig()
    rho = np.asarray(range_m, dtype=float)
    n, j = rho.shape
    if j > MAX_DISCS:
        raise ValueError(f"a scene holds at most {MAX_DISCS} discs, got {j}")
    valid = np.asarray(valid, dtype=bool).copy()
    gens: list[np.random.Generator] = []
    boats = np.zeros(0, dtype=np.intp)
    if degradation is not None and degradation.degraded.any():
        boats = np.flatnonzero(degradation.degraded)
        given = [None if rngs is None else rngs[k] for k in boats.tolist()]
        gens = [g for g in given if g is not None]
        if len(gens) < boats.size:
            raise ValueError(
                "radar degradation is enabled: pass a noise source (a generator per degraded boat)"
            )
        # each degraded boat's missed returns: MAX_DISCS uniforms, one per possible disc
        u_miss = np.stack([g.random(MAX_DISCS) for g in gens])
        valid[boats] &= u_miss[:, :j] >= degradation.missed_probability[boats, None]
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
    lit = depth[:, : cfg.n_rows] > 0  # (N, rows, cols)
    out = np.empty((n, *cfg.shape), dtype=np.uint8)
    np.multiply(lit.view(np.uint8), np.uint8(255), out=out[:, 0])
    if gens:
        assert degradation is not None
        out[boats, 0] = _degrade(lit[boats], gens, degradation, boats)
    return out


def _degrade(
    lit: NDArray[np.bool_],
    gens: Sequence[np.random.Generator],
    q: RadarDegradation,
    boats: NDArray[np.intp],
) -> NDArray[np.uint8]:
    """The degraded images (B, rows, cols) of B boats from their lit pixels (module docstring):
    speckle on lit pixels, then clutter (the brighter of the return and the clutter), then
    additive noise, clipped to 0..255. ``gens[b]``, ``q``'s fields at ``boats[b]``: boat b's."""
    b_count, rows, cols = lit.shape
    pixels = rows * cols
    flat_lit = lit.reshape(b_count, pixels)
    level = flat_lit.astype(np.float32) * np.float32(255.0)
    speckle, clutter = q.speckle[boats], q.clutter_probability[boats]
    noise = q.noise_amplitude[boats]
    lit_counts = np.count_nonzero(flat_lit, axis=1)
    speckled, noisy = np.flatnonzero(speckle > 0), np.flatnonzero(noise > 0)
    noise_fields = np.empty((noisy.size, pixels), dtype=np.float32)
    # per boat, in this order: speckle factors, clutter positions and intensities, noise field
    u_speckle, clutter_at, u_clutter = [], [], []
    n_field = 0
    for b, (g, sp, cl, no) in enumerate(
        zip(gens, (speckle > 0).tolist(), clutter.tolist(), (noise > 0).tolist(), strict=True)
    ):
        if sp:  # one factor per lit pixel, in pixel order
            u_speckle.append(g.random(int(lit_counts[b]), dtype=np.float32))
        if cl > 0:
            at = bernoulli_positions(g, pixels, cl)
            clutter_at.append(b * pixels + at)
            u_clutter.append(g.random(at.size, dtype=np.float32))
        if no:
            g.random(dtype=np.float32, out=noise_fields[n_field])
            n_field += 1
    flat = level.reshape(-1)
    if u_speckle:  # the lit pixels of the speckled boats, boat by boat in pixel order
        on = np.flatnonzero(flat_lit & (speckle > 0)[:, None])
        u = np.concatenate(u_speckle)
        flat[on] *= 1.0 - np.repeat(speckle[speckled], lit_counts[speckled]) * u
    if clutter_at:
        at = np.concatenate(clutter_at)
        flat[at] = np.maximum(flat[at], 255.0 * np.concatenate(u_clutter))
    if noisy.size:
        level[noisy] += noise[noisy, None].astype(np.float32) * noise_fields
    np.clip(level, 0.0, 255.0, out=level)
    return level.astype(np.uint8).reshape(b_count, rows, cols)


def bernoulli_positions(g: np.random.Generator, n: int, p: float) -> NDArray[np.intp]:
    """The indices i < ``n`` where independent Bernoulli(``p``) trials succeed, drawn as the
    Geometric(``p``) gaps between successes (exactly the law of ``g.random(n) < p``, for
    ``n · p`` numbers instead of ``n``). ``0 < p <= 1``."""
    mean = n * p
    chunk = int(mean + 6.0 * math.sqrt(mean) + 8.0)  # enough at once but in ~1e-9 of frames
    pos = np.cumsum(g.geometric(p, chunk)) - 1
    while pos[-1] < n:  # the chunk ended inside the image: draw on
        pos = np.concatenate([pos, pos[-1] + np.cumsum(g.geometric(p, chunk))])
    return pos[: np.searchsorted(pos, n)]
