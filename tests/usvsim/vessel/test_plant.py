"""The batched plant: fast path equals the CasADi Function, batching, reproducibility, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usvsim.vessel.codegen import BatchStepper
from usvsim.vessel.plant import NS, Plant


@pytest.fixture(scope="module")
def plant() -> Plant:
    return Plant("default")


def random_state(plant: Plant, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    eta = np.column_stack(
        [rng.uniform(-100, 100, n), rng.uniform(-100, 100, n), rng.uniform(-math.pi, math.pi, n)]
    )
    return plant.initial_state(eta, speed_mps=rng.uniform(1.0, 4.0, n)), rng


def test_compiled_fast_path_agrees_with_casadi_function(plant):
    assert plant.backend == "compiled"
    state, rng = random_state(plant, 64)
    psi_ref = rng.uniform(-math.pi, math.pi, 64)
    _, traj = plant.step(state, psi_ref, n_steps=20)
    s = np.concatenate([state.x, state.c], axis=1)
    w = np.column_stack([psi_ref, np.full(64, 3.0), np.zeros(64), np.zeros(64)])
    for k in range(20):  # reference: the CasADi Function itself, one boat at a time
        s = np.stack(
            [np.asarray(plant.step_function(s[i], w[i], plant.gains)).ravel() for i in range(64)]
        )
        scale = np.maximum(np.abs(s), 1.0)
        assert np.max(np.abs(traj[:, k, :] - s) / scale) <= 1e-9


def test_casadi_map_backend_equals_compiled(plant):
    slow = BatchStepper(plant.step_function, backend="casadi")
    state, rng = random_state(plant, 8, seed=3)
    s0 = np.concatenate([state.x, state.c], axis=1)
    w = np.column_stack([rng.uniform(-3, 3, 8), np.full(8, 3.0), np.zeros(8), np.zeros(8)])
    a = slow.run(s0, w, plant.gains, 5)
    b = plant._stepper.run(s0, w, plant.gains, 5)
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)


def test_batch_equals_single_boats(plant):
    state, rng = random_state(plant, 5, seed=7)
    psi_ref = rng.uniform(-3, 3, 5)
    batch_state, _ = plant.step(state, psi_ref, n_steps=30)
    for i in range(5):
        from usvsim.vessel.plant import PlantState

        single = PlantState(x=state.x[i : i + 1], c=state.c[i : i + 1])
        one, _ = plant.step(single, psi_ref[i : i + 1], n_steps=30)
        np.testing.assert_array_equal(one.x[0], batch_state.x[i])


def test_trajectory_shape_and_last_row_is_state(plant):
    state, _ = random_state(plant, 3)
    new, traj = plant.step(state, 0.0, n_steps=20)
    assert traj.shape == (3, 20, NS)
    np.testing.assert_array_equal(traj[:, -1, :8], new.x)


def test_current_pushes_boat_sideways():
    still = Plant("default")
    drift = Plant("default", current=(0.5, math.pi / 2))  # flowing east
    s0 = still.initial_state(np.zeros((1, 3)))
    a, _ = still.step(s0, 0.0, n_steps=2000)
    _, traj = drift.step(drift.initial_state(np.zeros((1, 3))), 0.0, n_steps=2000)
    # heading held north: after the sway transient (m/|Y_v| ≈ 22 s) the boat drifts east with
    # the water at 0.5 m/s, while the still-water boat keeps y = 0
    east_speed = (traj[0, -1, 1] - traj[0, -101, 1]) / 10.0
    assert east_speed == pytest.approx(0.5, rel=0.02)
    assert abs(a.x[0, 1]) < 1e-9


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_commands_raise(plant, bad):
    state, _ = random_state(plant, 2)
    with pytest.raises(ValueError, match="psi_ref_rad contains NaN or inf"):
        plant.step(state, np.array([0.0, bad]))
    with pytest.raises(ValueError, match="speed_ref_mps contains NaN or inf"):
        plant.step(state, 0.0, speed_ref_mps=bad)


def test_non_finite_state_and_wrong_shapes_raise(plant):
    state, _ = random_state(plant, 2)
    broken = state.x.copy()
    broken[0, 3] = np.nan
    from usvsim.vessel.plant import PlantState

    with pytest.raises(ValueError, match="plant state contains NaN"):
        plant.step(PlantState(x=broken, c=state.c), 0.0)
    with pytest.raises(ValueError, match=r"psi_ref_rad must be a scalar or have shape \(2,\)"):
        plant.step(state, np.zeros(3))
    with pytest.raises(ValueError, match=r"eta must have shape \(N, 3\)"):
        plant.initial_state(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="n_steps must be a positive integer"):
        plant.step(state, 0.0, n_steps=0)


def test_bad_plant_arguments_raise():
    with pytest.raises(ValueError, match="unknown vessel"):
        Plant("nonexistent")
    with pytest.raises(ValueError, match="dt_s must be in"):
        Plant("default", dt_s=-0.1)
    with pytest.raises(ValueError, match="current must be"):
        Plant("default", current=(-1.0, 0.0))
    with pytest.raises(ValueError, match="backend must be"):
        Plant("default", backend="gpu")  # type: ignore[arg-type]


def test_trim_actuator_looks_up_a_repeated_speed_with_the_same_numbers():
    fresh = Plant("default")
    speeds = np.array([3.0, 3.0, 3.0])
    direct = np.asarray(fresh._surge_drag(speeds[None, :])).ravel()
    first, again = fresh.trim_actuator(speeds), fresh.trim_actuator(speeds[:2])
    np.testing.assert_array_equal(first[:, 0], np.clip(direct, *_a1_range(fresh)))
    np.testing.assert_array_equal(again, first[:2])
    mixed = np.array([1.0, 3.0, 0.0])
    expected = np.clip(np.asarray(fresh._surge_drag(mixed[None, :])).ravel(), *_a1_range(fresh))
    np.testing.assert_array_equal(fresh.trim_actuator(mixed)[:, 0], expected)


def _a1_range(plant: Plant) -> tuple[float, float]:
    return plant.vessel.actuation.a1_min, plant.vessel.actuation.a1_max
