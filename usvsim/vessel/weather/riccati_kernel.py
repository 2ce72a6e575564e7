"""The wave filter's Riccati doubling in C: every boat's equation in one call, no NumPy per step.

:func:`usvsim.vessel.weather.observer.solve_filter_riccati` runs the structure-preserving
doubling (Chu, Fan & Lin 2005) on an (N, n, n) stack. In NumPy each of its ~14 doublings is a
dozen array calls whose overhead, not their arithmetic, is the cost at the few boats an
environment step resets (0.5-0.9 ms per reset of 1-4 boats, most of the weather's reset time).
This is the same iteration, boat by boat, in C: the same operations in the same order
(W = I + G_k Q_k; [W⁻¹A_k, W⁻¹G_k] by LU with partial pivoting, as LAPACK's ``dgesv``;
Q_{k+1} = Q_k + (A_kᵀ Q_k) W⁻¹A_k; G_{k+1} = G_k + (A_k W⁻¹G_k) A_kᵀ; A_{k+1} = A_k W⁻¹A_k) and
the same stopping rule per boat; only the order of each matrix product's sums can differ from
BLAS's, so the results agree to rounding (tested against the NumPy path and scipy's DARE).

Built with :func:`usvsim.common.cbuild.load_function` (IEEE arithmetic, no FMA contraction);
where no C compiler is found, :func:`riccati_doubling` returns None and the NumPy path runs.
"""

from __future__ import annotations

import ctypes
import functools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.cbuild import load_function

__all__ = ["HELPERS", "MAX_SIZE", "riccati_doubling"]

#: Largest state size the C kernel takes (the wave filter has 5).
MAX_SIZE = 8

#: The shared C helpers: small matrix products, an LU solve and one boat's doubling
#: (:mod:`usvsim.vessel.weather.start_kernel` builds on them).
HELPERS = r"""
#include <math.h>
#include <string.h>
#define MS 8
/* c = a b for d x d row-major matrices */
static void mm(int d, const double* a, const double* b, double* c) {
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < d; ++j) {
      double s = 0.0;
      for (int k = 0; k < d; ++k) s += a[i * d + k] * b[k * d + j];
      c[i * d + j] = s;
    }
}
/* x (d x r) = w⁻¹ rhs by LU with partial pivoting (w and rhs overwritten); 0 if singular */
static int solve(int d, int r, double* w, double* rhs) {
  for (int c = 0; c < d; ++c) {
    int p = c;
    for (int i = c + 1; i < d; ++i)
      if (fabs(w[i * d + c]) > fabs(w[p * d + c])) p = i;
    if (w[p * d + c] == 0.0) return 0;
    if (p != c) {
      for (int j = 0; j < d; ++j) {
        double t = w[c * d + j];
        w[c * d + j] = w[p * d + j];
        w[p * d + j] = t;
      }
      for (int j = 0; j < r; ++j) {
        double t = rhs[c * r + j];
        rhs[c * r + j] = rhs[p * r + j];
        rhs[p * r + j] = t;
      }
    }
    for (int i = c + 1; i < d; ++i) {
      double l = w[i * d + c] / w[c * d + c];
      for (int j = c + 1; j < d; ++j) w[i * d + j] -= l * w[c * d + j];
      for (int j = 0; j < r; ++j) rhs[i * r + j] -= l * rhs[c * r + j];
    }
  }
  for (int c = d - 1; c >= 0; --c)
    for (int j = 0; j < r; ++j) {
      double s = rhs[c * r + j];
      for (int k = c + 1; k < d; ++k) s -= w[c * d + k] * rhs[k * r + j];
      rhs[c * r + j] = s / w[c * d + c];
    }
  return 1;
}
/* one boat's doubling: a_c (d x d, the control-form A = Aᵀ of the filter), g0 (d x d,
   Hᵀ R⁻¹ H), q (d x d) -> p (d x d); returns the doublings used, -1 if not converged in
   max_iter, -2 if a W was singular */
static int doubling(int d, const double* a_c, const double* g0, const double* q, double tol,
                    int max_iter, double* p) {
  double ak[MS * MS], gk[MS * MS], qk[MS * MS], w[MS * MS], x[MS * 2 * MS];
  double wa[MS * MS], wg[MS * MS], akt[MS * MS], t1[MS * MS], step[MS * MS], t2[MS * MS];
  int dd = d * d, status = -1;
  memcpy(ak, a_c, sizeof(double) * dd);
  memcpy(gk, g0, sizeof(double) * dd);
  memcpy(qk, q, sizeof(double) * dd);
  for (int it = 0; it < max_iter; ++it) {
    mm(d, gk, qk, w);
    for (int i = 0; i < d; ++i) w[i * d + i] += 1.0;
    for (int i = 0; i < d; ++i)
      for (int j = 0; j < d; ++j) {
        x[i * 2 * d + j] = ak[i * d + j];
        x[i * 2 * d + d + j] = gk[i * d + j];
      }
    if (!solve(d, 2 * d, w, x)) { status = -2; break; }
    for (int i = 0; i < d; ++i)
      for (int j = 0; j < d; ++j) {
        wa[i * d + j] = x[i * 2 * d + j];
        wg[i * d + j] = x[i * 2 * d + d + j];
      }
    for (int i = 0; i < d; ++i)
      for (int j = 0; j < d; ++j) akt[i * d + j] = ak[j * d + i];
    mm(d, akt, qk, t1);
    mm(d, t1, wa, step);
    double big = 0.0, change = 0.0;
    for (int i = 0; i < dd; ++i) {
      qk[i] += step[i];
      if (fabs(qk[i]) > big) big = fabs(qk[i]);
      if (fabs(step[i]) > change) change = fabs(step[i]);
    }
    mm(d, ak, wg, t1);
    mm(d, t1, akt, t2);
    for (int i = 0; i < dd; ++i) gk[i] += t2[i];
    mm(d, ak, wa, t1);
    memcpy(ak, t1, sizeof(double) * dd);
    if (change <= tol * big) { status = it + 1; break; }
  }
  for (int i = 0; i < d; ++i)
    for (int j = 0; j < d; ++j) p[i * d + j] = 0.5 * (qk[i * d + j] + qk[j * d + i]);
  return status;
}
"""

_ENTRY = r"""
/* per boat b: a_c, q (d x d each, boat b's) and the shared g0 -> p (d x d) and iters[b] (as
   doubling's return) */
void usv_riccati_doubling(int n, int d, const double* a_c, const double* g0, const double* q,
                          double tol, int max_iter, double* p, int* iters) {
  #pragma omp parallel for schedule(static) if(n >= 256)
  for (int b = 0; b < n; ++b) {
    long o = (long)b * d * d;
    iters[b] = doubling(d, a_c + o, g0, q + o, tol, max_iter, p + o);
  }
}
"""


@functools.lru_cache(maxsize=1)
def _kernel() -> Any | None:
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    argtypes = [int_, int_, ptr, ptr, ptr, ctypes.c_double, int_, ptr, ptr]
    return load_function(HELPERS + _ENTRY, "usv_riccati_doubling", argtypes, prefix="riccati")


def riccati_doubling(
    a_c: NDArray[np.float64],
    g0: NDArray[np.float64],
    q: NDArray[np.float64],
    tol: float,
    max_iter: int,
) -> tuple[NDArray[np.float64], NDArray[np.int32]] | None:
    """Stationary Q of the doubling for N boats (the filter's prior covariances P, symmetrised),
    (N, n, n), and the doublings each boat took (N,) (-1: not converged in ``max_iter``, -2: a
    singular W); ``a_c`` (N, n, n) the control-form A (the filter's Aᵀ), ``g0`` (n, n)
    Hᵀ R⁻¹ H, ``q`` (N, n, n). None where the C kernel does not build or n > :data:`MAX_SIZE`."""
    kernel = _kernel()
    n, d = a_c.shape[0], a_c.shape[-1]
    if kernel is None or d > MAX_SIZE:
        return None
    a_c = np.ascontiguousarray(a_c, dtype=np.float64)
    g0 = np.ascontiguousarray(g0, dtype=np.float64)
    q = np.ascontiguousarray(q, dtype=np.float64)
    if a_c.shape != (n, d, d) or q.shape != (n, d, d) or g0.shape != (d, d):
        raise ValueError(f"need a_c, q of shape (N, n, n) and g0 (n, n), got {a_c.shape}")
    p = np.empty((n, d, d))
    iters = np.empty(n, dtype=np.int32)
    kernel(n, d, a_c.ctypes.data, g0.ctypes.data, q.ctypes.data, tol, max_iter, p.ctypes.data,
           iters.ctypes.data)  # fmt: skip
    return p, iters
