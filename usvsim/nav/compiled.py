"""The navigation filter as one CasADi Function: the twin of :class:`usvsim.nav.filter.Navigator`.

:func:`build_nav_step` writes :meth:`Navigator.step <usvsim.nav.filter.Navigator.step>` for one
boat with the same formulas in the same order, so the compiled, fused plant + filter step
(:mod:`usvsim.nav.navplant`) reproduces the NumPy filter to rounding (tested to 1e-12 per step
and 1e-9 over episodes in ``tests/test_navplant.py``). The NumPy :class:`Navigator` stays the
reference; it is tested equal to filterpy's ``KalmanFilter``. The sensor noise is drawn
beforehand, in the Navigator's draw order, and handed over per step by :func:`nav_noise_block`.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from usvsim.common.angles import ssa_casadi
from usvsim.nav.filter import Navigator
from usvsim.nav.kalman import FilterNoise, HeadingState, PositionState
from usvsim.nav.models import NavConfig
from usvsim.nav.sensors import period_steps
from usvsim.nav.start import first_fix, start_variances

__all__ = [
    "NAV_NOISE",
    "NAV_NS",
    "NAV_STATE_FIELDS",
    "build_nav_step",
    "export_nav_state",
    "import_nav_state",
    "nav_draws_per_step",
    "nav_noise_block",
    "started_nav_rows",
]

FloatArray = NDArray[np.float64]

#: Layout of the filter state of one boat (15 entries): :class:`PositionState` (complex numbers
#: as real, imaginary pairs), :class:`HeadingState`, the true gyro bias and the yaw-rate estimate.
NAV_STATE_FIELDS = (
    "p_n", "p_e", "w_n", "w_e", "L_pp", "L_pw_re", "L_pw_im", "L_ww",
    "psi", "b", "P_psi", "P_pb", "P_b", "gyro_bias", "yaw_rate",
)  # fmt: skip
NAV_NS = len(NAV_STATE_FIELDS)


def export_nav_state(nav: Navigator) -> FloatArray:
    """The navigator's filter states as an (N, 15) array (layout :data:`NAV_STATE_FIELDS`)."""
    x, h = nav.filter_state
    return np.column_stack([
        x.p.real, x.p.imag, x.w.real, x.w.imag, x.L_pp, x.L_pw.real, x.L_pw.imag, x.L_ww,
        h.psi, h.b, h.P_psi, h.P_pb, h.P_b, nav.true_gyro_bias, nav.estimate.yaw_rate,
    ])  # fmt: skip


def started_nav_rows(
    cfg: NavConfig, eta: FloatArray, nu: FloatArray, rng: np.random.Generator
) -> FloatArray:
    """The (k, 15) filter states (layout :data:`NAV_STATE_FIELDS`) that
    :meth:`Navigator.reset <usvsim.nav.filter.Navigator.reset>` gives k boats at true states
    ``eta``, ``nu`` (k, 3): the same first fix (:func:`usvsim.nav.filter.first_fix`) and
    starting covariances, so the same numbers (tested); for a caller that keeps the states
    packed (the batched environments), without the navigator's copies of every boat's arrays."""
    fix = first_fix(cfg, eta, nu, rng)
    out = np.zeros((eta.shape[0], NAV_NS))  # cross terms and the bias estimate start at 0
    out[:, 0:2] = fix.pos_ne
    out[:, 2], out[:, 3] = fix.vel_ne.real, fix.vel_ne.imag
    out[:, 4], out[:, 7], out[:, 10], out[:, 12] = start_variances(cfg)
    out[:, 8] = fix.heading_rad
    out[:, 13] = fix.gyro_bias_radps
    out[:, 14] = fix.gyro_radps
    return out


def import_nav_state(nav: Navigator, state: FloatArray) -> None:
    """Load (N, 15) filter states (from the compiled path) back into ``nav``."""
    s = np.asarray(state, dtype=np.float64)
    if s.shape != (nav.n_boats, NAV_NS):
        raise ValueError(f"nav state must have shape ({nav.n_boats}, {NAV_NS}), got {s.shape}")
    pos = PositionState(
        p=s[:, 0] + 1j * s[:, 1],
        w=s[:, 2] + 1j * s[:, 3],
        L_pp=s[:, 4].copy(),
        L_pw=s[:, 5] + 1j * s[:, 6],
        L_ww=s[:, 7].copy(),
    )
    head = HeadingState(*(s[:, j].copy() for j in range(8, 13)))
    nav.load_state(pos, head, yaw_rate=s[:, 14].copy(), true_gyro_bias=s[:, 13].copy())


#: Standard normals one plant step consumes, in :meth:`Navigator.step`'s draw order.
NAV_NOISE = ("gyro", "gps_n", "gps_e", "vel_n", "vel_e", "compass")


def nav_draws_per_step(cfg: NavConfig, step_index: int) -> tuple[bool, bool, int]:
    """(GNSS fires, compass fires, standard normals drawn) at plant step ``step_index``."""
    gps = step_index % period_steps(cfg.sensors.gps_rate_hz, cfg.dt_s) == 0
    compass = step_index % period_steps(cfg.sensors.compass_rate_hz, cfg.dt_s) == 0
    n = 1 + (2 + (2 if cfg.gnss_velocity else 0) if gps else 0) + (1 if compass else 0)
    return gps, compass, n


def nav_noise_block(
    cfg: NavConfig, first_step_index: int, n_steps: int, normals: FloatArray
) -> FloatArray:
    """Arrange per-boat standard normals, drawn in :meth:`Navigator.step` order, per step.

    ``normals`` (N, M) holds each boat's next M draws (M from :func:`nav_draws_per_step`);
    returns (N, n_steps, 8): the 6 :data:`NAV_NOISE` entries (0 where a sensor is silent) and
    the GNSS / compass firing flags.
    """
    n = normals.shape[0]
    out = np.zeros((n, n_steps, 8))
    col = 0
    for j in range(n_steps):  # a loop over the few steps of a period, never over boats
        gps, compass, _ = nav_draws_per_step(cfg, first_step_index + j)
        out[:, j, 0] = normals[:, col]
        col += 1
        if gps:
            out[:, j, 1:3] = normals[:, col : col + 2]
            col += 2
            if cfg.gnss_velocity:
                out[:, j, 3:5] = normals[:, col : col + 2]
                col += 2
            out[:, j, 6] = 1.0
        if compass:
            out[:, j, 5] = normals[:, col]
            col += 1
            out[:, j, 7] = 1.0
    if col != normals.shape[1]:
        raise ValueError(f"expected {col} normals per boat for these steps, got {normals.shape[1]}")
    return out


def build_nav_step(cfg: NavConfig) -> Any:
    """:meth:`Navigator.step` for one boat as a CasADi Function (same formulas, same order).

    ``nav_step(n[15], x[8], e[8]) -> n_next[15]``: ``n`` the filter state
    (:data:`NAV_STATE_FIELDS`), ``x`` the plant state after the step (true η, ν), ``e`` the
    standard normals and sensor flags of :func:`nav_noise_block`. Complex quantities of the
    circular position filter are carried as (real, imaginary) pairs.
    """
    s, dt = cfg.sensors, cfg.dt_s
    q = FilterNoise.from_config(cfg)  # the Navigator's numbers
    q_pp, q_pw, q_ww, q_psi, q_bias = q.q_pp, q.q_pw, q.q_ww, q.q_psi, q.q_bias
    r_gps, r_c, r_v = q.r_gps, q.r_compass, q.r_gps_vel
    n, x, e = ca.SX.sym("n", NAV_NS), ca.SX.sym("x", 8), ca.SX.sym("e", 8)

    def mul(a: tuple[Any, Any], b: tuple[Any, Any]) -> tuple[Any, Any]:
        return (a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])

    def conj(a: tuple[Any, Any]) -> tuple[Any, Any]:
        return (a[0], -a[1])

    def add(a: tuple[Any, Any], b: tuple[Any, Any]) -> tuple[Any, Any]:
        return (a[0] + b[0], a[1] + b[1])

    p, w = (n[0], n[1]), (n[2], n[3])
    L_pp, L_pw, L_ww = n[4], (n[5], n[6]), n[7]
    psi, b, P_psi, P_pb, P_b, bias = n[8], n[9], n[10], n[11], n[12], n[13]
    gyro = x[5] + bias + s.gyro_sigma_radps * e[0]
    omega = gyro - b
    # heading predict
    psi = psi + dt * omega
    P_pb_new = P_pb - dt * P_b
    P_psi = P_psi - dt * (P_pb + P_pb_new) + q_psi
    P_pb, P_b = P_pb_new, P_b + q_bias
    # position predict (coordinated turn at the gyro rate, or constant velocity)
    G: tuple[Any, Any]
    E: tuple[Any, Any]
    if cfg.turn_rate_aided:
        half = (0.5 * dt) * omega
        sinc = ca.if_else(half != 0, ca.sin(half) / half, 1.0)
        E_half = (ca.cos(half), ca.sin(half))
        G = (dt * sinc * E_half[0], dt * sinc * E_half[1])
        E = mul(E_half, E_half)
    else:
        G, E = (dt, 0.0), (1.0, 0.0)
    L_pw_G = add(L_pw, (G[0] * L_ww, G[1] * L_ww))
    L_pp = L_pp + mul(conj(G), add(L_pw, L_pw_G))[0] + q_pp
    L_pw = add(mul(L_pw_G, conj(E)), (q_pw, 0.0))
    L_ww = L_ww + q_ww
    p = add(p, mul(G, w))
    w = mul(E, w)
    gps_on, compass_on = e[6] > 0.5, e[7] > 0.5

    def pick(cond: Any, new: Any, old: Any) -> Any:
        return ca.if_else(cond, new, old)

    # GNSS position update
    S = L_pp + r_gps
    y = (x[0] + s.gps_sigma_m * e[1] - p[0], x[1] + s.gps_sigma_m * e[2] - p[1])
    k_p, k_w = L_pp / S, (L_pw[0] / S, -L_pw[1] / S)
    p_u = (p[0] + k_p * y[0], p[1] + k_p * y[1])
    w_u = add(w, mul(k_w, y))
    L_ww_u = L_ww - mul(k_w, L_pw)[0]
    L_pw_u = (L_pw[0] * (1 - k_p), L_pw[1] * (1 - k_p))
    L_pp_u = r_gps * k_p
    p = (pick(gps_on, p_u[0], p[0]), pick(gps_on, p_u[1], p[1]))
    w = (pick(gps_on, w_u[0], w[0]), pick(gps_on, w_u[1], w[1]))
    L_pp, L_ww = pick(gps_on, L_pp_u, L_pp), pick(gps_on, L_ww_u, L_ww)
    L_pw = (pick(gps_on, L_pw_u[0], L_pw[0]), pick(gps_on, L_pw_u[1], L_pw[1]))
    if cfg.gnss_velocity:  # GNSS velocity update, with each fix
        vel = mul((x[3], x[4]), (ca.cos(x[2]), ca.sin(x[2])))
        S = L_ww + r_v
        y = (vel[0] + s.gps_velocity_sigma_mps * e[3] - w[0],
             vel[1] + s.gps_velocity_sigma_mps * e[4] - w[1])  # fmt: skip
        k_p, k_w2 = (L_pw[0] / S, L_pw[1] / S), L_ww / S
        p_u = add(p, mul(k_p, y))
        w_u = (w[0] + k_w2 * y[0], w[1] + k_w2 * y[1])
        L_pp_u = L_pp - mul(k_p, conj(L_pw))[0]
        L_pw_u = (L_pw[0] * (1 - k_w2), L_pw[1] * (1 - k_w2))
        L_ww_u = r_v * k_w2
        p = (pick(gps_on, p_u[0], p[0]), pick(gps_on, p_u[1], p[1]))
        w = (pick(gps_on, w_u[0], w[0]), pick(gps_on, w_u[1], w[1]))
        L_pp, L_ww = pick(gps_on, L_pp_u, L_pp), pick(gps_on, L_ww_u, L_ww)
        L_pw = (pick(gps_on, L_pw_u[0], L_pw[0]), pick(gps_on, L_pw_u[1], L_pw[1]))
    # compass update (innovation wrapped)
    S = P_psi + r_c
    y_c = ssa_casadi(x[2] + s.compass_sigma_rad * e[5] - psi)
    k_psi, k_b = P_psi / S, P_pb / S
    psi_u, b_u = psi + k_psi * y_c, b + k_b * y_c
    P_b_u, P_pb_u, P_psi_u = P_b - k_b * P_pb, P_pb * (1.0 - k_psi), r_c * k_psi
    psi, b = pick(compass_on, psi_u, psi), pick(compass_on, b_u, b)
    P_b, P_pb = pick(compass_on, P_b_u, P_b), pick(compass_on, P_pb_u, P_pb)
    P_psi = pick(compass_on, P_psi_u, P_psi)
    out = ca.vertcat(p[0], p[1], w[0], w[1], L_pp, L_pw[0], L_pw[1], L_ww,
                     ssa_casadi(psi), b, P_psi, P_pb, P_b, bias, gyro - b)  # fmt: skip
    return ca.Function("nav_step", [n, x, e], [out], ["n", "x", "e"], ["n_next"])
