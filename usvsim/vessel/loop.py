"""The heading loop analysed on the full linearisation: margins, poles, Bode, rate limit.

The PID of :mod:`usvsim.vessel.autopilot` acts on the measured heading and yaw rate,
τ_N = -(K_p + K_i/s) ψ - K_d r (feed-forward and reference model outside the loop). The loop is
broken at the commanded yaw moment; in series (Fossen 2021, §15.3, with the actuator and sampling
of a digital autopilot):

===========================  ======================================================
block                        model
===========================  ======================================================
sampling (10 Hz ZOH)         half-sample delay e^{-s dt/2}, 2nd-order Padé
steering actuator            1 / (1 + T_δ s), T_δ = ``lag_s[1]``
hull                         sway–yaw [v, r] linearised at cruise with the actuator's own
                             force direction (:func:`usvsim.vessel.model.linearize_steering`)
heading                      ψ = r / s
===========================  ======================================================

L(s) = [(K_p + K_i/s)/s + K_d] G_r(s) e^{-s dt/2} / (1 + T_δ s), where G_r is r per yaw moment.
The closed loop 1 / (1 + L) has the poles reported. The slew-rate limit is not linear: below
the nozzle amplitude R / ω at frequency ω it is inactive; above, its describing function N(ρ),
ρ = R / (A ω), lowers the gain and adds phase lag (computed numerically from the first harmonic
of a rate-limited sine, Gelb & Vander Velde 1968, ch. 2). :func:`analyse_loop` reports the phase
margin with it at a stated nozzle amplitude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usvsim.vessel.model import linearize_steering
from usvsim.vessel.vessels import VesselParams

__all__ = [
    "LoopAnalysis",
    "analyse_loop",
    "full_loop_transfer",
    "gain_margin_db",
    "rate_limiter_df",
]


def full_loop_transfer(
    vessel: VesselParams, speed_mps: float, Kp: float, Kd: float, Ki: float, dt_s: float
) -> Any:
    """Open loop L(s) (python-control TransferFunction) of the module docstring."""
    import control

    A, b = linearize_steering(vessel, speed_mps)
    G_r = control.ss2tf(control.ss(A, b, np.array([[0.0, 1.0]]), np.zeros((1, 1))))
    s = control.tf("s")
    lag = max(vessel.actuation.lag_s[1], 1e-6)
    num, den = control.pade(dt_s / 2, 2)
    pid = (Kp + Ki / s) / s + Kd
    return control.minreal(pid * G_r / (1 + lag * s) * control.tf(num, den), verbose=False)


def rate_limiter_df(rho: NDArray[np.float64] | float) -> NDArray[np.complex128]:
    """Describing function N(ρ) of a rate limiter, ρ = R / (A ω) (R rate, A amplitude).

    N = 1 for ρ ≥ 1. Computed from the steady state of a discrete rate limiter driven by sin θ with
    slew rate ρ per radian of phase, first harmonic over the last of five periods.
    """
    rho_arr = np.atleast_1d(np.asarray(rho, dtype=float))
    n, periods = 1024, 5
    theta = np.linspace(0.0, periods * 2 * math.pi, periods * n, endpoint=False)
    h = theta[1] - theta[0]
    y = np.zeros(rho_arr.shape)
    out = np.empty((theta.size, rho_arr.size))
    for k, th in enumerate(theta):  # vectorised over ρ; the loop is over phase samples
        y = y + np.clip(np.sin(th) - y, -rho_arr * h, rho_arr * h)
        out[k] = y
    last = out[-n:]
    ph = theta[-n:]
    a1 = 2 / n * (last * np.sin(ph)[:, None]).sum(axis=0)
    b1 = 2 / n * (last * np.cos(ph)[:, None]).sum(axis=0)
    df = a1 + 1j * b1
    return np.where(rho_arr >= 1.0, 1.0 + 0j, df)


def _stable_with_gain(num: NDArray[np.float64], den: NDArray[np.float64], k: float) -> bool:
    n = np.zeros(max(num.size, den.size))
    n[-num.size :] += k * num
    n[-den.size :] += den
    return bool(np.all(np.roots(np.trim_zeros(n, "f")).real < 0))


def gain_margin_db(loop: Any) -> float:
    """Gain margin (dB) of L: how far the loop gain k may move from 1 before 1 + k L loses
    stability, the smaller of raising it and (for an open-loop unstable hull, which a too-low gain
    destabilises) lowering it. -inf when the closed loop at k = 1 is unstable; inf when no gain
    in [1e-4, 1e4] destabilises it. Found by scanning k and bisecting the boundary.
    """
    num = np.asarray(loop.num[0][0], dtype=float)
    den = np.asarray(loop.den[0][0], dtype=float)
    if not _stable_with_gain(num, den, 1.0):
        return -math.inf
    margins = []
    for direction in (1.0, -1.0):  # raise, then lower the gain
        ok, bad = 0.0, math.nan
        for e in np.linspace(0.05, 4.0, 80):  # log10 of the factor
            if not _stable_with_gain(num, den, 10.0 ** (direction * e)):
                bad = e
                break
            ok = e
        if math.isnan(bad):
            margins.append(math.inf)
            continue
        for _ in range(30):
            mid = 0.5 * (ok + bad)
            ok, bad = (
                (mid, bad) if _stable_with_gain(num, den, 10.0 ** (direction * mid)) else (ok, mid)
            )
        margins.append(20.0 * ok)
    return min(margins)


@dataclass(frozen=True)
class LoopAnalysis:
    """Margins and poles of the full linear heading loop (see module docstring)."""

    gain_margin_db: float  # dB (inf: phase never crosses -180°)
    phase_margin_deg: float  # deg
    gain_crossover_rad_s: float  # rad/s, where |L| = 1
    phase_crossover_rad_s: float  # rad/s, where arg L = -180°
    poles: NDArray[np.complex128]  # closed-loop poles (1/s)
    rate_linear_amplitude_deg: float  # deg, nozzle amplitude at crossover the slew limit passes
    rate_check_amplitude_deg: float  # deg, nozzle amplitude of the describing-function check
    phase_margin_rate_limited_deg: float  # deg, phase margin with the limiter at that amplitude

    @property
    def stable(self) -> bool:
        return bool(np.all(self.poles.real < 0))


def analyse_loop(
    vessel: VesselParams,
    speed_mps: float,
    Kp: float,
    Kd: float,
    Ki: float,
    dt_s: float = 0.1,
    nozzle_amplitude_deg: float = 20.0,
) -> LoopAnalysis:
    """Margins and poles of :func:`full_loop_transfer`, and the slew-rate-limited phase margin.

    The rate-limited margin: on a frequency grid, |N(ρ(ω)) L(jω)| = 1 with ρ = R / (A ω), A the
    steering-actuator amplitude ``nozzle_amplitude_deg`` (deg; for force actuators the same
    fraction of the limit as that angle of 30°); the phase margin is 180° + arg(N L) there.
    """
    import control

    loop = full_loop_transfer(vessel, speed_mps, Kp, Kd, Ki, dt_s)
    _, pm, wcg, wcp = control.margin(loop)
    poles = np.sort_complex(np.asarray(control.poles(control.feedback(loop, 1)), dtype=complex))
    gm_db = gain_margin_db(loop)
    act = vessel.actuation
    rate = act.a2_rate_max
    if act.kind == "waterjet":
        amp = math.radians(nozzle_amplitude_deg)
    else:
        amp = nozzle_amplitude_deg / 30.0 * act.a2_max
    omega = np.logspace(-2, 2, 2000)
    L = np.asarray(loop(1j * omega), dtype=complex).ravel()
    if math.isfinite(rate):
        NL = rate_limiter_df(rate / (amp * omega)) * L
        unit = 1.0 if act.kind == "waterjet" else act.a2_max / math.radians(30.0)
        lin_amp = math.degrees(rate / (float(wcp) if np.isfinite(wcp) else 1.0) / unit)
    else:
        NL = L
        lin_amp = math.inf
    crossing = np.nonzero(np.diff(np.sign(np.abs(NL) - 1.0)) < 0)[0]
    if crossing.size:
        k = int(crossing[0])
        pm_rl = 180.0 + math.degrees(float(np.angle(NL[k])))
        if pm_rl > 180.0:
            pm_rl -= 360.0
    else:
        pm_rl = math.inf
    return LoopAnalysis(
        gain_margin_db=gm_db,
        phase_margin_deg=float(pm),
        gain_crossover_rad_s=float(wcp),
        phase_crossover_rad_s=float(wcg),
        poles=poles,
        rate_linear_amplitude_deg=lin_amp,
        rate_check_amplitude_deg=nozzle_amplitude_deg,
        phase_margin_rate_limited_deg=pm_rl,
    )
