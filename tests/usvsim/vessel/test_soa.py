"""The structure-of-arrays kernel equals the CasADi Function and the scalar kernel (1e-9)."""

from __future__ import annotations

import math
import os

import casadi as ca
import numpy as np
import pytest

from usvsim.nav.models import NavConfig
from usvsim.nav.navplant import NavigatedPlant
from usvsim.vessel import codegen
from usvsim.vessel.autopilot import AutopilotConfig, AutopilotKind
from usvsim.vessel.codegen import BatchStepper, CompileError
from usvsim.vessel.pcg64 import Pcg64Uniforms
from usvsim.vessel.plant import Plant
from usvsim.vessel.soa import BLOCK, SoaUnsupportedError, soa_source
from usvsim.vessel.vessels import VESSELS

RTOL = 1e-9


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max(|b|, 1): relative for large entries, absolute below 1."""
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1.0)))


def random_inputs(plant: Plant, n: int, seed: int):
    """States off trim (sway, yaw rate, nozzle, controller), references and currents, all
    random; the inputs (N, 13), (N, 4) of the closed-loop step."""
    rng = np.random.default_rng(seed)
    eta = np.column_stack([rng.uniform(-200, 200, (n, 2)), rng.uniform(-math.pi, math.pi, n)])
    cruise = plant.cruise_speed_mps
    state = plant.initial_state(eta, speed_mps=rng.uniform(0.2, 1.5, n) * cruise)
    act = plant.vessel.actuation
    x = state.x.copy()
    x[:, 4] = rng.normal(0.0, 0.1 * cruise, n)  # sway
    x[:, 5] = rng.normal(0.0, 0.2, n)  # yaw rate
    x[:, 7] = rng.uniform(act.a2_min, act.a2_max, n)
    c = state.c + rng.normal(0.0, 0.2, state.c.shape)
    w = np.column_stack(
        [
            rng.uniform(-math.pi, math.pi, n),  # heading reference
            rng.uniform(0.3, 1.2, n) * cruise,  # speed reference
            rng.uniform(0.0, 0.3 * cruise, n),  # current speed
            rng.uniform(-math.pi, math.pi, n),  # current direction
        ]
    )
    return np.concatenate([x, c], axis=1), w


@pytest.mark.parametrize("kind", ["pid", "rover"])
@pytest.mark.parametrize("vessel", sorted(VESSELS))
def test_soa_equals_casadi_function_and_scalar_kernel(vessel: str, kind: AutopilotKind) -> None:
    plant = Plant(vessel, AutopilotConfig(kind=kind))
    fn = plant.step_function
    s0, w = random_inputs(plant, 77, seed=len(vessel))  # 77: two full blocks and a partial one
    steppers = {k: BatchStepper(fn, k) for k in ("soa", "scalar", "casadi")}
    assert steppers["soa"].kernel == "soa" and steppers["scalar"].kernel == "scalar"
    traj = {k: st.run(s0, w, plant.gains, 30) for k, st in steppers.items()}
    assert np.all(np.isfinite(traj["casadi"]))
    assert relative_error(traj["soa"], traj["casadi"]) <= RTOL
    assert relative_error(traj["soa"], traj["scalar"]) <= RTOL
    # the reference moves: the comparison is not one of states that stay put
    assert np.max(np.abs(traj["casadi"][:, -1, :3] - s0[:, :3])) > 1.0


def test_plant_uses_the_soa_kernel_by_default_and_keeps_scalar_selectable() -> None:
    assert Plant("default")._stepper.kernel == "soa"
    scalar = Plant("default", backend="scalar")
    assert scalar._stepper.kernel == "scalar" and scalar.backend == "compiled"
    assert Plant("default", backend="casadi")._stepper.kernel == "casadi"


@pytest.mark.parametrize("n", [1, BLOCK - 1, BLOCK, BLOCK + 1])
def test_block_edges_give_the_same_boats(n: int) -> None:
    plant = Plant("default")
    s0, w = random_inputs(plant, BLOCK + 1, seed=5)
    every = BatchStepper(plant.step_function, "soa").run(s0, w, plant.gains, 7)
    part = BatchStepper(plant.step_function, "soa").run(s0[:n], w[:n], plant.gains, 7)
    assert relative_error(part, every[:n]) <= RTOL


def test_gathered_per_step_inputs_of_the_navigated_plant() -> None:
    fused = NavigatedPlant(Plant("default"), NavConfig())
    assert fused.backend == "compiled" and fused._stepper.kernel == "soa"
    n, rng = 40, np.random.default_rng(3)
    s_plant, w = random_inputs(fused.plant, n, seed=3)
    nav = rng.normal(0.0, 1.0, (n, 15))
    nav[:, [4, 7, 10, 12]] = 1.0  # variances
    s0 = np.concatenate([s_plant, nav], axis=1)
    steps = fused.noise_steps(0, 20, rng.standard_normal((n, fused.draws_needed(0, 20))))
    fn, g = fused.step_function, fused.plant.gains
    traj = {k: BatchStepper(fn, k).run(s0, w, g, 20, steps) for k in ("soa", "scalar", "casadi")}
    assert relative_error(traj["soa"], traj["casadi"]) <= RTOL
    assert relative_error(traj["soa"], traj["scalar"]) <= RTOL
    dense = BatchStepper(fn, "soa").run(s0, w, g, 20, steps.dense())
    np.testing.assert_array_equal(dense, traj["soa"])


@pytest.fixture(scope="module")
def trig() -> BatchStepper:
    s, w, g = ca.SX.sym("s", 2), ca.SX.sym("w", 1), ca.SX.sym("g", 1)
    fn = ca.Function("trig_probe", [s, w, g], [ca.vertcat(ca.sin(s[0]), ca.cos(s[0]))])
    return BatchStepper(fn, "soa")


def run_trig(stepper: BatchStepper, x: np.ndarray) -> np.ndarray:
    s0 = np.column_stack([x, np.zeros_like(x)])
    return stepper.run(s0, np.zeros((x.size, 1)), np.zeros(1), 1)[:, 0, :]


def test_inline_sin_cos_within_one_ulp_of_the_c_library(trig: BatchStepper) -> None:
    rng = np.random.default_rng(0)
    k = rng.integers(-60_000, 60_000, 50_000)
    x = np.concatenate(
        [
            rng.uniform(-4.0, 4.0, 100_000),
            rng.uniform(-9.9e4, 9.9e4, 100_000),
            k * (np.pi / 2) * (1.0 + rng.uniform(-1e-15, 1e-15, k.size)),  # near k pi/2
            rng.uniform(-1e-9, 1e-9, 1000),
            [0.0, -0.0, 5e-324, -1e-300, np.pi / 4, -np.pi / 4, np.pi / 2, np.pi, 3 * np.pi / 2],
        ]
    )
    got = run_trig(trig, x)
    for col, ref in ((0, [math.sin(v) for v in x]), (1, [math.cos(v) for v in x])):
        exact = np.asarray(ref)
        ulps = np.abs(got[:, col] - exact) / np.spacing(np.abs(exact))
        assert ulps.max() <= 1.0
    assert np.signbit(got[x == 0.0, 0]).tolist() == np.signbit(x[x == 0.0]).tolist()


def test_trig_and_fmod_outside_the_stand_ins_range_give_the_c_librarys_bits(
    trig: BatchStepper,
) -> None:
    x = np.array([1e5, -3e7, 1e300, np.inf, -np.inf, np.nan, 0.5, 2.0])  # one block
    got = run_trig(trig, x)
    ref = np.column_stack(
        [
            np.array([math.sin(v) if math.isfinite(v) else np.nan for v in x]),
            np.array([math.cos(v) if math.isfinite(v) else np.nan for v in x]),
        ]
    )
    ok = ~np.isnan(ref)
    assert got.view(np.uint64)[ok].tolist() == ref.view(np.uint64)[ok].tolist()
    np.testing.assert_array_equal(np.isnan(got), np.isnan(ref))


def test_plant_with_a_huge_heading_falls_back_and_stays_equal() -> None:
    plant = Plant("default")
    s0, w = random_inputs(plant, 8, seed=9)
    s0[3, 2] = 4e7  # heading far outside the stand-ins' range: the block goes to the C library
    a = BatchStepper(plant.step_function, "soa").run(s0, w, plant.gains, 3)
    b = BatchStepper(plant.step_function, "casadi").run(s0, w, plant.gains, 3)
    assert relative_error(a, b) <= RTOL
    assert -math.pi <= a[3, 0, 2] <= math.pi  # wrapped by the exact fmod


def test_portable_builds_equal_the_native_one(monkeypatch: pytest.MonkeyPatch) -> None:
    plant = Plant("default")
    s0, w = random_inputs(plant, 20, seed=11)
    native = BatchStepper(plant.step_function, "soa")
    assert native.build == "native+libmvec"
    portable = [b for b in codegen.SOA_BUILDS if b[0].startswith("portable")]
    monkeypatch.setattr(codegen, "SOA_BUILDS", tuple(portable))
    fallback = BatchStepper(plant.step_function, "soa")
    assert fallback.build == "portable+libmvec"
    a = fallback.run(s0, w, plant.gains, 10)
    assert relative_error(a, native.run(s0, w, plant.gains, 10)) <= RTOL


def test_a_failing_native_build_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    bad = ("native-broken", [*codegen.SOA_BUILDS[0][1], "-mno-such-option"])
    monkeypatch.setattr(codegen, "SOA_BUILDS", (bad, codegen.SOA_BUILDS[-1]))
    stepper = BatchStepper(Plant("default").step_function, "soa")
    assert stepper.build == "portable"


def test_without_a_compiler_auto_uses_casadi_and_soa_says_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", "/nonexistent")
    fn = Plant("default").step_function
    assert BatchStepper(fn, "auto").kernel == "casadi"
    with pytest.raises(CompileError, match="no C compiler"):
        BatchStepper(fn, "soa")


def test_unsupported_operation_is_reported() -> None:
    s, w, g = ca.SX.sym("s", 1), ca.SX.sym("w", 1), ca.SX.sym("g", 1)
    fn = ca.Function("erf_probe", [s, w, g], [ca.erf(s)])
    with pytest.raises(SoaUnsupportedError, match="operation"):
        soa_source(fn, "")
    assert BatchStepper(fn, "compiled").kernel == "scalar"  # compiled falls back to scalar


def test_bad_backend_names_the_allowed_ones() -> None:
    with pytest.raises(ValueError, match="auto, compiled, soa, scalar, casadi"):
        BatchStepper(Plant("default").step_function, "fast")  # type: ignore[arg-type]


def test_kernel_rates_side_by_side_rank_the_vectorised_kernel_first() -> None:
    from usvsim.evaluation.perf import kernel_rates

    rates = kernel_rates(256, seconds=0.6, rounds=3)
    assert set(rates) == {"soa", "scalar", "casadi_map"}
    # interleaved turns: machine load slows all alike (measured 4-60x apart; bars kept loose)
    assert rates["soa"] > rates["casadi_map"] > 0


def test_fmod_stand_in_gives_the_c_librarys_bits_for_constant_and_variable_divisors() -> None:
    s, w, g = ca.SX.sym("s", 2), ca.SX.sym("w", 1), ca.SX.sym("g", 1)
    # a constant divisor (the heading wrap's 2 pi: its reciprocal folded) and a variable one
    out = ca.vertcat(ca.fmod(s[0], 2 * math.pi), ca.fmod(s[0], s[1]))
    stepper = BatchStepper(ca.Function("fmod_probe", [s, w, g], [out]), "soa")
    rng = np.random.default_rng(4)
    n = 60_000
    x = rng.uniform(-1, 1, n) * 10.0 ** rng.uniform(-300, 17, n)
    y = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-5, 5, n)
    k = rng.integers(-(2**40), 2**40, n // 4).astype(float)
    x[: n // 4] = k * y[: n // 4] + rng.choice([0.0, 1e-15, -1e-12], n // 4)  # near multiples
    x[n // 4 : n // 2] = k * (2 * math.pi) * (1.0 + rng.uniform(-1e-15, 1e-15, n // 4))
    got = stepper.run(np.column_stack([x, y]), np.zeros((n, 1)), np.zeros(1), 1)[:, 0, :]
    assert got[:, 0].view(np.uint64).tolist() == np.fmod(x, 2 * math.pi).view(np.uint64).tolist()
    assert got[:, 1].view(np.uint64).tolist() == np.fmod(x, y).view(np.uint64).tolist()


def test_a_boats_numbers_do_not_depend_on_its_batch() -> None:
    plant = Plant("default")
    stepper = BatchStepper(plant.step_function, "soa")
    s0, w = random_inputs(plant, 3 * BLOCK + 3, seed=12)
    s0[BLOCK + 2, 2] = 4e7  # a neighbour the C library must step (heading out of range)
    batch = stepper.run(s0, w, plant.gains, 12)
    for i in (0, 5, BLOCK + 1, BLOCK + 3, 3 * BLOCK + 2):
        alone = stepper.run(s0[i : i + 1], w[i : i + 1], plant.gains, 12)
        np.testing.assert_array_equal(alone[0], batch[i])


@pytest.mark.parametrize("preset", [None, "ACTIVE"])
def test_openmp_threads_wait_passively_unless_the_user_chose(
    monkeypatch: pytest.MonkeyPatch, preset: str | None
) -> None:
    if preset is None:
        monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    else:
        monkeypatch.setenv("OMP_WAIT_POLICY", preset)
    BatchStepper(Plant("default").step_function, "soa")
    assert os.environ["OMP_WAIT_POLICY"] == (preset or "PASSIVE")


@pytest.mark.parametrize("kernel", ["soa", "scalar", "casadi"])
def test_pcg64_uniforms_are_numpys_draws_bit_for_bit(kernel: str) -> None:
    """Per-step inputs generated by the drivers from a PCG64 state (Pcg64Uniforms) are
    Generator.random((N, n_sub, 3)) of that generator, bit for bit (a step that returns its
    per-step input records them; 37 boats: a partial block), and the generator moves past
    them as random() would, its buffered 32-bit half kept."""
    s, w, g, e = (ca.SX.sym(name, size) for name, size in (("s", 3), ("w", 1), ("g", 1), ("e", 3)))
    stepper = BatchStepper(ca.Function("echo", [s, w, g, e], [e + 0.0 * s]), kernel)
    assert stepper.kernel == kernel
    n, n_sub = 37, 11
    rng = np.random.default_rng(2026)
    rng.integers(0, 2**31, dtype=np.uint32)  # leaves a buffered 32-bit half
    twin = np.random.default_rng(2026)
    twin.integers(0, 2**31, dtype=np.uint32)
    draws = Pcg64Uniforms.take(rng, n * n_sub * 3)
    assert draws is not None
    traj, last = stepper.run_recorded(
        np.zeros((n, 3)), np.zeros((n, 1)), np.zeros(1), n_sub, draws, 2
    )
    want = twin.random((n, n_sub, 3))
    np.testing.assert_array_equal(traj, want[:, :, :2])
    np.testing.assert_array_equal(last, want[:, -1])
    np.testing.assert_array_equal(
        rng.integers(0, 2**31, size=5, dtype=np.uint32),
        twin.integers(0, 2**31, size=5, dtype=np.uint32),
    )
    np.testing.assert_array_equal(rng.random(4), twin.random(4))
    assert Pcg64Uniforms.take(np.random.Generator(np.random.MT19937(0)), 3) is None
