"""The compiled candidate-by-obstacle terms of the ``vo`` helmsman: one C call for N boats.

:func:`baselines.velocity_obstacle.vo_course` scores C candidate courses against K obstacle
slots per boat; its NumPy path builds (N, C, S, K, 2) arrays for the turn's S arc samples, which
is most of its time (reactive targets, issue 41: 1,024 target rows a decision at N = 256 boats).
This kernel does per boat, candidate and *valid* slot what that path does with arrays, and
skips empty slots (their terms are zero there too):

- arc: the sample positions ``radius (sin α − sin χ, cos χ − cos α)``, ``α = χ + Δ f_s``; the
  obstacle at ``p + v t_s``; a hit where ``gap < R + arc_margin`` and ``gap < gap_0``, the
  first such sample's time;
- cone from the arc's end: ``t* = clip(w·rel / max(w·w, 1e-9), 0, τ)``, ``d_cpa = |rel − w t*|``,
  in the cone where ``w·rel > 0`` and ``d_cpa < R_safe``;
- outputs: per candidate (N, C) the count of COLREG flags ``give_way ∧ starboard pass ∧
  w·p > 0`` over the slots; per slot (N, C, K) the VO term ``[θ ∈ VO] (1.1 − min(t_hit, τ)/τ)``
  and on request ``[θ ∈ VO]``, the starboard-pass flag and the shortfall
  ``max(in_cone (1 − d_cpa/R_safe), hit_arc (1 − min_s gap / R_arc))``.

The VO terms' sum over slots, the cost and the argmin stay in NumPy, so the result is the NumPy
path's bit for bit (tested): the arithmetic is its operation for operation (double, no FMA
contraction), with transcendentals only where libm's equal NumPy's (``sin``, ``cos``, ``hypot``; the
``arctan2`` of the course comes from NumPy). Tests that cannot change a result are skipped:
an arc sample farther than ``(R + arc_margin)·(1 + 1e-9)`` by its squared distance, an obstacle
farther than ``R_arc + (U + |v|) t_turn + 1 m`` from the boat (no sample of the turn can come
nearer), a cone with ``w·rel ≤ 0``; without the shortfall output. Built on first use
(:func:`usvsim.common.cbuild.load_function`); None where no build succeeds (NumPy path then).
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable

from usvsim.common.cbuild import load_function

__all__ = ["VO_SOURCE", "load_vo_kernel"]

VO_SOURCE = r"""
#include <math.h>
#include <stdint.h>
#include <string.h>

#define MAX_SAMPLES 16

/* n boats, nc candidates, k slots, ns arc samples. frac (ns); cth, sth (nc): the candidates'
   cos, sin; speed, course, sin_c0, cos_c0 (n); turn, t_turn, radius (n, nc); p, v (n, k, 2);
   valid, give_way (n, k); r_safe, r_arc (n, k). Outputs: colreg (n, nc) the count of COLREG
   flags; (n, nc, k): term; in_vo,
   starboard, shortfall where not NULL (shortfall: every test exact, nothing skipped). */
void usv_vo_terms(int n, int nc, int k, int ns, const double* frac, const double* cth,
                  const double* sth, const double* speed, const double* course,
                  const double* sin_c0, const double* cos_c0, const double* turn,
                  const double* t_turn, const double* radius, const double* p, const double* v,
                  const uint8_t* valid, const uint8_t* give_way, const double* r_safe,
                  const double* r_arc, double horizon, double* term, int64_t* colreg,
                  uint8_t* in_vo_out, uint8_t* starboard_out, double* shortfall) {
  const int exact = shortfall != NULL;
  for (int b = 0; b < n; ++b) {
    const long row = (long)b * nc * k;
    memset(term + row, 0, sizeof(double) * nc * k);
    memset(colreg + (long)b * nc, 0, sizeof(int64_t) * nc);
    if (in_vo_out) memset(in_vo_out + row, 0, (size_t)nc * k);
    if (starboard_out) memset(starboard_out + row, 0, (size_t)nc * k);
    if (shortfall) memset(shortfall + row, 0, sizeof(double) * nc * k);
    int any = 0;
    for (int j = 0; j < k; ++j) any |= valid[(long)b * k + j] != 0;
    if (!any && !starboard_out) continue;
    const double u = speed[b], chi = course[b], s0 = sin_c0[b], c0 = cos_c0[b];
    for (int c = 0; c < nc; ++c) {
      const long bc = (long)b * nc + c;
      const double tt = t_turn[bc], rad = radius[bc], dturn = turn[bc];
      const double wx0 = u * cth[c], wy0 = u * sth[c];  /* the candidate's velocity */
      double ax[MAX_SAMPLES], ay[MAX_SAMPLES], ta[MAX_SAMPLES];
      int have_arc = 0;
      /* the arc's end: always needed by the cone */
      const double a_end = chi + dturn * frac[ns - 1];
      ax[ns - 1] = rad * (sin(a_end) - s0);
      ay[ns - 1] = rad * (c0 - cos(a_end));
      for (int s = 0; s < ns; ++s) ta[s] = tt * frac[s];
      for (int j = 0; j < k; ++j) {
        const long bj = (long)b * k + j, o = bc * k + j;
        const double px = p[2 * bj], py = p[2 * bj + 1], vx = v[2 * bj], vy = v[2 * bj + 1];
        const double wx = wx0 - vx, wy = wy0 - vy;
        const int stbd = (wx * py - wy * px) > 0;
        if (starboard_out) starboard_out[o] = (uint8_t)stbd;
        if (!valid[bj]) continue;
        const double ra = r_arc[bj], rs = r_safe[bj];
        /* the turn: first sample nearer than R_arc and nearer than at its start */
        int hit_arc = 0, first = 0;
        double min_gap = INFINITY;
        const double reach = ra + (u + sqrt(vx * vx + vy * vy)) * tt + 1.0;
        if (exact || px * px + py * py <= reach * reach) {
          if (!have_arc) {
            for (int s = 0; s < ns - 1; ++s) {
              const double a = chi + dturn * frac[s];
              ax[s] = rad * (sin(a) - s0);
              ay[s] = rad * (c0 - cos(a));
            }
            have_arc = 1;
          }
          const double g0 = hypot((px + vx * ta[0]) - ax[0], (py + vy * ta[0]) - ay[0]);
          const double ra2 = ra * ra * (1.0 + 1e-9);
          min_gap = g0;
          for (int s = 1; s < ns; ++s) {
            const double dx = (px + vx * ta[s]) - ax[s], dy = (py + vy * ta[s]) - ay[s];
            if (!exact && dx * dx + dy * dy > ra2) continue;
            const double g = hypot(dx, dy);
            if (g < min_gap) min_gap = g;
            if (!hit_arc && g < ra && g < g0) { hit_arc = 1; first = s; }
          }
        }
        /* the cone from the arc's end */
        const double relx = (px + vx * ta[ns - 1]) - ax[ns - 1];
        const double rely = (py + vy * ta[ns - 1]) - ay[ns - 1];
        const double pw = wx * relx + wy * rely;
        double ww = wx * wx + wy * wy;
        if (ww < 1e-9) ww = 1e-9;
        double t_star = pw / ww;
        if (t_star < 0.0) t_star = 0.0;
        if (t_star > horizon) t_star = horizon;
        int in_cone = 0;
        double d_cpa = INFINITY;
        if (pw > 0 || exact) {
          const double mx = relx - wx * t_star, my = rely - wy * t_star;
          if (exact || mx * mx + my * my <= rs * rs * (1.0 + 1e-9)) d_cpa = hypot(mx, my);
          in_cone = pw > 0 && d_cpa < rs;
        }
        const int in_vo = hit_arc || in_cone;
        if (in_vo) {
          double t_hit = hit_arc ? ta[first] : tt + t_star;
          if (t_hit > horizon) t_hit = horizon;
          term[o] = 1.1 - t_hit / horizon;
        }
        if (in_vo_out) in_vo_out[o] = (uint8_t)in_vo;
        colreg[bc] += give_way[bj] && stbd && (wx * px + wy * py) > 0;
        if (shortfall) {
          const double sc = in_cone ? 1.0 - d_cpa / rs : 0.0;
          const double sa = hit_arc ? 1.0 - min_gap / ra : 0.0;
          shortfall[o] = sc >= sa ? sc : sa;
        }
      }
    }
  }
}
"""

MAX_ARC_SAMPLES = 16  # the kernel's stack arrays (``vo`` samples 6)


@functools.cache
def load_vo_kernel() -> Callable[..., None] | None:
    """The compiled ``usv_vo_terms`` (argument types set), or None where no build succeeds
    (built and loaded once per process)."""
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    fn: Callable[..., None] | None = load_function(
        VO_SOURCE,
        "usv_vo_terms",
        [int_, int_, int_, int_, *[ptr] * 16, ctypes.c_double, *[ptr] * 5],
        prefix="vo",
    )
    return fn
