"""Tests of guidance/: path errors, switching, LOS/ILOS/ALOS in closed loop with the real Plant.

Closed-loop runs: default vessel, PID autopilot, 3 m/s, plant step 0.1 s, guidance updated every
plant step. Figures measured when the tests were written are quoted next to each threshold.
"""

from __future__ import annotations

import numpy as np
import pytest

from guidance import (
    LOSConfig,
    LOSGuidance,
    WaypointManager,
    WaypointPath,
    initial_guidance_state,
    los_step,
)
from guidance.waypoints import path_errors
from usvsim.vessel.plant import Plant

DT_S = 0.1  # s, plant step and guidance update interval
CROSS_CURRENT = (0.5, -np.pi / 2)  # 0.5 m/s towards west, perpendicular to a northbound path
STRAIGHT = [(0.0, 0.0), (2000.0, 0.0)]  # a line due north
ZIGZAG = [(0.0, 0.0), (150.0, 0.0), (150.0, 150.0), (300.0, 150.0)]  # N, E, N legs


@pytest.fixture(scope="module")
def calm_plant() -> Plant:
    return Plant(dt_s=DT_S)


@pytest.fixture(scope="module")
def current_plant() -> Plant:
    return Plant(dt_s=DT_S, current=CROSS_CURRENT)


def simulate(plant: Plant, guidance: LOSGuidance, eta0: np.ndarray, duration_s: float):
    """Closed loop; returns (ψ_ref, ψ_LOS, y_e, segment) histories (T, N) and the final x (N, 8)."""
    state = plant.initial_state(eta0)
    hist: dict[str, list[np.ndarray]] = {"ref": [], "los": [], "ye": [], "seg": []}
    for _ in range(round(duration_s / DT_S)):
        out = guidance.update(state.x[:, 0:2], state.x[:, 2], DT_S)
        hist["ref"].append(out.psi_ref_rad)
        hist["los"].append(out.psi_los_rad)
        hist["ye"].append(out.cross_track_m)
        hist["seg"].append(out.segment)
        state, _ = plant.step(state, out.psi_ref_rad)
    return {k: np.array(v) for k, v in hist.items()}, state.x


def offset_start() -> np.ndarray:
    """20 m east (starboard) of the northbound line, heading north."""
    return np.array([[0.0, 20.0, 0.0]])


# ---------------------------------------------------------------- level 1: exact pieces


def test_path_errors_on_a_diagonal_segment_match_geometry():
    path = WaypointPath.from_lists([[(0.0, 0.0), (100.0, 100.0)]])
    # 10 m along the path and 5 m to starboard (south-east of the north-east line)
    along, right = np.array([1.0, 1.0]) / np.sqrt(2), np.array([-1.0, 1.0]) / np.sqrt(2)
    pos = (10.0 * along + 5.0 * right)[None, :]
    pi_p, x_e, y_e, to_go = path_errors(path, np.array([0]), pos)
    np.testing.assert_allclose(
        [pi_p[0], x_e[0], y_e[0], to_go[0]],
        [np.pi / 4, 10.0, 5.0, 100.0 * np.sqrt(2) - 10.0],
        atol=1e-12,
    )


@pytest.mark.parametrize("law", ["los", "ilos", "alos"])
def test_one_step_matches_the_published_laws(law):
    cfg = LOSConfig(
        law=law, lookahead_m=20.0, kappa_mps=0.4, gamma_radpms=2e-3, observer_omega_radps=None
    )
    path = WaypointPath.from_lists([STRAIGHT])
    state = initial_guidance_state(1)
    state = type(state)(**{**state.__dict__, "y_int": np.array([3.0]), "beta_hat": np.array([0.1])})
    new, out = los_step(cfg, path, state, np.array([[50.0, 8.0]]), np.array([0.0]), 0.5)
    y, d = 8.0, 20.0
    expected_psi = {
        "los": -np.arctan(y / d),
        "ilos": -np.arctan((y + 0.4 * 3.0) / d),  # Børhaug et al. (2008)
        "alos": -0.1 - np.arctan(y / d),
    }[law]  # Fossen (2023)
    assert out.psi_ref_rad[0] == pytest.approx(expected_psi, abs=1e-15)
    assert out.cross_track_m[0] == pytest.approx(8.0, abs=1e-12)
    expected_int = 3.0 + 0.5 * d * y / (d**2 + (y + 0.4 * 3.0) ** 2) if law == "ilos" else 3.0
    expected_beta = 0.1 + 0.5 * 2e-3 * d * y / np.hypot(d, y) if law == "alos" else 0.1
    assert new.y_int[0] == pytest.approx(expected_int, abs=1e-15)
    assert new.beta_hat[0] == pytest.approx(expected_beta, abs=1e-15)


def test_observer_first_step_after_a_jump_is_h_k1_times_the_jump():
    """From rest (ψ̂ = measured heading = 0, r̂ = 0) a command A moves ψ̂ by exactly h K1 A."""
    cfg = LOSConfig(law="los", observer_omega_radps=0.5)
    path = WaypointPath.from_lists([STRAIGHT])
    _, out = los_step(
        cfg, path, initial_guidance_state(1), np.array([[0.0, 20.0]]), np.array([0.0]), DT_S
    )
    jump = -np.pi / 4  # the raw LOS command for 20 m offset and Δ = 20 m
    k1, k2 = cfg.observer_gains
    assert (k1, k2) == (1.0, 0.25)
    assert out.psi_los_rad[0] == pytest.approx(jump, abs=1e-15)
    assert out.psi_ref_rad[0] == pytest.approx(DT_S * k1 * jump, abs=1e-15)
    assert out.r_ref_radps[0] == pytest.approx(DT_S * k2 * jump, abs=1e-15)


def test_switching_by_circle_or_by_passing_the_normal_and_holding_the_last_line():
    path = WaypointPath.from_lists([ZIGZAG])
    mgr = WaypointManager(path, switch_radius_m=10.0)
    assert mgr.update(np.array([[139.0, 0.0]])).segment.tolist() == [0]  # 11 m to go
    err = mgr.update(np.array([[141.0, 0.0]]))  # 9 m to go: inside the circle
    assert err.segment.tolist() == [1] and err.switched.tolist() == [True]
    # 50 m off the second leg (port side) and 5 m before its end: 50.2 m from the waypoint,
    # outside the circle, but past the normal R_switch before it, so it switches
    err = mgr.update(np.array([[100.0, 145.0]]))
    assert err.segment.tolist() == [2] and err.switched.tolist() == [True]
    assert err.along_track_m[0] == pytest.approx(-50.0) and err.cross_track_m[0] == -5.0
    # beyond the last waypoint: stays on the last leg, follows its extension, reports finished
    err = mgr.update(np.array([[400.0, 152.0]]))
    assert err.segment.tolist() == [2] and err.finished.tolist() == [True]
    assert err.cross_track_m[0] == pytest.approx(2.0) and err.to_go_m[0] == pytest.approx(-100.0)


def test_several_segments_can_be_passed_in_one_update():
    mgr = WaypointManager(WaypointPath.from_lists([ZIGZAG]), switch_radius_m=10.0)
    err = mgr.update(np.array([[290.0, 150.0]]))
    assert err.segment.tolist() == [2] and err.switched.tolist() == [True]


def test_reset_mask_resets_only_the_masked_boats_and_can_change_their_paths():
    path = WaypointPath.from_lists([ZIGZAG, ZIGZAG])
    g = LOSGuidance(path, LOSConfig(law="ilos"))
    g.update(np.array([[145.0, 3.0], [145.0, 3.0]]), np.zeros(2), DT_S)
    assert g.state.segment.tolist() == [1, 1] and np.all(g.state.y_int != 0)
    new = WaypointPath.from_lists([STRAIGHT, [(0.0, 0.0), (0.0, 100.0)]])
    g.reset(np.array([False, True]), path=new)
    assert g.state.segment.tolist() == [1, 0]
    assert g.state.y_int[0] != 0 and g.state.y_int[1] == 0
    assert g.state.observer_ready.tolist() == [True, False]
    assert g.path.counts.tolist() == [4, 2]
    np.testing.assert_array_equal(g.path.points_m[1, :2], [[0.0, 0.0], [0.0, 100.0]])


# ---------------------------------------------------------------- level 2: closed loop


@pytest.mark.parametrize("law", ["los", "ilos", "alos"])
def test_cross_track_error_vanishes_on_a_line_without_current(calm_plant, law):
    # measured |y_e(120 s)|: los 0.067 m, ilos 0.075 m, alos 0.051 m, but ilos/alos still swing
    # slowly (±0.5 m, period ~60 s: the vessel's sway lags its heading); so the whole last 30 s
    # of 180 s are checked: measured max |y_e| over 150-180 s: los 0.046, ilos 0.229, alos 0.248
    hist, _ = simulate(
        calm_plant,
        LOSGuidance(WaypointPath.from_lists([STRAIGHT]), LOSConfig(law=law)),
        offset_start(),
        180.0,
    )
    assert hist["ye"][0, 0] == pytest.approx(20.0)
    assert np.max(np.abs(hist["ye"][-300:, 0])) < 0.5


def test_plain_los_keeps_the_offset_predicted_for_a_cross_current(current_plant):
    """Heading LOS in a cross current V: steady y_e = −Δ tan(asin(V/U)) (≈ −3.38 m here)."""
    cfg = LOSConfig(law="los")
    hist, _ = simulate(
        current_plant, LOSGuidance(WaypointPath.from_lists([STRAIGHT]), cfg), offset_start(), 180.0
    )
    predicted = -cfg.lookahead_m * np.tan(np.arcsin(CROSS_CURRENT[0] / 3.0))
    final = hist["ye"][-1, 0]  # measured −3.269 m at 180 s (−3.274 m at 120 s)
    assert final == pytest.approx(predicted, abs=0.3)
    # the offset stays: measured |y_e| over 150-180 s between 3.265 and 3.314 m
    assert np.min(np.abs(hist["ye"][-300:, 0])) > 3.0


@pytest.mark.parametrize("law", ["ilos", "alos"])
def test_integral_and_adaptive_los_remove_the_current_offset(current_plant, law):
    # measured |y_e(120 s)|: ilos 0.253 m, alos 0.252 m (plain LOS 3.27 m); max |y_e| over
    # 150-180 s: ilos 0.197 m, alos 0.189 m (plain LOS ≥ 3.265 m)
    hist, _ = simulate(
        current_plant,
        LOSGuidance(WaypointPath.from_lists([STRAIGHT]), LOSConfig(law=law)),
        offset_start(),
        180.0,
    )
    assert np.max(np.abs(hist["ye"][-300:, 0])) < 0.5


def test_waypoint_path_is_followed_segment_by_segment(calm_plant):
    cfg = LOSConfig(law="alos")
    hist, x = simulate(
        calm_plant,
        LOSGuidance(WaypointPath.from_lists([ZIGZAG]), cfg),
        np.array([[0.0, 0.0, 0.0]]),
        180.0,
    )
    seg = hist["seg"][:, 0]
    assert np.all(np.diff(seg) >= 0)  # never goes back
    assert np.unique(seg).tolist() == [0, 1, 2]
    # 540 m at 3 m/s: past the last waypoint (300, 150) and on the extension of the last leg
    assert x[0, 0] > 300.0
    assert abs(x[0, 1] - 150.0) < 1.0  # measured 0.61 m (last turn at 97.7 s)
    assert abs(hist["ye"][-1, 0]) < 1.0


def test_los_observer_bounds_the_reference_jump_at_a_switch(calm_plant):
    path = WaypointPath.from_lists([ZIGZAG])
    eta0 = np.array([[0.0, 0.0, 0.0]])
    raw, _ = simulate(
        calm_plant, LOSGuidance(path, LOSConfig(law="los", observer_omega_radps=None)), eta0, 80.0
    )
    i = int(np.argmax(np.diff(raw["seg"][:, 0]) > 0)) + 1  # first step on segment 1
    raw_jump = abs(raw["ref"][i, 0] - raw["ref"][i - 1, 0])
    assert raw_jump > 1.0  # measured 1.111 rad (≈ 90° turn − atan(R_switch/Δ) = 1.107)

    cfg = LOSConfig(law="los", observer_omega_radps=0.5)
    smooth, _ = simulate(calm_plant, LOSGuidance(path, cfg), eta0, 80.0)
    k1, _ = cfg.observer_gains
    j = int(np.argmax(np.diff(smooth["seg"][:, 0]) > 0)) + 1
    los_jump = abs(smooth["los"][j, 0] - smooth["ref"][j - 1, 0])  # command jump A seen by ψ̂
    # per-step change ≤ h K1 |A| (observer) + h U/Δ (the LOS command's own rate, U ≤ 3.5 m/s)
    bound = DT_S * k1 * los_jump + DT_S * 3.5 / cfg.lookahead_m
    steps = np.abs(np.diff(smooth["ref"][:, 0]))
    assert steps.max() <= bound  # measured 0.111 rad (= h K1 |A|) ≤ bound 0.129 rad
    assert steps.max() <= DT_S * k1 * np.pi  # worst case for any jump, |A| ≤ π
    assert steps.max() < raw_jump / 5


def test_batch_equals_single_boat_runs(calm_plant):
    paths = [ZIGZAG, STRAIGHT, [(10.0, -30.0), (-60.0, 40.0), (-60.0, 200.0)]]
    eta0 = np.array([[0.0, 5.0, 0.3], [0.0, 20.0, 0.0], [0.0, 0.0, -2.0]])
    cfg = LOSConfig(law="alos")
    batched, xb = simulate(calm_plant, LOSGuidance(WaypointPath.from_lists(paths), cfg), eta0, 60.0)
    for i, p in enumerate(paths):
        single, xs = simulate(
            calm_plant, LOSGuidance(WaypointPath.from_lists([p]), cfg), eta0[i : i + 1], 60.0
        )
        for key in ("ref", "ye"):
            assert np.max(np.abs(batched[key][:, i] - single[key][:, 0])) < 1e-12
        np.testing.assert_array_equal(batched["seg"][:, i], single["seg"][:, 0])
        assert np.max(np.abs(xb[i] - xs[0])) < 1e-12


# ---------------------------------------------------------------- bad input


def test_bad_inputs_raise_clear_errors():
    path = WaypointPath.from_lists([STRAIGHT, ZIGZAG])
    g = LOSGuidance(path)
    pos, psi = np.zeros((2, 2)), np.zeros(2)
    with pytest.raises(ValueError, match="pos_m contains NaN"):
        g.update(np.array([[0.0, np.nan], [0.0, 0.0]]), psi, DT_S)
    with pytest.raises(ValueError, match=r"pos_m must have shape \(2, 2\)"):
        g.update(np.zeros((2, 3)), psi, DT_S)
    with pytest.raises(ValueError, match=r"psi_rad must be finite with shape \(2,\)"):
        g.update(pos, np.zeros(3), DT_S)
    with pytest.raises(ValueError, match="psi_rad must be finite"):
        g.update(pos, np.array([0.0, np.inf]), DT_S)
    with pytest.raises(ValueError, match="dt_s must be > 0"):
        g.update(pos, psi, 0.0)
    with pytest.raises(ValueError, match="LOS observer unstable"):
        g.update(pos, psi, 4.0)
    with pytest.raises(ValueError, match="mask must be a boolean array"):
        g.reset(np.array([1, 0]))
    for bad in (0.0, -5.0):
        with pytest.raises(ValueError, match=r"lookahead_m \(Δ\) must be > 0"):
            LOSConfig(lookahead_m=bad)
    with pytest.raises(ValueError, match="must be finite"):
        LOSConfig(lookahead_m=np.nan)
    with pytest.raises(ValueError, match="law must be"):
        LOSConfig(law="pure-pursuit")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="at least 2 are needed"):
        WaypointPath.from_lists([[(0.0, 0.0)]])
    with pytest.raises(ValueError, match="at least 2 waypoints"):
        WaypointPath(points_m=np.zeros((1, 3, 2)), counts=np.array([1]))
    with pytest.raises(ValueError, match="waypoints contain NaN"):
        WaypointPath.from_lists([[(0.0, 0.0), (np.nan, 1.0)]])
    with pytest.raises(ValueError, match="1 mm apart"):
        WaypointPath.from_lists([[(0.0, 0.0), (0.0, 0.0), (5.0, 0.0)]])
    with pytest.raises(ValueError, match="shorter than every segment"):
        LOSGuidance(WaypointPath.from_lists([[(0.0, 0.0), (8.0, 0.0)]]))
