"""The compiled GNSS faults of a decision period: N boats' GNSS error entries scaled in one call.

:meth:`usvsim.task.disturbance.BoatDisturbances.perturb_normals` scales each faulty boat's GNSS
error draws (the standard normals the fused plant + filter step turns into position and velocity
errors) by its noise scale, and by its outlier scale where that entry's outlier draw fires. In
NumPy that is a gather, a few (N, G) array passes and a scatter over strided columns (about
95 µs at N = 256, G = 40); here one pass over the faulty boats' G entries. The outlier draws
and their thresholds Φ⁻¹(p) stay with the caller (the boats' own streams, SciPy's ``ndtri``);
the arithmetic is the NumPy path's (the scale, times the outlier scale where an outlier fires,
then the draw times the scale: double, no FMA contraction), so the two agree bit for bit
(tested). Built on first use like the other kernels (:func:`usvsim.common.cbuild.load_function`);
None where no build succeeds, and the NumPy path runs.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable

from usvsim.common.cbuild import load_function

__all__ = ["GNSS_FAULT_SOURCE", "load_gnss_fault_kernel"]

GNSS_FAULT_SOURCE = r"""
#include <stdint.h>

/* out (n, m): a copy of the draws, rows `rows` (f of them) rewritten at the g columns `cols`:
   s = scale[i]; s = s * outlier_scale[i] where draw row d = drawing[k] >= 0 has
   z[d, c] < threshold[i]; out[i, col] = out[i, col] * s */
void usv_gnss_faults(int f, int m, int g, const int64_t* rows, const int64_t* cols,
                     const double* scale, const double* outlier_scale, const int64_t* drawing,
                     const double* z, const double* threshold, double* out) {
  for (int k = 0; k < f; ++k) {
    const int64_t i = rows[k], d = drawing[k];
    double* row = out + i * (int64_t)m;
    const double s0 = scale[i];
    if (d < 0) {
      for (int c = 0; c < g; ++c) row[cols[c]] = row[cols[c]] * s0;
    } else {
      const double s1 = s0 * outlier_scale[i], t = threshold[i];
      const double* zr = z + d * (int64_t)g;
      for (int c = 0; c < g; ++c) row[cols[c]] = row[cols[c]] * (zr[c] < t ? s1 : s0);
    }
  }
}
"""


@functools.cache
def load_gnss_fault_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_gnss_faults`` (argument types set), or None where no build succeeds
    (built and loaded once per process)."""
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    fn: Callable[..., None] | None = load_function(
        GNSS_FAULT_SOURCE, "usv_gnss_faults", [int_, int_, int_, *([ptr] * 8)], "gnss"
    )
    return fn
