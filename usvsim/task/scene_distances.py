"""Every boat's nearest disc and collisions over a decision's sub-steps (the open-water step's
judge), compiled or in NumPy.

:func:`nearest_and_hits` takes N boats' positions at the T plant steps of a decision and their
discs (static discs and moving vessels, padded per boat with a validity mask) and returns the
smallest pole-equivalent distance ``h + (r_pole − r)`` (N, T) m (``inf`` without a valid disc;
the success rule of :mod:`usvsim.task.openwater`) and whether any disc is hit, ``h < r +
half_beam`` (N, T); ``h`` is the distance to the disc's centre, each vessel at its position at
that step (:func:`usvsim.task.openwater.vessel_motion`).

The NumPy path (``backend="numpy"``) is the reference: (N, J, T) arrays, ``np.hypot``. The
compiled path (the default where a C compiler is found; built on first use like the scene
radar, :func:`usvsim.common.cbuild.load_function`) loops per boat (OpenMP over boats) and
sub-step, makes no (N, J, T) array, and runs ``hypot`` (exact but slow) only where it can
decide something: first every disc's distance by ``sqrt(dx² + dy²)`` (within a few ulp of
``hypot``), then ``hypot`` for the discs within 1e-9 relative of the smallest and for a
collision test within 1e-9 of its threshold. Its arithmetic is otherwise the reference's
operation for operation (double, no FMA contraction); vessel positions go through libm
``sin``/``cos``, which may differ from NumPy's in the last bit, so distances to vessels agree to
rounding (tested: ≤ 1e-12 relative; static discs exactly); every row of the stress suite came
out unchanged.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from usvsim.common.cbuild import load_function
from usvsim.task.openwater import vessel_motion

__all__ = [
    "DISTANCE_SOURCE",
    "MAX_KERNEL_DISCS",
    "PackedDiscs",
    "load_distance_kernel",
    "nearest_and_hits",
]

FloatArray = NDArray[np.float64]

MAX_KERNEL_DISCS = 64  # discs per boat (statics + vessels) the kernel takes; more: NumPy

DISTANCE_SOURCE = r"""
#include <math.h>
#include <stdint.h>

/* boats n, sub-steps T, statics K, vessels M; the position (x, y) of boat b at sub-step s is
   traj[b * boat_stride + s * step_stride + {0, 1}] (strides in doubles), at episode time
   t_s[b * T + s]. Outputs d_min (n, T), hit (n, T). */
/* the exact distance (libm hypot, as NumPy's) is needed only where it can matter: for the discs
   whose distance by sqrt(dx^2 + dy^2) (within 1e-12 relative of hypot's) lies near the smallest,
   and for a collision test near its threshold; elsewhere the cheap one decides the same. */
#define NEAR(a, b) (fabs((a) - (b)) <= 1e-9 * (fabs(a) + fabs(b) + 1.0))

void usv_scene_distances(int n, int T, int K, int M, double r_pole, double half_beam,
                         const double* traj, long boat_stride, long step_stride,
                         const double* t_s,
                         const double* centres, const double* radii, const uint8_t* static_ok,
                         const double* v_p0, const double* v_course, const double* v_speed,
                         const double* v_turn, const double* v_radius, const uint8_t* vessel_ok,
                         double* d_min, uint8_t* hit) {
  if (K + M > 64) return;  /* the caller's NumPy path takes such scenes */
  #pragma omp parallel for schedule(static) if(n >= 64)
  for (int b = 0; b < n; ++b) {
    double dxs[64], dys[64], rs[64];  /* discs of boat b at one sub-step: K + M <= 64 */
    double sin0[64], cos0[64];
    for (int m = 0; m < M; ++m) {
      sin0[m] = sin(v_course[(long)b * M + m]);
      cos0[m] = cos(v_course[(long)b * M + m]);
    }
    for (int s = 0; s < T; ++s) {
      const double* p = traj + (long)b * boat_stride + (long)s * step_stride;
      const double x = p[0], y = p[1];
      const double t = t_s[(long)b * T + s];
      int nd = 0;
      for (int k = 0; k < K; ++k) {
        const long i = (long)b * K + k;
        if (!static_ok[i]) continue;
        dxs[nd] = x - centres[2 * i]; dys[nd] = y - centres[2 * i + 1]; rs[nd] = radii[i];
        ++nd;
      }
      for (int m = 0; m < M; ++m) {
        const long i = (long)b * M + m;
        if (!vessel_ok[i]) continue;
        const double course = v_course[i], speed = v_speed[i], turn = v_turn[i];
        double dx, dy;
        if (fabs(turn * t) < 1e-9) {  /* a straight course: no sin/cos of the course now */
          dx = speed * t * cos0[m];
          dy = speed * t * sin0[m];
        } else {
          const double chi = course + turn * t;
          dx = speed / turn * (sin(chi) - sin0[m]);
          dy = speed / turn * (cos0[m] - cos(chi));
        }
        dxs[nd] = x - (v_p0[2 * i] + dx); dys[nd] = y - (v_p0[2 * i + 1] + dy);
        rs[nd] = v_radius[i];
        ++nd;
      }
      double approx[64], cheap_best = INFINITY;
      uint8_t any = 0;
      for (int q = 0; q < nd; ++q) {
        const double h = sqrt(dxs[q] * dxs[q] + dys[q] * dys[q]);
        approx[q] = h + (r_pole - rs[q]);
        if (approx[q] < cheap_best) cheap_best = approx[q];
        const double limit = rs[q] + half_beam;
        if (NEAR(h, limit)) { if (hypot(dxs[q], dys[q]) < limit) any = 1; }
        else if (h < limit) any = 1;
      }
      double best = INFINITY;
      for (int q = 0; q < nd; ++q) {
        /* every disc where the cheap minimum is inf (overflow) or the distance NaN */
        if (isfinite(cheap_best) && !isnan(approx[q]) && !NEAR(approx[q], cheap_best)) continue;
        const double d = hypot(dxs[q], dys[q]) + (r_pole - rs[q]);
        if (d < best || isnan(d)) best = d;
        if (isnan(best)) break;  /* NaN wins, as in NumPy's minimum */
      }
      d_min[(long)b * T + s] = best;
      hit[(long)b * T + s] = any;
    }
  }
}
"""


@functools.cache
def load_distance_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_scene_distances`` (argument types set), or None where no build
    succeeds (built and loaded once per process)."""
    ptr, int_, dbl, long_ = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_long
    argtypes = [int_, int_, int_, int_, dbl, dbl, ptr, long_, long_, *([ptr] * 12)]
    fn: Callable[..., None] | None = load_function(
        DISTANCE_SOURCE, "usv_scene_distances", argtypes, "distance"
    )
    return fn


@dataclass(frozen=True)
class PackedDiscs:
    """N boats' discs, padded per boat: K static discs, centres (N, K, 2) m, radii (N, K) m,
    valid (N, K); M vessels, start positions (N, M, 2) m, courses (N, M) rad, speeds (N, M)
    m/s, turn rates (N, M) rad/s, radii (N, M) m, valid (N, M)."""

    centres_ne: FloatArray
    radii_m: FloatArray
    static_ok: NDArray[np.bool_]
    vessel_p0_ne: FloatArray
    vessel_course_rad: FloatArray
    vessel_speed_mps: FloatArray
    vessel_turn_radps: FloatArray
    vessel_radius_m: FloatArray
    vessel_ok: NDArray[np.bool_]


def nearest_and_hits(
    pos_ne: FloatArray,
    t_s: FloatArray,
    discs: PackedDiscs,
    r_pole_m: float,
    half_beam_m: float,
    backend: Literal["auto", "compiled", "numpy"] = "auto",
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Smallest pole-equivalent distance (N, T) m and any-disc-hit flags (N, T) of N boats at
    positions ``pos_ne`` (N, T, ≥ 2; the first two columns are used) and episode times
    ``t_s`` (N, T) s (module docstring). ``backend="compiled"`` raises ``ValueError`` where the
    kernel did not build; ``"auto"`` runs it where it did (and the boat has ≤
    :data:`MAX_KERNEL_DISCS` discs), NumPy otherwise."""
    if backend not in ("auto", "compiled", "numpy"):
        raise ValueError(f"backend must be 'auto', 'compiled' or 'numpy', got {backend!r}")
    n_discs = discs.centres_ne.shape[1] + discs.vessel_p0_ne.shape[1]
    kernel = load_distance_kernel() if backend != "numpy" else None
    if backend == "compiled" and (kernel is None or n_discs > MAX_KERNEL_DISCS):
        raise ValueError(
            "backend='compiled': the distance kernel did not build (no C compiler?) or the "
            f"scene has more than {MAX_KERNEL_DISCS} discs per boat ({n_discs})"
        )
    pos = np.asarray(pos_ne, dtype=np.float64)
    t = np.ascontiguousarray(np.broadcast_to(t_s, pos.shape[:2]), dtype=np.float64)
    if kernel is None or n_discs > MAX_KERNEL_DISCS:
        return _numpy_path(pos, t, discs, r_pole_m, half_beam_m)
    if pos.strides[2] != 8 or pos.strides[0] % 8 or pos.strides[1] % 8:
        pos = np.ascontiguousarray(pos)
    n, steps = pos.shape[0], pos.shape[1]
    d_min, hit = np.empty((n, steps)), np.empty((n, steps), dtype=np.bool_)
    arrays = [
        np.ascontiguousarray(a, dtype=dt)
        for a, dt in (
            (discs.centres_ne, np.float64), (discs.radii_m, np.float64),
            (discs.static_ok, np.bool_), (discs.vessel_p0_ne, np.float64),
            (discs.vessel_course_rad, np.float64), (discs.vessel_speed_mps, np.float64),
            (discs.vessel_turn_radps, np.float64), (discs.vessel_radius_m, np.float64),
            (discs.vessel_ok, np.bool_),
        )
    ]  # fmt: skip
    kernel(
        n, steps, arrays[0].shape[1], arrays[3].shape[1], r_pole_m, half_beam_m,
        pos.ctypes.data, pos.strides[0] // 8, pos.strides[1] // 8, t.ctypes.data,
        *(a.ctypes.data for a in arrays), d_min.ctypes.data, hit.ctypes.data,
    )  # fmt: skip
    return d_min, hit


def _numpy_path(
    pos: FloatArray, t_s: FloatArray, discs: PackedDiscs, r_pole_m: float, half_beam_m: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The reference: (N, J, T) distances; statics broadcast over the T steps, then vessels."""
    c = discs.centres_ne
    vessels, _ = vessel_motion(
        discs.vessel_p0_ne[:, :, None, :], discs.vessel_course_rad[:, :, None],
        discs.vessel_speed_mps[:, :, None], discs.vessel_turn_radps[:, :, None],
        t_s[:, None, :],
    )  # fmt: skip
    x, y = pos[:, None, :, 0], pos[:, None, :, 1]
    h = np.concatenate(
        [
            np.hypot(x - c[:, :, None, 0], y - c[:, :, None, 1]),
            np.hypot(x - vessels[..., 0], y - vessels[..., 1]),
        ],
        axis=1,
    )
    radii = np.concatenate([discs.radii_m, discs.vessel_radius_m], axis=1)
    ok = np.concatenate([discs.static_ok, discs.vessel_ok], axis=1)
    d = np.where(ok[..., None], h + (r_pole_m - radii)[..., None], np.inf)
    hit = ok[..., None] & (h < (radii + half_beam_m)[..., None])
    return d.min(axis=1, initial=np.inf), np.any(hit, axis=1)
