"""The compiled scene radar: disc rendering and degradation of N boats' images in one C call.

The C below is a line-for-line port of the NumPy path of :mod:`usvsim.task.scene_radar` (the
reference; the module docstring there states the geometry and the laws): per boat (OpenMP over
boats), the missed returns (a disc's draw numbered among the boat's valid discs), then each valid
disc's lit columns and range rows, then one pass over the pixels for speckle, clutter and
additive noise, each pixel's draws from one counter-based hash (SplitMix64) of the boat's frame
key. Float arithmetic is that of the reference (double for the geometry, float32 for the
intensities, no FMA contraction), so the two agree bit for bit except where a libm
``sin``/``cos`` and NumPy's differ in the last bit at a cell edge (measured: no pixel differed
in 5,120 random boat-frames of 12 discs, 30 M pixels; the test compares 1,024).

Built on first use with the system compiler (:func:`usvsim.common.cbuild.compile_library`),
``-O3 -march=native`` with a portable fallback; where neither builds, :func:`load_kernel`
returns None and the NumPy path runs.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable

from usvsim.common.cbuild import load_function

__all__ = ["KERNEL_SOURCE", "load_kernel"]

KERNEL_SOURCE = r"""
#include <math.h>
#include <stdint.h>
#include <string.h>

#define GOLDEN 0x9E3779B97F4A7C15ULL

static inline uint64_t mix64(uint64_t z) {  /* SplitMix64's output function (Steele et al. 2014) */
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

static inline double np_mod(double a, double b) {  /* NumPy's float remainder (sign of b) */
  double m = fmod(a, b);
  if (m != 0.0) { if ((b < 0.0) != (m < 0.0)) m += b; }
  else m = copysign(0.0, b);
  return m;
}

static inline double ssa(double a) { return np_mod(a + M_PI, 2.0 * M_PI) - M_PI; }

/* the first index c < n with x_sorted[c] > x (n where none) */
static inline int first_above(const double* x_sorted, int n, double x) {
  int lo = 0, hi = n;
  while (lo < hi) { int m = (lo + hi) / 2; if (x_sorted[m] > x) hi = m; else lo = m + 1; }
  return lo;
}

/* flags (n, j): bit 0 valid, bit 1 inside (boat within the disc), bit 2 box (a study pole) */
void usv_scene_radar(int n, int j, int rows, int cols, double dr, const double* edges,
                     const double* b_hi, const double* rho, const double* phi, const double* r,
                     const double* half, const uint8_t* flags, const uint64_t* keys,
                     const double* p_clutter, const double* speckle, const double* p_miss,
                     const double* noise, uint8_t* out) {
  const long pixels = (long)rows * cols;
  #pragma omp parallel for schedule(dynamic, 4) if(n >= 32)
  for (int b = 0; b < n; ++b) {
    uint8_t* img = out + (long)b * pixels;
    memset(img, 0, (size_t)pixels);
    const uint64_t key = keys ? keys[b] : 0;
    const int degrade = keys && (p_clutter[b] > 0 || speckle[b] > 0 || p_miss[b] > 0 ||
                                 noise[b] > 0);
    int rank = 0;  /* valid discs so far: padding slots take no draw */
    for (int d = 0; d < j; ++d) {
      const long k = (long)b * j + d;
      if (!(flags[k] & 1)) continue;
      const int m = rank++;
      if (degrade) {  /* missed return: draw `pixels + m` of the frame, 24 bits */
        uint64_t h = mix64(key + GOLDEN * (uint64_t)(pixels + m + 1));
        if ((double)(h >> 40) * 0x1p-24 < p_miss[b]) continue;
      }
      const double rc = rho[k], pc = phi[k], radius = r[k];
      const double lo = pc - half[k], hi = pc + half[k];
      const int inside = flags[k] & 2, box = flags[k] & 4;
      /* the columns lit for each shift of the span by 0, -2pi, +2pi are one run: those with
         b_hi[c] > lo + s and edges[c] <= hi + s (both sequences increase), found by bisection;
         a column in two runs is marked twice, to the same pixels */
      for (int w = 0; w < 3; ++w) {
        const double s = w == 0 ? 0.0 : (w == 1 ? -2.0 * M_PI : 2.0 * M_PI);
        const int c0 = first_above(b_hi, cols, lo + s);
        const int c1 = first_above(edges, cols, hi + s);  /* edges[c] <= hi + s for c < c1 */
        for (int c = c0; c < c1; ++c) {
          double near, far;
          if (box) { near = rc - radius; far = rc + radius; }
          else {
            double clipped = pc < edges[c] ? edges[c] : (pc > edges[c + 1] ? edges[c + 1] : pc);
            double delta = ssa(clipped - pc);
            double along = rc * cos(delta), across = rc * sin(delta);
            double sq = radius * radius - across * across;
            double chord = sqrt(sq > 0.0 ? sq : 0.0);
            near = inside ? 0.0 : along - chord;
            far = along + chord;
          }
          double k_lo = floor((near > 0.0 ? near : 0.0) / dr);
          double k_hi = floor(far / dr);
          if (k_hi > rows - 1) k_hi = rows - 1;
          if (!(k_lo <= k_hi && k_lo < rows && far >= 0.0)) continue;
          for (int row = (int)k_lo; row <= (int)k_hi; ++row) img[(long)row * cols + c] = 1;
        }
      }
    }
    if (!degrade) {
      for (long p = 0; p < pixels; ++p) img[p] = img[p] ? 255 : 0;
      continue;
    }
    /* one hash per pixel: bits 0-19 clutter trial, 20-35 noise, 36-49 clutter intensity,
       50-63 speckle (module docstring of usvsim.task.scene_radar). Branch-free, so that it
       vectorises: a zero speckle or noise multiplies by 1 or adds 0 (exact), and the clutter
       trial u < p is the integer test k < ceil(p 2^20) (k 2^-20 < p, exactly) */
    const float sp = speckle[b] > 0 ? (float)speckle[b] : 0.0f;
    const float amp = noise[b] > 0 ? (float)noise[b] : 0.0f;
    const double scaled = p_clutter[b] > 0 ? ceil(p_clutter[b] * 0x1p20) : 0.0;
    const uint32_t threshold = scaled > 0x1p21 ? (1u << 21) : (uint32_t)scaled;
    uint64_t state = key;  /* key + G (p + 1) at pixel p, by addition */
    for (long p = 0; p < pixels; ++p) {
      state += GOLDEN;
      uint64_t h = mix64(state);
      float level = (float)img[p] * 255.0f;
      level *= 1.0f - sp * ((float)(int32_t)(h >> 50) * 0x1p-14f);
      float c = 255.0f * ((float)(int32_t)((h >> 36) & 0x3FFF) * 0x1p-14f);
      float brighter = c > level ? c : level;
      level = (uint32_t)(h & 0xFFFFF) < threshold ? brighter : level;
      level += amp * ((float)(int32_t)((h >> 20) & 0xFFFF) * 0x1p-16f);
      level = level < 0.0f ? 0.0f : level;
      level = level > 255.0f ? 255.0f : level;
      img[p] = (uint8_t)(int32_t)level;
    }
  }
}
"""


@functools.cache
def load_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_scene_radar`` (argument types set), or None where no build succeeds
    or the cache folder cannot be written (built and loaded once per process)."""
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    argtypes = [int_, int_, int_, int_, ctypes.c_double, *([ptr] * 13)]
    fn: Callable[..., None] | None = load_function(
        KERNEL_SOURCE, "usv_scene_radar", argtypes, "radar"
    )
    return fn
