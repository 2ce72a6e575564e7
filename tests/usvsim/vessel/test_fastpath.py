"""The compiled fast path: exact C-library stand-ins, per-step inputs gathered from a pool."""

from __future__ import annotations

import itertools

import casadi as ca
import numpy as np
import pytest

from usvsim.nav.models import NavConfig
from usvsim.nav.navplant import NavigatedPlant
from usvsim.vessel.codegen import BatchStepper, GatheredSteps
from usvsim.vessel.plant import Plant

SPECIAL = [0.0, -0.0, 1.0, -1.0, 2.5, -7.25, 1e-300, -5e-324, 1e300, np.inf, -np.inf, np.nan]


@pytest.fixture(scope="module")
def libm_steppers() -> tuple[BatchStepper, BatchStepper]:
    s, w, g = ca.SX.sym("s", 3), ca.SX.sym("w", 1), ca.SX.sym("g", 1)
    out = ca.vertcat(ca.fmod(s[0], s[1]), ca.fmax(s[0], s[1]), ca.fmin(s[0], s[1]))
    fn = ca.Function("libm_probe", [s, w, g], [out])
    return BatchStepper(fn, backend="compiled"), BatchStepper(fn, backend="casadi")


def run_pairs(stepper: BatchStepper, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    s0 = np.column_stack([x, y, np.zeros_like(x)])
    return stepper.run(s0, np.zeros((x.size, 1)), np.zeros(1), 1)[:, 0, :]


def test_libm_stand_ins_give_the_c_librarys_bits_on_special_values(libm_steppers):
    compiled, reference = libm_steppers  # reference: CasADi's virtual machine calls the C library
    x, y = np.array(list(itertools.product(SPECIAL, SPECIAL))).T
    a, b = run_pairs(compiled, x, y), run_pairs(reference, x, y)
    assert a.view(np.uint64)[~np.isnan(b)].tolist() == b.view(np.uint64)[~np.isnan(b)].tolist()
    np.testing.assert_array_equal(np.isnan(a), np.isnan(b))


def test_fmod_stand_in_is_exact_near_multiples_of_the_divisor(libm_steppers):
    compiled, _ = libm_steppers
    rng = np.random.default_rng(0)
    y = np.full(20_000, 2.0 * np.pi)  # the heading wrap of every plant step
    k = rng.integers(-10_000, 10_000, y.size).astype(float)
    x = k * y + rng.choice([0.0, 1e-15, -1e-15, 1e-9, 3.0], y.size) * rng.uniform(-1, 1, y.size)
    x[::7] = rng.uniform(-1e6, 1e6, x[::7].size)
    got = run_pairs(compiled, x, y)[:, 0]
    assert got.view(np.uint64).tolist() == np.fmod(x, y).view(np.uint64).tolist()


@pytest.fixture(scope="module")
def fused() -> NavigatedPlant:
    return NavigatedPlant(Plant("default"), NavConfig())


def gathered_inputs(fused: NavigatedPlant, n: int, seed: int):
    rng = np.random.default_rng(seed)
    plant = fused.plant
    eta = np.column_stack([rng.uniform(-50, 50, (n, 2)), rng.uniform(-3, 3, n)])
    start = plant.initial_state(eta)
    nav = rng.normal(0.0, 1.0, (n, 15))
    nav[:, [4, 7, 10, 12]] = 1.0  # variances
    s0 = np.concatenate([start.x, start.c, nav], axis=1)
    w = np.column_stack([rng.uniform(-3, 3, n), np.full(n, 3.0), np.zeros(n), np.zeros(n)])
    normals = rng.standard_normal((n, fused.draws_needed(1, 20)))
    return s0, w, fused.noise_steps(1, 20, normals)


def test_gathered_per_step_input_equals_the_dense_array(fused):
    s0, w, steps = gathered_inputs(fused, 16, 0)
    stepper = fused._stepper
    a = stepper.run(s0, w, fused.plant.gains, 20, steps)
    b = stepper.run(s0, w, fused.plant.gains, 20, steps.dense())
    np.testing.assert_array_equal(a, b)


def test_gathered_dense_array_keeps_signed_zeros_and_constants():
    pool = np.array([[-1.5, 2.0], [0.25, -4.0]])
    index = np.array([[0, 1, -1], [1, 0, -1]], dtype=np.int64)
    factor = np.array([[1.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    dense = GatheredSteps(pool, index, factor).dense()
    np.testing.assert_array_equal(dense[0], [[-1.5, 0.0, 1.0], [2.0, -0.0, 0.0]])
    np.testing.assert_array_equal(dense[1], [[0.25, -0.0, 1.0], [-4.0, 0.0, 0.0]])
    assert np.signbit(dense[0, 1, 1]) and not np.signbit(dense[0, 1, 2])


def test_casadi_backend_takes_gathered_steps(fused):
    s0, w, steps = gathered_inputs(fused, 4, 1)
    slow = BatchStepper(fused.step_function, backend="casadi")
    a = slow.run(s0, w, fused.plant.gains, 20, steps)
    b = fused._stepper.run(s0, w, fused.plant.gains, 20, steps)
    np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-9)


def test_gathered_steps_are_checked(fused):
    s0, w, steps = gathered_inputs(fused, 4, 2)
    run = fused._stepper.run
    too_far = GatheredSteps(steps.pool[:, :3], steps.index, steps.factor)
    with pytest.raises(ValueError, match="past the pool"):
        run(s0, w, fused.plant.gains, 20, too_far)
    with pytest.raises(ValueError, match="index and factor must have shape"):
        run(s0, w, fused.plant.gains, 19, steps)
    with pytest.raises(ValueError, match="pool must have shape"):
        run(s0[:3], w[:3], fused.plant.gains, 20, steps)
