"""Tests of usvsim.common.angles: the one smallest signed angle, for numbers and for CasADi."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from usvsim.common.angles import ssa, ssa_casadi, ssa_float


@pytest.fixture(scope="module")
def ssa_function() -> ca.Function:
    x = ca.SX.sym("x")
    return ca.Function("ssa", [x], [ssa_casadi(x)])


def test_ssa_maps_into_the_half_open_interval_and_keeps_the_angle() -> None:
    a = np.random.default_rng(0).uniform(-100.0, 100.0, 100_000)
    wrapped = ssa(a)
    assert wrapped.min() >= -np.pi and wrapped.max() < np.pi
    turns = (a - wrapped) / (2.0 * np.pi)
    np.testing.assert_allclose(turns, np.round(turns), rtol=0, atol=1e-12)
    assert float(ssa(np.pi)) == -np.pi  # the interval is closed at -π, open at +π
    assert float(ssa(3 * np.pi / 2)) == -np.pi / 2


def test_casadi_ssa_gives_numpys_bits(ssa_function: ca.Function) -> None:
    rng = np.random.default_rng(1)
    a = np.concatenate([rng.uniform(-50.0, 50.0, 50_000), np.arange(-20, 21) * np.pi, [0.0, -0.0]])
    got = np.array(ssa_function(ca.DM(a))).ravel()
    assert got.view(np.uint64).tolist() == ssa(a).view(np.uint64).tolist()


def test_casadi_ssa_stays_below_pi_where_numpys_rounds_up(ssa_function: ca.Function) -> None:
    # just below -π, a + π = -4.4e-16 and NumPy's mod rounds 2π - 4.4e-16 up to 2π (→ +π);
    # the second fmod of the CasADi form folds that back to -π
    a = np.nextafter(-np.pi, -np.inf)
    assert float(ssa(a)) == np.pi
    assert float(ssa_function(a)) == -np.pi


def test_scalar_ssa_gives_numpys_bits() -> None:
    rng = np.random.default_rng(2)
    a = np.concatenate([
        rng.uniform(-50.0, 50.0, 20_000), np.arange(-20, 21) * np.pi, [0.0, -0.0, 1e-300],
        [np.nextafter(-np.pi, -np.inf), np.nextafter(np.pi, np.inf), 1e9, -1e9],
    ])  # fmt: skip
    got = np.array([ssa_float(float(x)) for x in a])
    assert got.view(np.uint64).tolist() == ssa(a).view(np.uint64).tolist()
