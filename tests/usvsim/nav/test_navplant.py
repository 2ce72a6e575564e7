"""The fused compiled plant + filter equals Plant.step followed by Navigator.run."""

from __future__ import annotations

import numpy as np
import pytest

from usvsim.nav.compiled import build_nav_step, export_nav_state, started_nav_rows
from usvsim.nav.filter import Navigator
from usvsim.nav.models import NavConfig
from usvsim.nav.navplant import PACKED, NavigatedPlant
from usvsim.vessel.plant import Plant


class RecordingRng:
    """A Generator stand-in that records the standard normals the navigator draws."""

    def __init__(self, normals: np.ndarray) -> None:
        self.normals, self.col = normals, 0

    def normal(self, loc=0.0, scale=1.0, size=None):
        m = int(np.prod(size[1:]))
        z = self.normals[:, self.col : self.col + m].reshape(size)
        self.col += m
        return loc + scale * z


@pytest.fixture(scope="module")
def plant() -> Plant:
    return Plant("default")


def boats(plant: Plant, n: int, seed: int):
    rng = np.random.default_rng(seed)
    eta = np.column_stack([rng.uniform(-50, 50, (n, 2)), rng.uniform(-3, 3, n)])
    return plant.initial_state(eta), rng


@pytest.mark.parametrize(
    "cfg",
    [NavConfig(), NavConfig(turn_rate_aided=False), NavConfig(gnss_velocity=False)],
    ids=["aided+velocity", "cv", "position-only"],
)
def test_fused_step_equals_plant_then_navigator(plant, cfg):
    n, T = 16, 20
    state, rng = boats(plant, n, 0)
    nav_a, nav_b = Navigator(cfg, n), Navigator(cfg, n)
    nav_a.reset(state.eta, state.nu, np.random.default_rng(1))
    nav_b.reset(state.eta, state.nu, np.random.default_rng(1))
    fused = NavigatedPlant(plant, cfg)
    s_fused, s_ref = state, state
    first = 1
    for _ in range(3):  # three decision periods
        psi_ref = rng.uniform(-3, 3, n)
        normals = rng.standard_normal((n, fused.draws_needed(first, T)))
        s_fused, traj_f, nav_traj = fused.step(s_fused, nav_a, psi_ref, 3.0, T, first, normals)
        s_ref, traj_r = plant.step(s_ref, psi_ref, 3.0, n_steps=T)
        est = nav_b.run(traj_r[:, :, 0:3], traj_r[:, :, 3:6], RecordingRng(normals), first)
        first += T
        np.testing.assert_allclose(traj_f, traj_r, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(nav_traj[:, :, 0:2], est.pos_ne, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(nav_traj[:, :, 8], est.psi, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(export_nav_state(nav_a), export_nav_state(nav_b), atol=1e-9)


def test_nav_step_function_matches_navigator_one_step(plant):
    cfg = NavConfig()
    state, _ = boats(plant, 4, 3)
    nav = Navigator(cfg, 4)
    nav.reset(state.eta, state.nu, np.random.default_rng(2))
    before = export_nav_state(nav)
    normals = np.random.default_rng(4).standard_normal((4, 6))  # step 2: gyro, GNSS, vel, compass
    new, _ = plant.step(state, 0.0)
    nav.step(2, new.eta, new.nu, RecordingRng(normals))
    F = build_nav_step(cfg)
    e = np.column_stack([normals, np.ones((4, 2))])
    out = np.stack([np.asarray(F(before[i], new.x[i], e[i])).ravel() for i in range(4)])
    np.testing.assert_allclose(out, export_nav_state(nav), atol=1e-12)


def test_fused_step_rejects_wrong_noise(plant):
    cfg = NavConfig()
    state, _ = boats(plant, 2, 0)
    nav = Navigator(cfg, 2)
    nav.reset(state.eta, state.nu, np.random.default_rng(0))
    fused = NavigatedPlant(plant, cfg)
    with pytest.raises(ValueError, match="normals per boat"):
        fused.step(state, nav, np.zeros(2), 3.0, 20, 1, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="NaN or inf"):
        fused.step(state, nav, np.array([0.0, np.nan]), 3.0, 20, 1, np.zeros((2, 100)))


def test_packed_run_equals_the_navigator_step(plant):
    cfg = NavConfig()
    n, T = 8, 20
    state, rng = boats(plant, n, 5)
    nav = Navigator(cfg, n)
    nav.reset(state.eta, state.nu, np.random.default_rng(6))
    fused = NavigatedPlant(plant, cfg)
    packed = np.concatenate([state.x, state.c, export_nav_state(nav)], axis=1)
    psi_ref = rng.uniform(-3, 3, n)
    normals = rng.standard_normal((n, fused.draws_needed(21, T)))
    traj = fused.run(packed, psi_ref, 3.0, T, 21, normals)
    _, plant_traj, nav_traj = fused.step(state, nav, psi_ref, 3.0, T, 21, normals)
    np.testing.assert_array_equal(traj[:, :, PACKED.closed_loop], plant_traj)
    np.testing.assert_array_equal(traj[:, :, PACKED.nav], nav_traj)
    np.testing.assert_array_equal(traj[:, -1, PACKED.nav], export_nav_state(nav))
    # the named slices read the navigator's estimate
    est = nav.estimate
    np.testing.assert_array_equal(traj[:, -1, PACKED.nav_pos], est.pos_ne)
    np.testing.assert_array_equal(traj[:, -1, PACKED.nav_vel], est.vel_ne)
    np.testing.assert_array_equal(traj[:, -1, PACKED.nav_psi], est.psi)


def test_packed_layout_tiles_the_state():
    # x (8) | c (5) | n (15): the parts follow each other without gaps and fill the vector
    parts = [PACKED.plant, PACKED.controller, PACKED.nav]
    assert [(p.start, p.stop) for p in parts] == [(0, 8), (8, 13), (13, 28)]
    assert PACKED.closed_loop == slice(0, 13) and PACKED.size == 28
    assert (PACKED.nav_pos, PACKED.nav_vel, PACKED.nav_psi) == (slice(13, 15), slice(15, 17), 21)


def test_started_rows_equal_a_masked_navigator_reset():
    cfg = NavConfig()
    rng = np.random.default_rng(3)
    n, idx = 7, np.array([1, 4, 5])
    eta = np.column_stack([rng.uniform(-100, 100, (n, 2)), rng.uniform(-np.pi, np.pi, n)])
    nu = np.column_stack([rng.uniform(0, 3, n), rng.uniform(-0.3, 0.3, n), rng.normal(0, 0.1, n)])
    nav = Navigator(cfg, n)
    nav.reset(eta, nu, np.random.default_rng(0))
    mask = np.zeros(n, dtype=bool)
    mask[idx] = True
    est = nav.reset(eta, nu, np.random.default_rng(9), mask=mask)
    rows = started_nav_rows(cfg, eta[idx], nu[idx], np.random.default_rng(9))
    np.testing.assert_array_equal(rows, export_nav_state(nav)[idx])
    np.testing.assert_array_equal(rows[:, 0:2], est.pos_ne[idx])
    np.testing.assert_array_equal(rows[:, 8], est.psi[idx])


def test_weather_fused_step_equals_weather_plant_then_navigator_on_sensed_motion(plant):
    """With weather, the fused step equals WeatherPlant.step then Navigator.run on the sensed
    pose and yaw rate (true + first-order wave motion); with no weather, the calm fused step."""
    from usvsim.vessel.weather.waves import sea_state_from_code
    from usvsim.vessel.weather_plant import SeaConditions, WeatherPlant, sensed_offsets

    cfg, n, T = NavConfig(), 8, 20
    state, rng = boats(plant, n, 5)
    cond = SeaConditions.uniform(n, 10.0, 1.0, sea_state_from_code(4, 2.4))
    weather = WeatherPlant(plant, seed=0, innovations="normal")
    fused = NavigatedPlant(plant, cfg, weather)
    assert fused.layout.size == PACKED.size + 8
    start = weather.initial_state(state.eta, cond)
    nav = Navigator(cfg, n)
    nav.reset(state.eta, state.nu, np.random.default_rng(1))
    s0 = np.concatenate([start.x, start.c, start.m, export_nav_state(nav)], axis=1)
    psi_ref = rng.uniform(-3, 3, n)
    normals = rng.standard_normal((n, fused.draws_needed(1, T)))
    wx = rng.standard_normal((n, 3 * T))
    packed = fused.run(s0, psi_ref, 3.0, T, 1, normals, None, None, start.inputs, wx)
    # reference: the weather plant with the same innovations, then the navigator on what it senses
    weather.rng = _Replay(wx.reshape(n, T, 3))
    _, traj = weather.step(start, psi_ref, 3.0, n_steps=T, weather_states=True)
    x, m = traj[:, :, 0:8], traj[:, :, 13:21]
    d = sensed_offsets(
        x, m, np.broadcast_to(start.inputs[:, None, :], (n, T, start.inputs.shape[1]))
    )
    eta = x[:, :, 0:3] + d[:, :, 0:3]
    nu = np.concatenate([x[:, :, 3:5], x[:, :, 5:6] + d[:, :, 3:4]], axis=2)
    est = nav.run(eta, nu, RecordingRng(normals), 1)
    lay = fused.layout
    np.testing.assert_allclose(packed[:, :, 0:21], traj, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(packed[:, :, lay.nav_pos], est.pos_ne, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(packed[:, :, lay.nav_psi], est.psi, rtol=1e-9, atol=1e-9)
    assert np.std(d[:, :, 0]) > 0.05  # the GNSS does see the waves (m)


class _Replay:
    """A Generator stand-in whose standard_normal returns given numbers."""

    def __init__(self, values: np.ndarray) -> None:
        self.values = values

    def standard_normal(self, shape):
        assert shape == self.values.shape
        return self.values
