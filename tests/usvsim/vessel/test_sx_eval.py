"""usvsim.vessel.sx_eval: a scalar SX Function evaluated by NumPy gives CasADi's numbers."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from usvsim.vessel.plant import Plant
from usvsim.vessel.sx_eval import numpy_function
from usvsim.vessel.vessels import vessel_names

SPEEDS = np.concatenate(
    [
        np.random.default_rng(3).uniform(-10.0, 40.0, 20_000),
        [0.0, -0.0, 1e-300, -1e-300, 1e300, np.inf, -np.inf, 3.0, 1e-8],
    ]
)


@pytest.mark.parametrize("name", vessel_names())
def test_surge_trim_bit_for_bit(name: str) -> None:
    plant = Plant(name)
    fast = numpy_function(plant._surge_drag)
    assert fast is not None
    reference = np.asarray(plant._surge_drag(SPEEDS[None, :])).ravel()
    got = fast(SPEEDS)
    assert got.shape == SPEEDS.shape and got.dtype == np.float64
    assert np.array_equal(got.view(np.uint64), reference.view(np.uint64))


def test_trim_actuator_uses_the_same_numbers() -> None:
    plant = Plant("default")
    speeds = SPEEDS[:500]
    act = plant.vessel.actuation
    drag = np.asarray(plant._surge_drag(speeds[None, :])).ravel()
    reference = np.clip(drag, act.a1_min, act.a1_max)
    assert np.array_equal(plant.trim_actuator(speeds)[:, 0], reference)


def test_expressions_mixing_ops() -> None:
    x = ca.SX.sym("x")
    fn = ca.Function("f", [x], [ca.fmin(ca.sqrt(ca.fabs(x)) * 3.0 - x / 7.0, 2.0 * x * x) + 1.5])
    fast = numpy_function(fn)
    assert fast is not None
    xs = np.linspace(-50.0, 50.0, 1001)
    assert np.array_equal(fast(xs), np.asarray(fn(xs[None, :])).ravel())


def test_constant_output_broadcasts() -> None:
    x = ca.SX.sym("x")
    fast = numpy_function(ca.Function("c", [x], [ca.SX(4.25)]))
    assert fast is not None
    assert np.array_equal(fast(np.zeros(3)), np.full(3, 4.25))


@pytest.mark.parametrize(
    "build",
    [
        lambda x: ca.sin(x),  # libm: NumPy's SIMD routine may round differently
        lambda x: ca.exp(x) + x,
        lambda x: ca.vertcat(x, x),  # two outputs
    ],
)
def test_refuses_what_it_cannot_reproduce(build) -> None:  # type: ignore[no-untyped-def]
    x = ca.SX.sym("x")
    assert numpy_function(ca.Function("f", [x], [build(x)])) is None


def test_refuses_non_scalar_inputs() -> None:
    x = ca.SX.sym("x", 2)
    assert numpy_function(ca.Function("f", [x], [x[0] + x[1]])) is None
