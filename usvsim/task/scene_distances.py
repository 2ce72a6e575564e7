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
from usvsim.task.batch import within_radius
from usvsim.task.openwater import vessel_motion

__all__ = [
    "DISTANCE_SOURCE",
    "MAX_KERNEL_DISCS",
    "PackedDiscs",
    "PeriodJudgement",
    "judge_period",
    "load_distance_kernel",
    "load_judge_kernel",
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

/* the nearest disc (pole-equivalent distance, returned) and any hit (*hit) of boat b at one
   sub-step, at position (x, y) and episode time t; sin0/cos0 the boat's vessels' courses' */
static inline double step_distance(int b, int K, int M, double r_pole, double half_beam,
                                   double x, double y, double t,
                                   const double* centres, const double* radii,
                                   const uint8_t* static_ok, const double* v_p0,
                                   const double* v_course, const double* v_speed,
                                   const double* v_turn, const double* v_radius,
                                   const uint8_t* vessel_ok, const double* sin0,
                                   const double* cos0, uint8_t* hit) {
  double dxs[64], dys[64], rs[64];  /* discs of boat b at this sub-step: K + M <= 64 */
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
  *hit = any;
  return best;
}

#define DISC_ARGS centres, radii, static_ok, v_p0, v_course, v_speed, v_turn, v_radius, \
                  vessel_ok, sin0, cos0

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
    double sin0[64], cos0[64];
    for (int m = 0; m < M; ++m) {
      sin0[m] = sin(v_course[(long)b * M + m]);
      cos0[m] = cos(v_course[(long)b * M + m]);
    }
    for (int s = 0; s < T; ++s) {
      const double* p = traj + (long)b * boat_stride + (long)s * step_stride;
      d_min[(long)b * T + s] = step_distance(b, K, M, r_pole, half_beam, p[0], p[1],
                                             t_s[(long)b * T + s], DISC_ARGS,
                                             hit + (long)b * T + s);
    }
  }
}

/* one decision period of each boat judged (judge_period's reference, in NumPy): per boat the
   nearest distance up to the end step, any hit and any goal over all T steps, the end step (the
   first hit or goal step, else T - 1), the first goal step (0 if none), and the obstacle and
   goal distances at the end step; within_radius is |dx|, |dy| <= R and hypot(dx, dy) <= R */
void usv_scene_judge(int n, int T, int K, int M, double r_pole, double half_beam,
                     double goal_radius, const double* traj, long boat_stride, long step_stride,
                     const double* t_s,
                     const double* centres, const double* radii, const uint8_t* static_ok,
                     const double* v_p0, const double* v_course, const double* v_speed,
                     const double* v_turn, const double* v_radius, const uint8_t* vessel_ok,
                     const double* goal, double* nearest, uint8_t* collision, uint8_t* reached,
                     int64_t* end_step, int64_t* first_goal, double* d_obstacle_end,
                     double* d_goal_end) {
  if (K + M > 64) return;
  #pragma omp parallel for schedule(static) if(n >= 64)
  for (int b = 0; b < n; ++b) {
    double sin0[64], cos0[64];
    for (int m = 0; m < M; ++m) {
      sin0[m] = sin(v_course[(long)b * M + m]);
      cos0[m] = cos(v_course[(long)b * M + m]);
    }
    const double gx = goal[2 * b], gy = goal[2 * b + 1], R = goal_radius;
    double upto = INFINITY, d_end = INFINITY, dx_end = 0.0, dy_end = 0.0;
    int end = -1, first = -1;
    uint8_t any_hit = 0, any_goal = 0;
    for (int s = 0; s < T; ++s) {
      const double* p = traj + (long)b * boat_stride + (long)s * step_stride;
      uint8_t h;
      const double d = step_distance(b, K, M, r_pole, half_beam, p[0], p[1],
                                     t_s[(long)b * T + s], DISC_ARGS, &h);
      const double dx = p[0] - gx, dy = p[1] - gy;
      const uint8_t g = fabs(dx) <= R && fabs(dy) <= R && hypot(dx, dy) <= R;
      if (end < 0) {  /* up to and including the end step */
        if (d < upto || isnan(d)) upto = isnan(upto) ? upto : d;
        if (h || g || s == T - 1) { end = s; d_end = d; dx_end = dx; dy_end = dy; }
      }
      any_hit |= h;
      if (g && first < 0) first = s;
      any_goal |= g;
    }
    nearest[b] = upto;
    collision[b] = any_hit;
    reached[b] = any_goal;
    end_step[b] = end;
    first_goal[b] = first < 0 ? 0 : first;
    d_obstacle_end[b] = d_end;
    d_goal_end[b] = hypot(dx_end, dy_end);
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


@functools.cache
def load_judge_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_scene_judge`` (argument types set), or None where no build succeeds."""
    ptr, int_, dbl, long_ = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_long
    argtypes = [int_, int_, int_, int_, dbl, dbl, dbl, ptr, long_, long_, *([ptr] * 18)]
    fn: Callable[..., None] | None = load_function(
        DISTANCE_SOURCE, "usv_scene_judge", argtypes, "distance"
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
    arrays = _kernel_arrays(discs)
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


@dataclass(frozen=True)
class PeriodJudgement:
    """One decision period of N boats judged from their true positions at its T sub-steps; all
    (N,): the smallest pole-equivalent distance up to and including the end step (m), a hit and
    the goal reached at any sub-step, the end step (the first hit or goal sub-step, else T − 1),
    the first goal sub-step (0 if none), and the nearest obstacle's pole-equivalent distance and
    the goal's distance at the end step (m)."""

    nearest_m: FloatArray
    collision: NDArray[np.bool_]
    reached_goal: NDArray[np.bool_]
    end_step: NDArray[np.intp]
    first_goal_step: NDArray[np.intp]
    distance_to_obstacle_m: FloatArray
    distance_to_goal_m: FloatArray


def judge_period(
    pos_ne: FloatArray,
    t_s: FloatArray,
    discs: PackedDiscs,
    goal_ne: FloatArray,
    r_pole_m: float,
    half_beam_m: float,
    goal_radius_m: float,
    backend: Literal["auto", "compiled", "numpy"] = "auto",
) -> PeriodJudgement:
    """Judge N boats' decision period (:class:`PeriodJudgement`): positions ``pos_ne`` (N, T, ≥ 2)
    at episode times ``t_s`` (N, T) s among ``discs``, goals ``goal_ne`` (N, 2) m. The NumPy
    path is :func:`nearest_and_hits` and array operations on its (N, T) results (the
    reference); the compiled one does the same per boat in one C call (OpenMP over boats), with
    no (N, T) arrays; backends as :func:`nearest_and_hits`."""
    n_discs = discs.centres_ne.shape[1] + discs.vessel_p0_ne.shape[1]
    kernel = load_judge_kernel() if backend != "numpy" else None
    if kernel is None or n_discs > MAX_KERNEL_DISCS:
        if backend == "compiled":
            raise ValueError(
                "backend='compiled': the judge kernel did not build (no C compiler?) or the "
                f"scene has more than {MAX_KERNEL_DISCS} discs per boat ({n_discs})"
            )
        return _judge_numpy(pos_ne, t_s, discs, goal_ne, r_pole_m, half_beam_m, goal_radius_m,
                            backend)  # fmt: skip
    pos = np.asarray(pos_ne, dtype=np.float64)
    if pos.strides[2] != 8 or pos.strides[0] % 8 or pos.strides[1] % 8:
        pos = np.ascontiguousarray(pos)
    n, steps = pos.shape[0], pos.shape[1]
    t = np.ascontiguousarray(np.broadcast_to(t_s, (n, steps)), dtype=np.float64)
    goal = np.ascontiguousarray(goal_ne, dtype=np.float64)
    arrays = _kernel_arrays(discs)
    nearest, d_obstacle, d_goal = np.empty(n), np.empty(n), np.empty(n)
    collision, reached = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.bool_)
    end, first = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    kernel(
        n, steps, arrays[0].shape[1], arrays[3].shape[1], r_pole_m, half_beam_m, goal_radius_m,
        pos.ctypes.data, pos.strides[0] // 8, pos.strides[1] // 8, t.ctypes.data,
        *(a.ctypes.data for a in arrays), goal.ctypes.data, nearest.ctypes.data,
        collision.ctypes.data, reached.ctypes.data, end.ctypes.data, first.ctypes.data,
        d_obstacle.ctypes.data, d_goal.ctypes.data,
    )  # fmt: skip
    return PeriodJudgement(
        nearest, collision, reached, end.astype(np.intp), first.astype(np.intp), d_obstacle,
        d_goal,
    )  # fmt: skip


def _judge_numpy(
    pos: FloatArray, t_s: FloatArray, discs: PackedDiscs, goal_ne: FloatArray, r_pole_m: float,
    half_beam_m: float, goal_radius_m: float, backend: Literal["auto", "compiled", "numpy"],
) -> PeriodJudgement:  # fmt: skip
    """:func:`judge_period` on (N, T) arrays (the reference; distances by ``backend``)."""
    d_min_t, hit = nearest_and_hits(pos, t_s, discs, r_pole_m, half_beam_m, backend)
    steps = d_min_t.shape[1]
    dx, dy = pos[:, :, 0] - goal_ne[:, 0:1], pos[:, :, 1] - goal_ne[:, 1:2]
    inside = within_radius(dx, dy, goal_radius_m)
    collision: NDArray[np.bool_] = np.any(hit, axis=1)
    reached: NDArray[np.bool_] = np.any(inside, axis=1)
    end = np.where(reached | collision, np.argmax(hit | inside, axis=1), steps - 1)
    upto = np.where(np.arange(steps) > end[:, None], np.inf, d_min_t)
    rows = np.arange(len(end))
    return PeriodJudgement(
        upto.min(axis=1), collision, reached, end, np.argmax(inside, axis=1),
        d_min_t[rows, end], np.hypot(dx[rows, end], dy[rows, end]),
    )  # fmt: skip


def _kernel_arrays(discs: PackedDiscs) -> list[NDArray[np.generic]]:
    """``discs``' arrays as the kernels take them (C-contiguous float64 / bool)."""
    return [
        np.ascontiguousarray(a, dtype=dt)
        for a, dt in (
            (discs.centres_ne, np.float64), (discs.radii_m, np.float64),
            (discs.static_ok, np.bool_), (discs.vessel_p0_ne, np.float64),
            (discs.vessel_course_rad, np.float64), (discs.vessel_speed_mps, np.float64),
            (discs.vessel_turn_radps, np.float64), (discs.vessel_radius_m, np.float64),
            (discs.vessel_ok, np.bool_),
        )
    ]  # fmt: skip
