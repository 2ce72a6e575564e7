"""The plant in wind and waves (usvsim.vessel.weather_plant, issue 38): the compiled weather
step equals the calm plant bit for bit without weather, its loads equal the NumPy references,
and its gusts and wave motion have the designed statistics."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from usvsim.common.errors import UserError
from usvsim.vessel.autopilot import AutopilotConfig
from usvsim.vessel.codegen import BatchStepper
from usvsim.vessel.plant import Plant
from usvsim.vessel.weather.loads import USV105_HULL, drift_loads, wind_loads
from usvsim.vessel.weather.waves import (
    WaveResponse,
    drift_pressure,
    mean_drift_force,
    sea_state_from_code,
    wave_displacement,
)
from usvsim.vessel.weather.wind import wind_forces
from usvsim.vessel.weather_plant import (
    SeaConditions,
    WeatherPlant,
    WeatherPlantState,
    wave_offsets,
)


def _poses(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    eta = np.c_[rng.uniform(-100, 100, (n, 2)), rng.uniform(-3, 3, n)]
    return eta, rng.uniform(-math.pi, math.pi, n)


@pytest.mark.parametrize(
    ("backend", "autopilot"),
    [("casadi", "pid"), ("casadi", "rover"), ("soa", "pid"), ("scalar", "pid"), ("soa", "rover")],
)
def test_no_weather_gives_the_calm_plant(backend: str, autopilot: str) -> None:
    """No wind, calm sea, wave filter on (it stays off where there are no waves), a current:
    after 300 steps the plant and autopilot states equal Plant.step's bit for bit in CasADi's
    virtual machine (every weather term is an exact zero). Compiled, the weather kernel is another
    C function, so the compiler contracts (FMA) and packs some operations differently: agreement
    to 1e-9 m and 1e-9 rad, not bits. The calm Plant itself is unchanged (its own tests)."""
    plant = Plant(
        "default",
        autopilot=AutopilotConfig.from_name(autopilot),
        current=(0.4, 1.0),
        backend=backend,  # type: ignore[arg-type]
    )
    weather = WeatherPlant(plant, seed=3)
    assert weather.kernel == plant.kernel == backend
    n = 48
    eta, ref = _poses(n)
    _, calm = plant.step(plant.initial_state(eta), ref, n_steps=300)
    start = weather.initial_state(eta, SeaConditions.uniform(n))
    _, wavy = weather.step(start, ref, n_steps=300)
    if backend == "casadi":
        assert np.array_equal(calm, wavy[:, :, :13])
    else:
        np.testing.assert_allclose(wavy[:, :, :3], calm[:, :, :3], rtol=0, atol=1e-9)
        np.testing.assert_allclose(wavy[:, :, :13], calm, rtol=1e-9, atol=1e-9)


def test_kernel_wind_load_is_the_excess_over_still_air() -> None:
    nu, psi, v, beta = (ca.SX.sym(k, n) for k, n in (("nu", 3), ("psi", 1), ("v", 1), ("b", 1)))
    f = ca.Function("w", [nu, psi, v, beta], [wind_loads(USV105_HULL, nu, psi, v, beta)])
    rng = np.random.default_rng(2)
    for _ in range(20):
        state = rng.normal(size=3) * [3.0, 1.0, 0.2]
        heading, speed, direction = rng.uniform(-3, 3), rng.uniform(0.5, 20), rng.uniform(-3, 3)
        got = np.asarray(f(state, heading, speed, direction)).ravel()
        want = (
            wind_forces(state[None], [heading], [speed], [direction])[0]
            - wind_forces(state[None], [heading], [0.0], [direction])[0]
        )
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-9)
    # at rest: the whole wind force; without wind: exactly nothing, moving or not
    at_rest = np.asarray(f([0, 0, 0], 0.0, 10.0, math.pi / 2)).ravel()
    want = wind_forces(np.zeros((1, 3)), [0], [10], [math.pi / 2])[0]
    np.testing.assert_allclose(at_rest, want, rtol=1e-12, atol=1e-9)
    assert at_rest[1] == pytest.approx(833.765625, rel=1e-9)  # ½ ρ V² c_y A_L, to starboard
    assert np.all(np.asarray(f([3.0, 0.5, 0.1], 0.3, 0.0, 1.0)) == 0.0)


def test_kernel_drift_load_equals_the_reference_at_every_heading() -> None:
    psi, p, beta = (ca.SX.sym(k) for k in ("psi", "p", "b"))
    f = ca.Function("d", [psi, p, beta], [drift_loads(USV105_HULL, psi, p, beta)])
    sea = sea_state_from_code(4)
    pressure = drift_pressure([sea.hs_m], [sea.tp_s])[0]
    # following seas meet only the stern transom (3.5 m wide, normal -x): X = p_d 3.5 m ahead
    assert mean_drift_force([sea.hs_m], [sea.tp_s], [0.0], [0.0])[0, 0] == pytest.approx(
        3.5 * pressure, rel=1e-12
    )
    for heading in np.linspace(-math.pi, math.pi, 13):
        want = mean_drift_force([sea.hs_m], [sea.tp_s], [0.7], [heading])[0]
        got = np.asarray(f(heading, pressure, 0.7)).ravel()
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_beam_wind_pushes_the_boat_downwind_and_a_calm_sea_does_not() -> None:
    """10 m/s wind towards east on boats holding north at 3 m/s: the track drifts east, at a
    rate between 0 and the drift of a boat at rest (0.573 m/s, test_weather)."""
    plant = Plant("default")
    weather = WeatherPlant(plant, seed=0)
    n = 8
    eta = np.zeros((n, 3))
    cond = SeaConditions.uniform(n, 10.0, math.pi / 2, gust_intensity=0.0)
    end, _ = weather.step(weather.initial_state(eta, cond), np.zeros(n), n_steps=1200)
    east_rate = end.x[:, 1] / 120.0  # m/s
    assert np.all(east_rate > 0.05)
    assert np.all(east_rate < 0.573)
    assert np.ptp(end.x[:, 1]) < 1e-9  # no gusts, no waves: every boat the same


def test_same_seed_same_weather_other_seed_other_gusts() -> None:
    plant = Plant("default")
    n = 6
    eta, ref = _poses(n)
    cond = SeaConditions.uniform(n, 12.0, 1.0, sea_state_from_code(3, 2.0))
    runs = []
    for seed in (5, 5, 6):
        weather = WeatherPlant(plant, seed=seed)
        runs.append(weather.step(weather.initial_state(eta, cond), ref, n_steps=200)[1])
    assert np.array_equal(runs[0], runs[1])
    assert not np.allclose(runs[0], runs[2])


@pytest.mark.parametrize("backend", ["soa", "scalar", "casadi"])
def test_step_equals_the_numpy_drawn_full_trajectory(backend: str) -> None:
    """WeatherPlant.step (its uniforms generated in the kernel, Pcg64Uniforms; [x, c] recorded;
    blocks of 16 boats) gives the numbers of the path it replaced bit for bit: the uniforms
    drawn by NumPy's Generator.random((N, T, 3)), the whole [x, c, m] recorded at every step,
    blocks of 8; the end states, the weather_states trajectory and the generator after two
    calls equal too."""
    plant = Plant("default", backend=backend)  # type: ignore[arg-type]
    n = 37  # a partial block
    eta, ref = _poses(n, seed=4)
    cond = SeaConditions.uniform(n, 10.0, 1.0, sea_state_from_code(4, 2.0))
    weather = WeatherPlant(plant, seed=11)
    state = start = weather.initial_state(eta, cond)
    twin = WeatherPlant(plant, seed=11)
    twin_state = twin.initial_state(eta, cond)
    # the step function in a stepper of the default block (8 boats; the plant's has 16)
    reference = BatchStepper(twin.step_function, backend)  # type: ignore[arg-type]
    for steps, full in ((7, False), (30, True)):
        state, traj = weather.step(state, ref, n_steps=steps, weather_states=full)
        w = np.c_[ref, np.full(n, plant.cruise_speed_mps), np.tile(plant.current, (n, 1))]
        s0 = np.c_[twin_state.x, twin_state.c, twin_state.m]
        draws = twin.rng.random((n, steps, 3))
        want = reference.run(s0, np.c_[w, start.inputs], plant.gains, steps, draws)
        end = want[:, -1]
        twin_state = WeatherPlantState(end[:, :8], end[:, 8:13], end[:, 13:], start.inputs)
        np.testing.assert_array_equal(traj, want if full else want[:, :, :13])
        np.testing.assert_array_equal(np.c_[state.x, state.c, state.m], want[:, -1])
    np.testing.assert_array_equal(weather.rng.random(3), twin.rng.random(3))


def test_gusts_and_wave_motion_have_their_stationary_spread() -> None:
    """Gust std σ_g = I V̄ = 1 m/s; wave elevation std H_s / 4 (sea state 4: 0.47 m)."""
    plant = Plant("default")
    weather = WeatherPlant(plant, seed=9)
    n = 256
    sea = sea_state_from_code(4, 0.5)
    cond = SeaConditions.uniform(n, 10.0, 0.0, sea, gust_intensity=0.1)
    start = weather.initial_state(np.zeros((n, 3)), cond)
    _, traj = weather.step(start, 0.0, n_steps=600, weather_states=True)
    gust, elevation = traj[:, ::20, 13], traj[:, ::20, 15]
    assert gust.std() == pytest.approx(1.0, rel=0.05)
    assert elevation.std() == pytest.approx(sea.hs_m / 4, rel=0.05)


def test_sensed_wave_motion_is_the_reference_displacement() -> None:
    """wave_offsets (the kernel's sensed wave motion) equals waves.wave_displacement for the
    kernel's wave state, and sea state 4 from 45° off the bow yaws the compass visibly."""
    plant = Plant("default")
    weather = WeatherPlant(plant, seed=1)
    n = 16
    cond = SeaConditions.uniform(n, sea=sea_state_from_code(4, math.radians(135)))
    state, _ = weather.step(weather.initial_state(np.zeros((n, 3)), cond), 0.0, n_steps=50)
    omega = state.inputs[:, 6]
    resp = WaveResponse(omega, np.full(n, 0.1), np.ones(n))  # only ω₀ enters the displacement
    want = wave_displacement(state.m[:, 1:3], resp, cond.wave_dir_rad, state.x[:, 2])
    np.testing.assert_allclose(wave_offsets(state), want, rtol=1e-12, atol=1e-15)
    assert np.std(want[:, 2]) > math.radians(0.5)


def test_bad_conditions_raise_one_line() -> None:
    plant = Plant("default")
    weather = WeatherPlant(plant)
    bad = SeaConditions.uniform(2, wind_speed_mps=10.0)
    bad = SeaConditions(
        bad.wind_speed_mps * 5, bad.wind_dir_rad, bad.gust_intensity, bad.hs_m, bad.tp_s,
        bad.wave_dir_rad,
    )  # fmt: skip
    with pytest.raises(UserError, match="wind speed"):
        weather.initial_state(np.zeros((2, 3)), bad)
    with pytest.raises(UserError, match="finite numbers"):
        weather.initial_state(np.zeros((3, 3)), SeaConditions.uniform(2))


class _Uniforms:
    """A Generator stand-in whose random() returns given numbers."""

    def __init__(self, values: np.ndarray) -> None:
        self.values = values

    def random(self, shape: tuple[int, ...]) -> np.ndarray:
        assert shape == self.values.shape
        return self.values


def test_weather_step_has_a_torch_twin_equal_to_the_c_kernel() -> None:
    """The weather step generated as torch code (usvsim.vessel.torch_codegen, the calm torch
    kernel's generator) on torch-cpu in float64 follows the compiled C kernel: 16 boats in 10 m/s
    wind and sea state 4, filter on, 300 steps, positions within 1e-9 m (measured 1.1e-11 m)."""
    torch = pytest.importorskip("torch")
    from usvsim.vessel.torch_codegen import torch_function_source

    plant = Plant("default")
    weather = WeatherPlant(plant, seed=2)
    n, steps = 16, 300
    eta, ref = _poses(n, 4)
    start = weather.initial_state(
        eta, SeaConditions.uniform(n, 10.0, 1.0, sea_state_from_code(4, 2.4))
    )
    uniforms = np.random.default_rng(8).random((n, steps, 3))
    weather.rng = _Uniforms(uniforms)  # type: ignore[assignment]
    _, traj = weather.step(start, ref, n_steps=steps)
    namespace: dict[str, object] = {"torch": torch, "math": math}
    exec(torch_function_source(weather.step_function, "wx_step", "weather step"), namespace)
    step = namespace["wx_step"]
    s = [torch.tensor(c) for c in np.concatenate([start.x, start.c, start.m], axis=1).T]
    w = np.zeros((n, 4 + start.inputs.shape[1]))
    w[:, 0], w[:, 1], w[:, 4:] = ref, plant.cruise_speed_mps, start.inputs
    w_cols = [torch.tensor(c) for c in w.T]
    g_cols = [torch.tensor(float(v), dtype=torch.float64) for v in plant.gains]
    worst = 0.0
    for k in range(steps):
        e_cols = [torch.tensor(c) for c in uniforms[:, k, :].T]
        s = list(step(s, w_cols, g_cols, e_cols))  # type: ignore[operator]
        pos = np.stack([s[0].numpy(), s[1].numpy()], axis=1)
        worst = max(worst, float(np.abs(pos - traj[:, k, 0:2]).max()))
    assert worst <= 1e-9, worst
