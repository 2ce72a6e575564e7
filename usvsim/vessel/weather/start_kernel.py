"""A weather episode's start in C: every boat's wave pieces in one call.

:func:`usvsim.vessel.weather_plant.weather_inputs` turns each starting boat's sea into its
episode rows: the wave motion filter at the encounter frequency
(:func:`usvsim.vessel.weather.waves.encounter_response`), its exact discrete model
(:func:`~usvsim.vessel.weather.waves.wave_motion_discrete`), the drift pressure
(:func:`~usvsim.vessel.weather.waves.drift_pressure`, its spline), the wave filter's steady-state
gains (:func:`usvsim.vessel.weather.observer.observer_gains`) and the PID's wave design
(:func:`usvsim.vessel.autopilot.wave_mode_gain_changes`). In NumPy that is ~120 array calls
whose overhead, not their arithmetic, is the cost at the 1-4 boats an environment step starts
(183 μs a start against 54 μs here; `OpenWater-v0` at N = 256 starts some boats at nearly every
step, of 2.7-3.4 ms calm: docs/guide/weather.md, *Cost*). This is the same arithmetic boat by
boat in C, the Riccati equation by the doubling of
:mod:`usvsim.vessel.weather.riccati_kernel` (shared source): the NumPy functions stay the
definition, and this twin is tested equal to them to rounding
(``tests/usvsim/vessel/test_weather_start_kernel.py``).

Built with :func:`usvsim.common.cbuild.load_function`; where no C compiler is found,
:func:`wave_start` returns None and the NumPy path runs.
"""

from __future__ import annotations

import ctypes
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.common.cbuild import load_function
from usvsim.vessel.autopilot import (
    WAVE_BANDWIDTH_RATIO,
    WAVE_DESIGN_MIN_HS_M,
    AutopilotDesign,
    natural_per_bandwidth,
)
from usvsim.vessel.weather.observer import ObserverNoise, measurement_information
from usvsim.vessel.weather.riccati_kernel import HELPERS
from usvsim.vessel.weather.waves import (
    TP_RANGE_S,
    G,
    drift_pressure_spline,
    jonswap_peak_factor,
)

__all__ = ["WaveStart", "compiled_wave_start", "wave_start"]

FloatArray = NDArray[np.float64]

#: Values per boat the kernel writes, in order.
_OUT = (
    ("omega0", 1),  # rad/s, the encounter frequency ω_e
    ("damping", 1),  # -, λ
    ("gain", 1),  # K_w
    ("phi", 4),  # Φ row-major
    ("chol", 3),  # L₀₀, L₁₀, L₁₁
    ("drift", 1),  # N/m, drift pressure
    ("gains", 10),  # the wave filter's L (5 × 2) row-major
    ("pid", 3),  # ΔK_p, ΔK_d, ΔK_i
)
_WIDTH = sum(k for _, k in _OUT)

_ENTRY = r"""
#define NOUT 24
/* scipy's PPoly: the interval i with x[i] <= t < x[i+1] (the last one for t = x[m-1]) and
   c[3][i] + c[2][i] s + c[1][i] s^2 + c[0][i] s^3, s = t - x[i], summed in scipy's order */
static double spline(int m, const double* x, const double* c, double t) {
  int lo = 0, hi = m - 2;
  while (lo < hi) {
    int mid = (lo + hi + 1) / 2;
    if (x[mid] <= t) lo = mid; else hi = mid - 1;
  }
  double s = t - x[lo], res = 0.0, z = 1.0;
  for (int kp = 0; kp < 4; ++kp) {
    res = res + c[(3 - kp) * (m - 1) + lo] * z * 1.0;
    if (kp < 3) z *= s;
  }
  return res;
}
/* prm: 0 dt (s), 1 g (m/s²), 2 JONSWAP peak factor S(ω_p) / (H_s² T_p), 3 ω_e's upper clip
   (rad/s), 4 filter on (0/1), 5 yaw gain, 6 m (kg m²), 7 d (N m s/rad), 8 compass variance,
   9 gyro variance, 10 ψ, 11 r, 12 bias process variances, 13 tol, 14 max_iter, 15 PID wave
   design on (0/1), 16 ω_n, 17 ζ, 18 ω_n per unit bandwidth, 19 bandwidth ratio, 20 lowest H_s
   of the wave design (m), 21-23 the calm K_p, K_d, K_i, 24 m, 25 d of the PID's design model
   (as 6, 7 for the filter's). g0 (25): Hᵀ R⁻¹ H. status[b]: 0, -1 / -2
   a Riccati failure (riccati_kernel), -3 a damping λ >= 1 */
void usv_wave_start(int n, const double* hs, const double* tp, const double* rel,
                    const double* speed, const double* prm, const double* g0, int m,
                    const double* knots, const double* coef, double* out, int* status) {
  const double PI = 3.14159265358979323846;
  double dt = prm[0], g = prm[1];
  for (int b = 0; b < n; ++b) {
    double* o = out + (long)b * NOUT;
    for (int k = 0; k < NOUT; ++k) o[k] = 0.0;
    status[b] = 0;
    /* waves.encounter_response */
    int calm = hs[b] <= 0.0;
    double tpb = calm ? 10.0 : tp[b];
    double wp = 2.0 * PI / tpb;
    double we = fabs(wp - wp * wp * speed[b] * cos(rel[b]) / g);
    we = fmin(fmax(we, 0.1), prm[3]);
    double h2 = hs[b] * hs[b];
    double sigma2 = prm[2] * h2 * tpb;
    double m0 = h2 / 16.0;
    double lam = calm ? 0.1 : m0 / (PI * wp * sigma2);
    double sig_e = calm ? 0.0 : sqrt(m0 / (PI * lam * we));
    double kw = 2.0 * lam * we * sig_e;
    o[0] = we; o[1] = lam; o[2] = kw;
    if (lam >= 1.0) { status[b] = -3; continue; }
    /* waves.wave_motion_discrete: Φ, then L Lᵀ = P∞ − Φ P∞ Φᵀ with P∞ = diag(v0, v1) */
    double wd = we * sqrt(1.0 - lam * lam);
    double e = exp(-lam * we * dt);
    double c = cos(wd * dt), s = sin(wd * dt);
    double phi[4] = {e * (c + lam * we / wd * s), e * s / wd, -e * (we * we) / wd * s,
                     e * (c - lam * we / wd * s)};
    double k2 = PI * (kw * kw) / (4.0 * lam * we);
    double v0 = k2 / (we * we), v1 = k2;
    double pp00 = phi[0] * v0 * phi[0] + phi[1] * v1 * phi[1];
    double pp10 = phi[2] * v0 * phi[0] + phi[3] * v1 * phi[1];
    double pp11 = phi[2] * v0 * phi[2] + phi[3] * v1 * phi[3];
    double l00 = sqrt(fmax(v0 - pp00, 0.0));
    double l10 = l00 > 0.0 ? -pp10 / l00 : 0.0;
    double l11 = sqrt(fmax(v1 - pp11 - l10 * l10, 0.0));
    for (int k = 0; k < 4; ++k) o[3 + k] = phi[k];
    o[7] = l00; o[8] = l10; o[9] = l11;
    /* waves.drift_pressure (T_p inside the spline's range: the caller checks) */
    o[10] = calm ? 0.0 : h2 * exp(spline(m, knots, coef, log(tpb)));
    if (calm || prm[4] == 0.0) continue;
    /* observer.observer_gains */
    double w3 = we * we * we;
    double scale = prm[5] * w3 / g * sin(2.0 * rel[b]);
    double c2 = scale * scale;
    double a_c[25] = {0.0}, q[25] = {0.0}, p[25];
    double a[25] = {0.0};
    a[0] = phi[0]; a[1] = phi[1]; a[5] = phi[2]; a[6] = phi[3];
    a[12] = 1.0; a[13] = dt;
    a[18] = 1.0 - dt * prm[7] / prm[6]; a[19] = dt / prm[6];
    a[24] = 1.0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) a_c[i * 5 + j] = a[j * 5 + i];
    q[0] = c2 * (l00 * l00) + 1e-12;
    q[1] = q[5] = c2 * (l00 * l10);
    q[6] = c2 * (l10 * l10 + l11 * l11) + 1e-12;
    q[12] = prm[10]; q[18] = prm[11]; q[24] = prm[12];
    status[b] = doubling(5, a_c, g0, q, prm[13], (int)prm[14], p);
    if (status[b] < 0) continue;
    status[b] = 0;
    double ph[10];
    for (int i = 0; i < 5; ++i) {
      ph[2 * i] = p[i * 5 + 0] + p[i * 5 + 2];
      ph[2 * i + 1] = p[i * 5 + 1] + p[i * 5 + 3];
    }
    double s00 = ph[0] + ph[4] + prm[8], s01 = ph[1] + ph[5];
    double s10 = ph[2] + ph[6], s11 = ph[3] + ph[7] + prm[9];
    double det = s00 * s11 - s01 * s10;
    for (int i = 0; i < 5; ++i) {
      o[11 + 2 * i] = (ph[2 * i] * s11 - ph[2 * i + 1] * s10) / det;
      o[12 + 2 * i] = (ph[2 * i + 1] * s00 - ph[2 * i] * s01) / det;
    }
    /* autopilot.wave_mode_gain_changes */
    if (prm[15] == 0.0) continue;
    double wn = fmin(prm[16], prm[19] * we * prm[18]);
    if (hs[b] >= prm[20] && wn < prm[16]) {
      double kp = prm[24] * (wn * wn);
      o[21] = kp - prm[21];
      o[22] = 2.0 * prm[17] * wn * prm[24] - prm[25] - prm[22];
      o[23] = wn / 10.0 * kp - prm[23];
    }
  }
}
"""


@dataclass(frozen=True)
class WaveStart:
    """Per boat (N,) or (N, k): the wave response (ω_e rad/s, λ, K_w), Φ (N, 2, 2), L (N, 2, 2),
    drift pressure (N/m), the wave filter's gains (N, 10; zero where off) and the PID's wave
    design changes (N, 3; zero where it keeps the calm gains)."""

    omega0: FloatArray
    damping: FloatArray
    gain: FloatArray
    phi: FloatArray
    chol: FloatArray
    drift: FloatArray
    gains: FloatArray
    pid: FloatArray


@functools.lru_cache(maxsize=1)
def _kernel() -> Any | None:
    ptr, int_ = ctypes.c_void_p, ctypes.c_int
    argtypes = [int_, ptr, ptr, ptr, ptr, ptr, ptr, int_, ptr, ptr, ptr, ptr]
    return load_function(HELPERS + _ENTRY, "usv_wave_start", argtypes, prefix="wavestart")


def wave_start(
    hs_m: FloatArray,
    tp_s: FloatArray,
    relative_dir_rad: FloatArray,
    speed_mps: FloatArray,
    scalars: FloatArray,
    g0: FloatArray,
    knots: FloatArray,
    coef: FloatArray,
) -> WaveStart | None:
    """The wave pieces of N boats (module docstring): ``hs_m``, ``tp_s``, ``relative_dir_rad``
    (waves' direction minus heading) and ``speed_mps`` (N,) each; ``scalars`` the kernel's 26
    parameters (``prm`` in the C source; :func:`usvsim.vessel.weather_plant.weather_inputs`
    packs them); ``g0`` (5, 5) Hᵀ R⁻¹ H; ``knots`` (M,) and ``coef`` (4, M - 1) the drift
    pressure spline. None where the kernel does not build. Raises ``RuntimeError`` where a
    Riccati equation fails and ``ValueError`` for a damping λ >= 1."""
    kernel = _kernel()
    if kernel is None:
        return None
    n = hs_m.size
    cols = [np.ascontiguousarray(v, dtype=np.float64) for v in (hs_m, tp_s, relative_dir_rad)]
    speed = np.ascontiguousarray(np.broadcast_to(speed_mps, (n,)), dtype=np.float64)
    prm = np.ascontiguousarray(scalars, dtype=np.float64)
    g0c = np.ascontiguousarray(g0, dtype=np.float64)
    kn = np.ascontiguousarray(knots, dtype=np.float64)
    cf = np.ascontiguousarray(coef, dtype=np.float64)
    if prm.shape != (26,) or g0c.shape != (5, 5) or cf.shape != (4, kn.size - 1):
        raise ValueError("wave_start: need 26 scalars, g0 (5, 5) and coef (4, M - 1)")
    out = np.empty((n, _WIDTH))
    status = np.empty(n, dtype=np.int32)
    kernel(n, *(v.ctypes.data for v in cols), speed.ctypes.data, prm.ctypes.data,
           g0c.ctypes.data, kn.size, kn.ctypes.data, cf.ctypes.data, out.ctypes.data,
           status.ctypes.data)  # fmt: skip
    if n and status.min() < 0:
        if status.min() == -3:
            raise ValueError("wave response damping λ must be < 1 (a peaked spectrum)")
        raise RuntimeError(f"Riccati doubling did not converge in {int(prm[14])} steps")
    parts, start = {}, 0
    for name, width in _OUT:
        parts[name] = out[:, start] if width == 1 else out[:, start : start + width]
        start += width
    phi = parts["phi"].reshape(n, 2, 2)
    chol = np.zeros((n, 2, 2))
    chol[:, 0, 0], chol[:, 1, 0], chol[:, 1, 1] = parts["chol"].T
    return WaveStart(
        parts["omega0"], parts["damping"], parts["gain"], phi, chol, parts["drift"],
        parts["gains"], parts["pid"],
    )  # fmt: skip


def compiled_wave_start(
    hs_m: FloatArray,
    tp_s: FloatArray,
    relative_dir_rad: FloatArray,
    speed_mps: FloatArray,
    dt_s: float,
    wave_filter: ObserverNoise | None,
    yaw_model: tuple[float, float],
    yaw_gain: float,
    autopilot: AutopilotDesign | None,
) -> WaveStart | None:
    """:func:`usvsim.vessel.weather_plant.weather_inputs`' wave pieces (same arguments) from the
    kernel, its scalars packed here; None where it does not build or a boat in waves has a
    peak period outside the drift pressure spline's range (the NumPy path integrates those)."""
    tp_lo, tp_hi = TP_RANGE_S
    if (((tp_s < tp_lo) | (tp_s > tp_hi)) & (hs_m > 0)).any():
        return None
    noise = wave_filter or ObserverNoise()
    r, g0 = measurement_information(noise)
    pid = autopilot is not None and autopilot.config.kind == "pid"
    c = autopilot.config if autopilot is not None else None
    nomoto = autopilot.nomoto if autopilot is not None else None
    scalars = np.array([
        dt_s, G, jonswap_peak_factor(), 0.5 * math.pi / dt_s, wave_filter is not None, yaw_gain,
        *yaw_model, r[0, 0], r[1, 1], noise.psi_rad**2, (dt_s * noise.rate_rad_s2) ** 2,
        noise.bias_nm_per_step**2, 1e-15, 64,
        pid, c.omega_n if c else 0.0, c.zeta if c else 0.0,
        natural_per_bandwidth(c.zeta) if c else 0.0, WAVE_BANDWIDTH_RATIO, WAVE_DESIGN_MIN_HS_M,
        *((autopilot.Kp, autopilot.Kd, autopilot.Ki) if autopilot is not None else (0, 0, 0)),
        *((nomoto.m, nomoto.d) if nomoto is not None else (1.0, 0.0)),
    ], dtype=float)  # fmt: skip
    knots, coef = drift_pressure_spline()
    return wave_start(hs_m, tp_s, relative_dir_rad, speed_mps, scalars, g0, knots, coef)
