"""Tests of usvsim.nav.filter.

1. Cross-implementation: the batched filters equal filterpy's ``KalmanFilter`` run per boat on
   the same measurements (means and covariances, including masked per-boat resets).
2. Control property: the estimate beats raw GNSS on a turning manoeuvre; heading beats the compass.
3. API behaviour: reproducibility, run == repeated step, masked resets, input validation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter
from scipy.linalg import expm

from usvsim.common.angles import ssa
from usvsim.nav.filter import NavEstimate, Navigator
from usvsim.nav.models import (
    NavConfig,
    heading_filter_model,
    position_filter_model,
    position_transition,
)
from usvsim.nav.sensors import SensorConfig, sample_gps

DT = 0.1  # s, plant step


# --------------------------------------------------------------------------------------------
# Reference: filterpy per boat, fed with the measurements the Navigator draws (same rng order)
# --------------------------------------------------------------------------------------------


def ct_transition(omega: float, dt: float) -> np.ndarray:
    """Coordinated-turn transition written out with sin/cos (Bar-Shalom et al. 2001, Ch. 11)."""
    s, c = np.sin(omega * dt), np.cos(omega * dt)
    return np.array(
        [
            [1.0, 0.0, s / omega, -(1.0 - c) / omega],
            [0.0, 1.0, (1.0 - c) / omega, s / omega],
            [0.0, 0.0, c, -s],
            [0.0, 0.0, s, c],
        ]
    )


@dataclass
class RefBoat:
    """filterpy filters of one boat plus its true gyro bias."""

    pos: KalmanFilter
    head: KalmanFilter
    bias_true: float


def make_ref_boat(
    cfg: NavConfig, pos0: np.ndarray, vel0: np.ndarray, psi0: float, bias_true: float
) -> RefBoat:
    s = cfg.sensors
    kp = KalmanFilter(dim_x=4, dim_z=2)
    kp.x = np.array([*pos0, *vel0])
    kp.P = np.diag([s.gps_sigma_m**2] * 2 + [cfg.init_vel_sigma_mps**2] * 2)
    kp.F = np.array([[1, 0, DT, 0], [0, 1, 0, DT], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)
    kp.Q = Q_discrete_white_noise(
        dim=2, dt=DT, var=cfg.accel_sigma_mps2**2, block_size=2, order_by_dim=False
    )
    kp.H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    kp.R = s.gps_sigma_m**2 * np.eye(2)
    kh = KalmanFilter(dim_x=2, dim_z=1, dim_u=1)
    kh.x = np.array([psi0, 0.0])
    kh.P = np.diag([s.compass_sigma_rad**2, s.gyro_bias_sigma_radps**2])
    kh.F = np.array([[1.0, -DT], [0.0, 1.0]])
    kh.B = np.array([[DT], [0.0]])
    kh.Q = np.diag([(DT * s.gyro_sigma_radps) ** 2, cfg.gyro_bias_walk_sigma**2 * DT])
    kh.H = np.array([[1.0, 0.0]])
    kh.R = np.array([[s.compass_sigma_rad**2]])
    return RefBoat(kp, kh, float(bias_true))


def ref_reset(
    cfg: NavConfig,
    refs: list,
    eta: np.ndarray,
    nu: np.ndarray,
    rng: np.random.Generator,
    mask: np.ndarray | None = None,
) -> None:
    """Replay Navigator.reset's draws: GNSS (k,2), compass (k,), vel (k,2), bias (k,), gyro (k,)."""
    s = cfg.sensors
    idx = np.arange(len(refs)) if mask is None else np.flatnonzero(mask)
    k = idx.size
    gps = eta[idx, :2] + rng.normal(0.0, s.gps_sigma_m, (k, 2))
    compass = ssa(eta[idx, 2] + rng.normal(0.0, s.compass_sigma_rad, k))
    c, sn = np.cos(eta[idx, 2]), np.sin(eta[idx, 2])
    u, v = nu[idx, 0], nu[idx, 1]
    vel = np.stack([c * u - sn * v, sn * u + c * v], -1)
    vel = vel + rng.normal(0.0, cfg.init_vel_sigma_mps, (k, 2))
    bias = rng.normal(0.0, s.gyro_bias_sigma_radps, k)
    rng.normal(0.0, s.gyro_sigma_radps, k)  # initial gyro reading (only sets yaw_rate)
    for j, i in enumerate(idx):
        refs[i] = make_ref_boat(cfg, gps[j], vel[j], compass[j], bias[j])


def ref_step(
    cfg: NavConfig,
    refs: list,
    k: int,
    eta: np.ndarray,
    nu: np.ndarray,
    rng: np.random.Generator,
) -> None:
    """Replay Navigator.step's draws (gyro, GNSS, compass) and run filterpy per boat."""
    s, n = cfg.sensors, len(refs)
    gyro = nu[:, 2] + np.array([b.bias_true for b in refs]) + rng.normal(0, s.gyro_sigma_radps, n)
    gps = eta[:, :2] + rng.normal(0.0, s.gps_sigma_m, (n, 2)) if k % 2 == 0 else None
    gps_vel = None
    if gps is not None and cfg.gnss_velocity:
        c, sn = np.cos(eta[:, 2]), np.sin(eta[:, 2])
        vel = np.stack([c * nu[:, 0] - sn * nu[:, 1], sn * nu[:, 0] + c * nu[:, 1]], -1)
        gps_vel = vel + rng.normal(0.0, s.gps_velocity_sigma_mps, (n, 2))
    compass = ssa(eta[:, 2] + rng.normal(0.0, s.compass_sigma_rad, n))
    for i, b in enumerate(refs):
        omega = gyro[i] - b.head.x[1]
        b.head.predict(u=np.array([gyro[i]]))
        if cfg.turn_rate_aided:
            b.pos.F = ct_transition(omega, DT)
        b.pos.predict()
        if gps is not None:
            b.pos.update(gps[i])
        if gps_vel is not None:
            H_v = np.array([[0, 0, 1.0, 0], [0, 0, 0, 1.0]])
            b.pos.update(gps_vel[i], R=s.gps_velocity_sigma_mps**2 * np.eye(2), H=H_v)
        hx = b.head.x[0]
        b.head.update(np.array([hx + ssa(compass[i] - hx)]))  # unwrapped measurement


def random_states(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    eta = np.column_stack([rng.uniform(-100, 100, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    nu = np.column_stack(
        [rng.uniform(0, 4, n), rng.uniform(-0.3, 0.3, n), rng.uniform(-0.2, 0.2, n)]
    )
    return eta, nu


def assert_matches_reference(nav: Navigator, refs: list[RefBoat], est: NavEstimate) -> None:
    x_ref = np.array([b.pos.x for b in refs])
    np.testing.assert_allclose(est.pos_ne, x_ref[:, :2], rtol=0, atol=1e-9)
    np.testing.assert_allclose(est.vel_ne, x_ref[:, 2:], rtol=0, atol=1e-9)
    psi_ref = np.array([b.head.x[0] for b in refs])
    assert np.max(np.abs(ssa(est.psi - psi_ref))) < 1e-9
    bias_ref = np.array([b.head.x[1] for b in refs])
    np.testing.assert_allclose(nav.gyro_bias_estimate, bias_ref, rtol=0, atol=1e-12)
    P_ref = np.array([b.pos.P for b in refs])
    np.testing.assert_allclose(nav.position_covariance, P_ref, rtol=0, atol=1e-9)
    Ph_ref = np.array([b.head.P for b in refs])
    np.testing.assert_allclose(nav.heading_covariance, Ph_ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("aided", [True, False])
def test_batched_filters_equal_filterpy_per_boat(aided: bool) -> None:
    cfg = NavConfig(turn_rate_aided=aided)
    n, steps = 5, 60
    world = np.random.default_rng(123)
    eta, nu = random_states(world, n)
    nav, refs = Navigator(cfg, n), [None] * n
    nav.reset(eta, nu, np.random.default_rng(5))
    ref_reset(cfg, refs, eta, nu, np.random.default_rng(5))
    rng_nav, rng_ref = np.random.default_rng(6), np.random.default_rng(6)
    for k in range(1, steps + 1):
        eta = eta + DT * nu  # any path will do: the filters only see its samples
        est = nav.step(k, eta, nu, rng_nav)
        ref_step(cfg, refs, k, eta, nu, rng_ref)
        assert_matches_reference(nav, refs, est)


@pytest.mark.parametrize("aided", [True, False])
def test_batched_filters_equal_filterpy_with_masked_resets(aided: bool) -> None:
    cfg = NavConfig(turn_rate_aided=aided)
    n = 6
    world = np.random.default_rng(321)
    eta, nu = random_states(world, n)
    nav, refs = Navigator(cfg, n), [None] * n
    rng_nav, rng_ref = np.random.default_rng(9), np.random.default_rng(9)
    nav.reset(eta, nu, rng_nav)
    ref_reset(cfg, refs, eta, nu, rng_ref)
    resets = {15: np.array([1, 0, 0, 1, 0, 0], bool), 30: np.array([0, 0, 1, 0, 0, 1], bool)}
    for k in range(1, 51):
        eta = eta + DT * nu
        if k in resets:  # autoreset-style: the boats jump to new states and are re-initialised
            new_eta, new_nu = random_states(world, n)
            eta[resets[k]], nu[resets[k]] = new_eta[resets[k]], new_nu[resets[k]]
            nav.reset(eta, nu, rng_nav, mask=resets[k])
            ref_reset(cfg, refs, eta, nu, rng_ref, mask=resets[k])
        est = nav.step(k, eta, nu, rng_nav)
        ref_step(cfg, refs, k, eta, nu, rng_ref)
        assert_matches_reference(nav, refs, est)
    # the per-boat covariances really differ after the resets
    P = nav.position_covariance
    assert np.abs(P[0] - P[1]).max() > 1e-6


def test_position_transition_is_matrix_exponential_of_turn() -> None:
    # continuous model: p' = v, v' = omega J v (J: rotation generator, clockwise-positive in NE)
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    omegas = np.array([-0.7, -1e-9, 0.0, 0.05, 0.3])
    F = position_transition(omegas, DT)
    for omega, F_i in zip(omegas, F, strict=True):
        A = np.zeros((4, 4))
        A[:2, 2:] = np.eye(2)
        A[2:, 2:] = omega * J
        np.testing.assert_allclose(F_i, expm(A * DT), rtol=0, atol=1e-15)


def test_filter_models_match_their_definitions() -> None:
    cfg = NavConfig()
    pm, hm = position_filter_model(cfg), heading_filter_model(cfg)
    q = cfg.accel_sigma_mps2**2
    # DWNA per axis (Bar-Shalom et al. 2001, Sect. 6.3.2): q [[dt^4/4, dt^3/2], [dt^3/2, dt^2]]
    np.testing.assert_allclose(pm.Q[0, [0, 2]], q * np.array([DT**4 / 4, DT**3 / 2]), rtol=1e-14)
    np.testing.assert_allclose(pm.Q[2, 2], q * DT**2, rtol=1e-14)
    assert pm.Q[0, 1] == pm.Q[0, 3] == 0.0
    np.testing.assert_array_equal(pm.F, position_transition(np.zeros(1), DT)[0])
    np.testing.assert_array_equal(hm.F @ np.array([1.0, 0.2]), [1.0 - DT * 0.2, 0.2])
    assert not pm.F.flags.writeable


# --------------------------------------------------------------------------------------------
# Control property: beats raw GNSS on a manoeuvre
# --------------------------------------------------------------------------------------------


def manoeuvre(
    psi0: float = 2.0, speed: float = 3.0, turn_deg_s: float = 10.0
) -> tuple[np.ndarray, np.ndarray]:
    """3 m/s straight 30 s, 20 s at a constant rate, straight 30 s; exact circular arcs.

    Returns eta (T, 3) with an unwrapped heading (it crosses +pi) and nu (T, 3). Step k of the
    navigator propagates over [t_{k-1}, t_k] with the gyro read at t_k, so nu[k] holds the rate
    of that interval.
    """
    n = 801
    t = np.arange(n) * DT
    r = np.where((t >= 30.0 - 1e-9) & (t < 50.0 - 1e-9), np.deg2rad(turn_deg_s), 0.0)
    psi = psi0 + np.concatenate([[0.0], np.cumsum(r[:-1] * DT)])
    # position: integrate the exact arc of each step (r constant over [t_k, t_k+1))
    d_psi = psi[1:] - psi[:-1]
    chord = np.sinc(d_psi / (2 * np.pi)) * speed * DT  # 2 R sin(d_psi / 2)
    mid = psi[:-1] + 0.5 * d_psi
    steps = np.column_stack([chord * np.cos(mid), chord * np.sin(mid)])
    pos = np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])
    eta = np.column_stack([pos, psi])
    nu = np.column_stack([np.full(n, speed), np.zeros(n), np.concatenate([[0.0], r[:-1]])])
    return eta, nu


def run_manoeuvre(
    cfg: NavConfig, n_boats: int = 256, seed: int = 0
) -> tuple[Navigator, NavEstimate, np.ndarray]:
    eta, nu = manoeuvre()
    E = np.broadcast_to(eta, (n_boats, *eta.shape)).copy()
    V = np.broadcast_to(nu, (n_boats, *nu.shape)).copy()
    nav = Navigator(cfg, n_boats)
    rng = np.random.default_rng(seed)
    nav.reset(E[:, 0], V[:, 0], rng)
    est = nav.run(E[:, 1:], V[:, 1:], rng, first_step_index=1)
    return nav, est, E[:, 1:]


def position_rmse_ratio(est: NavEstimate, eta_true: np.ndarray, gps_sigma: float) -> float:
    rmse = np.sqrt(np.mean(np.sum((est.pos_ne - eta_true[..., :2]) ** 2, axis=-1)))
    return float(rmse / (np.sqrt(2.0) * gps_sigma))  # raw GNSS 2-D RMSE = sqrt(2) sigma


def test_manoeuvre_truth_is_consistent() -> None:
    eta, nu = manoeuvre()
    # speed over ground 3 m/s everywhere, heading turned by 200 deg, consistent with nu's rates
    assert np.allclose(np.linalg.norm(np.diff(eta[:, :2], axis=0), axis=1) / DT, 3.0, rtol=1e-3)
    assert eta[-1, 2] - eta[0, 2] == pytest.approx(np.deg2rad(200.0), abs=1e-9)
    np.testing.assert_allclose(np.diff(eta[:, 2]), nu[1:, 2] * DT, rtol=0, atol=1e-15)


def test_position_estimate_beats_raw_gnss_on_a_turn() -> None:
    cfg = NavConfig()
    _, est, eta = run_manoeuvre(cfg)
    # measured: 0.26 (256 boats, seed 0); the requirement is <= 0.5
    ratio = position_rmse_ratio(est, eta, cfg.sensors.gps_sigma_m)
    assert ratio <= 0.35


def test_raw_gnss_rmse_is_what_the_ratio_assumes() -> None:
    cfg = SensorConfig()
    pos = np.zeros((200_000, 2))
    err = sample_gps(pos, np.random.default_rng(0), cfg) - pos
    rmse = np.sqrt(np.mean(np.sum(err**2, axis=-1)))
    assert rmse == pytest.approx(np.sqrt(2.0) * cfg.gps_sigma_m, rel=0.01)


def test_turn_rate_aiding_beats_plain_constant_velocity() -> None:
    # position fixes only (with GNSS velocity both are ~0.14): aiding is what beats the lag
    aided = NavConfig(gnss_velocity=False, accel_sigma_mps2=0.2)
    plain = NavConfig(turn_rate_aided=False, accel_sigma_mps2=1.2, gnss_velocity=False)
    _, est_aided, eta = run_manoeuvre(aided, 64)
    _, est_plain, _ = run_manoeuvre(plain, 64)
    ratio_aided = position_rmse_ratio(est_aided, eta, 1.5)
    ratio_plain = position_rmse_ratio(est_plain, eta, 1.5)
    # measured: 0.26 vs 0.45
    assert ratio_aided < 0.7 * ratio_plain


def test_heading_estimate_beats_compass_and_wraps() -> None:
    cfg = NavConfig()
    nav, est, eta = run_manoeuvre(cfg)
    err = ssa(est.psi - eta[..., 2])
    rmse = np.sqrt(np.mean(err**2))
    # measured: 0.14 deg vs compass 1 deg (256 boats, seed 0)
    assert rmse < 0.5 * cfg.sensors.compass_sigma_rad
    assert est.psi.min() >= -np.pi and est.psi.max() < np.pi
    assert est.psi.min() < -2.5  # the turn crossed +-pi
    # the gyro bias is learnt: residual well below its prior sigma
    bias_err = nav.gyro_bias_estimate - nav.true_gyro_bias
    assert np.sqrt(np.mean(bias_err**2)) < 0.3 * cfg.sensors.gyro_bias_sigma_radps


# --------------------------------------------------------------------------------------------
# API behaviour
# --------------------------------------------------------------------------------------------


def small_setup(n: int = 4, seed: int = 0) -> tuple[Navigator, np.ndarray, np.ndarray]:
    eta, nu = random_states(np.random.default_rng(seed), n)
    nav = Navigator(NavConfig(), n)
    nav.reset(eta, nu, np.random.default_rng(seed))
    return nav, eta, nu


def test_same_seed_same_estimates() -> None:
    def run(seed: int) -> NavEstimate:
        nav, eta, nu = small_setup(seed=0)
        traj_eta = np.repeat(eta[:, None], 20, axis=1)
        traj_nu = np.repeat(nu[:, None], 20, axis=1)
        return nav.run(traj_eta, traj_nu, np.random.default_rng(seed), first_step_index=1)

    a, b, c = run(1), run(1), run(2)
    for name in ("pos_ne", "vel_ne", "psi", "yaw_rate"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
        assert not np.array_equal(getattr(a, name), getattr(c, name))


def test_run_equals_repeated_steps() -> None:
    nav_a, eta, nu = small_setup()
    nav_b, _, _ = small_setup()
    T = 20
    traj_eta = eta[:, None] + np.arange(T)[None, :, None] * 0.1 * nu[:, None]
    traj_nu = np.repeat(nu[:, None], T, axis=1)
    est_run = nav_a.run(traj_eta, traj_nu, np.random.default_rng(3), first_step_index=7)
    rng = np.random.default_rng(3)
    for j in range(T):
        est = nav_b.step(7 + j, traj_eta[:, j], traj_nu[:, j], rng)
        assert np.array_equal(est_run.pos_ne[:, j], est.pos_ne)
        assert np.array_equal(est_run.vel_ne[:, j], est.vel_ne)
        assert np.array_equal(est_run.psi[:, j], est.psi)
        assert np.array_equal(est_run.yaw_rate[:, j], est.yaw_rate)
    assert est_run.pos_ne.shape == (4, T, 2) and est_run.psi.shape == (4, T)


def test_masked_reset_leaves_other_boats_untouched() -> None:
    nav, eta, nu = small_setup()
    nav.step(1, eta, nu, np.random.default_rng(1))
    before = nav.estimate
    P_before = nav.position_covariance
    mask = np.array([False, True, False, False])
    after = nav.reset(eta + 10.0, nu, np.random.default_rng(2), mask=mask)
    keep = ~mask
    assert np.array_equal(after.pos_ne[keep], before.pos_ne[keep])
    assert np.array_equal(after.psi[keep], before.psi[keep])
    assert np.array_equal(nav.position_covariance[keep], P_before[keep])
    assert np.abs(after.pos_ne[1] - (eta[1, :2] + 10.0)).max() < 10.0  # a fix near the new spot
    np.testing.assert_allclose(
        nav.position_covariance[1], np.diag([1.5**2, 1.5**2, 0.1**2, 0.1**2]), rtol=1e-15
    )


def test_returned_estimates_are_not_mutated_later() -> None:
    nav, eta, nu = small_setup()
    est = nav.step(1, eta, nu, np.random.default_rng(1))
    copy = {k: np.array(getattr(est, k)) for k in ("pos_ne", "vel_ne", "psi", "yaw_rate")}
    nav.step(2, eta, nu, np.random.default_rng(2))
    nav.reset(eta + 5.0, nu, np.random.default_rng(3), mask=np.array([True, False, True, False]))
    for k, v in copy.items():
        assert np.array_equal(getattr(est, k), v)


def test_speed_and_course_over_ground() -> None:
    est = NavEstimate(
        pos_ne=np.zeros((2, 2)),
        vel_ne=np.array([[3.0, 4.0], [0.0, -2.0]]),
        psi=np.zeros(2),
        yaw_rate=np.zeros(2),
    )
    np.testing.assert_allclose(est.sog_mps, [5.0, 2.0], rtol=1e-15)
    np.testing.assert_allclose(est.cog_rad, [np.arctan2(4.0, 3.0), -np.pi / 2], rtol=1e-15)


def test_reset_estimate_is_a_fix_of_the_true_state() -> None:
    n = 20_000
    eta = np.tile([10.0, -5.0, 0.5], (n, 1))
    nu = np.tile([2.0, 0.5, 0.0], (n, 1))
    est = Navigator(NavConfig(), n).reset(eta, nu, np.random.default_rng(0))
    vel_true = [2.0 * np.cos(0.5) - 0.5 * np.sin(0.5), 2.0 * np.sin(0.5) + 0.5 * np.cos(0.5)]
    np.testing.assert_allclose(est.pos_ne.std(axis=0), 1.5, rtol=0.03)
    np.testing.assert_allclose(est.vel_ne.mean(axis=0), vel_true, atol=0.005)
    np.testing.assert_allclose(est.vel_ne.std(axis=0), 0.1, rtol=0.03)
    assert ssa(est.psi - 0.5).std() == pytest.approx(np.deg2rad(1.0), rel=0.03)


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dt_s": 0.0}, "NavConfig.dt_s must be finite and > 0"),
        ({"accel_sigma_mps2": -0.1}, "NavConfig.accel_sigma_mps2 must be finite and > 0"),
        ({"gyro_bias_walk_sigma": float("nan")}, "NavConfig.gyro_bias_walk_sigma must be finite"),
        ({"init_vel_sigma_mps": float("inf")}, "NavConfig.init_vel_sigma_mps must be finite"),
        ({"turn_rate_aided": 1}, "NavConfig.turn_rate_aided must be a bool"),
        ({"sensors": {"gps_sigma_m": 1.0}}, "NavConfig.sensors must be a SensorConfig"),
        ({"sensors": SensorConfig(gps_rate_hz=3.0)}, "integer multiple"),
        ({"dt_s": 0.25}, "integer multiple"),
    ],
)
def test_nav_config_rejects_bad_values(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        NavConfig(**kwargs)


def test_navigator_rejects_bad_construction() -> None:
    with pytest.raises(ValueError, match="n_boats must be a positive integer"):
        Navigator(NavConfig(), 0)
    with pytest.raises(ValueError, match="cfg must be a NavConfig"):
        Navigator(SensorConfig(), 3)  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_states_raise(bad: float) -> None:
    nav, eta, nu = small_setup()
    eta_bad, nu_bad = eta.copy(), nu.copy()
    eta_bad[2, 1], nu_bad[0, 2] = bad, bad
    with pytest.raises(ValueError, match="eta contains NaN or inf"):
        nav.step(1, eta_bad, nu, np.random.default_rng(0))
    with pytest.raises(ValueError, match="nu contains NaN or inf"):
        nav.step(1, eta, nu_bad, np.random.default_rng(0))
    with pytest.raises(ValueError, match="eta contains NaN or inf"):
        nav.reset(eta_bad, nu, np.random.default_rng(0))


def test_wrong_shapes_raise() -> None:
    nav, eta, nu = small_setup()
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match=r"eta must have shape \(N, 3\), got \(4, 2\)"):
        nav.step(1, eta[:, :2], nu, rng)
    with pytest.raises(ValueError, match="must have 4 rows"):
        nav.step(1, eta[:3], nu[:3], rng)
    with pytest.raises(ValueError, match=r"mask must be a bool array of shape \(4,\)"):
        nav.reset(eta, nu, rng, mask=np.array([1, 0, 0, 1]))
    with pytest.raises(ValueError, match=r"mask must be a bool array of shape \(4,\)"):
        nav.reset(eta, nu, rng, mask=np.array([True, False]))
    with pytest.raises(ValueError, match=r"eta_traj must have shape \(4, T, 3\)"):
        nav.run(eta, nu, rng, first_step_index=0)
    with pytest.raises(ValueError, match="must have one shape"):
        nav.run(np.zeros((4, 5, 3)), np.zeros((4, 6, 3)), rng, first_step_index=0)
    with pytest.raises(ValueError, match="step_index must be >= 0"):
        nav.step(-1, eta, nu, rng)


def test_step_before_reset_raises() -> None:
    eta, nu = random_states(np.random.default_rng(0), 3)
    nav = Navigator(NavConfig(), 3)
    with pytest.raises(RuntimeError, match="reset"):
        nav.step(0, eta, nu, np.random.default_rng(0))
    nav.reset(eta, nu, np.random.default_rng(0), mask=np.array([True, True, False]))
    with pytest.raises(RuntimeError, match="reset"):
        nav.step(0, eta, nu, np.random.default_rng(0))


def test_position_estimate_beats_raw_gnss_on_the_plant() -> None:
    """The issue's bar on the real closed-loop plant: RMSE ≤ 0.5 x raw GPS at default noise.

    Zig-zag ±30° every 10 s for 120 s, 32 boats (the default hull sideslips strongly in turns,
    which a kinematic manoeuvre does not show). Measured: 0.14 (position-only filter: 0.49).
    """
    import math

    from usvsim.vessel.plant import Plant

    plant = Plant("default")
    n = 32
    rng = np.random.default_rng(0)
    nav = Navigator(NavConfig(), n)
    state = plant.initial_state(np.zeros((n, 3)))
    nav.reset(state.eta, state.nu, rng)
    sq_err = []
    for k in range(60):
        psi_ref = np.full(n, math.radians(30.0 if (k // 5) % 2 == 0 else -30.0))
        state, traj = plant.step(state, psi_ref, n_steps=20)
        est = nav.run(traj[:, :, 0:3], traj[:, :, 3:6], rng, first_step_index=20 * k + 1)
        sq_err.append(np.sum((est.pos_ne - traj[:, :, 0:2]) ** 2, axis=-1))
    rmse = math.sqrt(np.mean(np.concatenate(sq_err)))
    raw_rmse = math.sqrt(2.0) * NavConfig().sensors.gps_sigma_m
    assert rmse <= 0.5 * raw_rmse
    assert rmse <= 0.25 * raw_rmse  # measured 0.14: keeps the margin visible
