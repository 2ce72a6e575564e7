"""The compiled slots of the ``scene`` observation: the k nearest discs of N boats in one C call.

:func:`usvsim.task.observations.scene_observation` computes every disc's range and bearing in
NumPy (``np.arctan2`` may be a SIMD routine whose last bit differs from C's ``atan2``), then
hands the rest to this kernel, which does per boat what the NumPy path does with (N, J) arrays:
the edge distance ``r − R`` (``inf`` for an empty slot), a stable sort by it (insertion sort,
NaN last as in ``np.argsort``), and for the k nearest the features ``[r, φ, R, v_x, v_y, 1]``
(relative velocity in the body frame, ``c·Δv_N + s·Δv_E``, ``−s·Δv_N + c·Δv_E``), an empty
slot all zeros, each rounded once to float32; also the own velocity in the body frame. The
arithmetic is the NumPy path's operation for operation (double, no FMA contraction), so the two
agree bit for bit (tested). Built on first use like the other kernels
(:func:`usvsim.common.cbuild.load_function`); None where no build succeeds.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable

from usvsim.common.cbuild import load_function

__all__ = ["MAX_SCENE_DISCS", "SCENE_SOURCE", "load_scene_kernel"]

MAX_SCENE_DISCS = 256  # discs per boat the kernel sorts on its stack; more: the NumPy path

SCENE_SOURCE = r"""
#include <math.h>
#include <stdint.h>

/* a before b in np.argsort's order (NaN last); ties keep their order (stable) */
static inline int before(double a, double b) { return a < b || (isnan(b) && !isnan(a)); }

/* n boats, j discs, k slots; r, phi, radius, valid (n, j); disc_vel (n, j, 2) m/s over ground;
   vel (n, 2); c, s (n) = cos, sin of the heading; out (n, 4 + 6 k) float32, columns 2.. written
   (0, 1: the goal, by the caller) */
void usv_scene_slots(int n, int j, int k, const double* r, const double* phi,
                     const double* radius, const uint8_t* valid, const double* disc_vel,
                     const double* vel, const double* c, const double* s, float* out) {
  const int width = 4 + 6 * k, m = j < k ? j : k;
  for (int b = 0; b < n; ++b) {
    float* o = out + (long)b * width;
    const double cb = c[b], sb = s[b], vn = vel[2 * b], ve = vel[2 * b + 1];
    o[2] = (float)(cb * vn + sb * ve);
    o[3] = (float)(-sb * vn + cb * ve);
    double edge[256];
    int order[256];
    for (int q = 0; q < j; ++q) {
      const long i = (long)b * j + q;
      const double e = valid[i] ? r[i] - radius[i] : INFINITY;
      int p = q;
      while (p > 0 && before(e, edge[p - 1])) {
        edge[p] = edge[p - 1]; order[p] = order[p - 1]; --p;
      }
      edge[p] = e; order[p] = q;
    }
    for (int q = 0; q < k; ++q) {
      float* f = o + 4 + 6 * q;
      const long i = (long)b * j + (q < m ? order[q] : 0);
      if (q >= m || !valid[i]) {
        f[0] = f[1] = f[2] = f[3] = f[4] = f[5] = 0.0f;
        continue;
      }
      const double dn = disc_vel[2 * i] - vn, de = disc_vel[2 * i + 1] - ve;
      f[0] = (float)r[i]; f[1] = (float)phi[i]; f[2] = (float)radius[i];
      f[3] = (float)(cb * dn + sb * de);
      f[4] = (float)(-sb * dn + cb * de);
      f[5] = 1.0f;
    }
  }
}
"""


@functools.cache
def load_scene_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_scene_slots`` (argument types set), or None where no build succeeds
    (built and loaded once per process)."""
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    fn: Callable[..., None] | None = load_function(
        SCENE_SOURCE, "usv_scene_slots", [int_, int_, int_, *([ptr] * 9)], "scene"
    )
    return fn
