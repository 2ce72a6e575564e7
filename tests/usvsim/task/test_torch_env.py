"""The pole-avoidance task on torch (torch-cpu, float64) against the CPU environment and the
NumPy / CasADi pieces it is generated from or mirrors."""

from __future__ import annotations

import subprocess
import sys

import casadi as ca
import numpy as np
import pytest
import torch

from usvsim.nav.compiled import build_nav_step, nav_noise_block, started_nav_rows
from usvsim.nav.models import NavConfig
from usvsim.nav.torch_nav import load_nav_kernel, noise_layout, started_nav_state
from usvsim.nav.torch_nav_codegen import DEFAULT_NAV_KERNEL_PATH, default_nav_kernel_source
from usvsim.task.batch import heading_change_rad
from usvsim.task.observations import GOAL_STANDARDIZATION, relative_polar
from usvsim.task.radar import RadarConfig, render_radar
from usvsim.task.scenario import BoatNoise, Scenario, draw_episode, episode_geometry
from usvsim.task.torch_env import TorchPoleAvoidanceEnv
from usvsim.task.torch_env_speed import torch_env_rates
from usvsim.task.torch_episodes import episode_geometry_torch
from usvsim.task.torch_observations import (
    GOAL_MEAN,
    GOAL_STD,
    RadarGrid,
    radar_image,
    standardized_goal,
)
from usvsim.task.vector_env import PoleAvoidanceVectorEnv, boat_generators

N_BOATS, N_STEPS, SEED = 16, 160, 11
INFO_KEYS = (
    "reward_pole", "reward_goal", "distance_to_pole_m", "distance_to_goal_m",
    "min_distance_to_pole_m", "time_s", "time_to_goal_s",
)  # fmt: skip
FLAG_KEYS = ("reached_goal", "collision", "out_of_area", "time_limit", "is_success")


def _policy(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Actions (N, 1) in [-1, 1]: steer to the goal, away from a near pole, plus noise (so
    episodes end every way: goal, collision, time limit, out of the area)."""
    r_pole, b_pole, b_goal = obs[:, 0], obs[:, 1], obs[:, 3]
    away = np.where(r_pole < 25.0, -np.sign(b_pole) * 0.8, 0.0)
    a = 1.5 * b_goal / np.radians(30.0) * rng.uniform(-0.5, 1.5, obs.shape[0]) + away
    return np.clip(a + rng.normal(0.0, 0.4, obs.shape[0]), -1.0, 1.0)[:, None]


@pytest.fixture(scope="module")
def replayed() -> dict[str, np.ndarray]:
    """Both envs, the same seed and actions: everything they return, stacked over the steps."""
    cpu = PoleAvoidanceVectorEnv(N_BOATS)
    gpu = TorchPoleAvoidanceEnv(
        N_BOATS, episodes="numpy", episodes_per_boat=12, noise="replay",
        observation_dtype="float64",
    )  # fmt: skip
    c_obs, c_info = cpu.reset(seed=SEED)
    t_obs, t_info = gpu.reset(seed=SEED)
    rec: dict[str, list[np.ndarray]] = {k: [] for k in ("c_obs", "t_obs", "c_est", "t_est")}
    for k in ("c_reward", "t_reward", "c_term", "t_term", "c_trunc", "t_trunc", "c_final",
              "t_final", *(f"c_{k}" for k in INFO_KEYS + FLAG_KEYS),
              *(f"t_{k}" for k in INFO_KEYS + FLAG_KEYS)):  # fmt: skip
        rec[k] = []
    rng = np.random.default_rng(5)
    np.testing.assert_array_equal(t_info["pole_ne"].numpy(), c_info["pole_ne"])
    for _ in range(N_STEPS):
        pos, psi = cpu.sim.estimate
        rec["c_obs"].append(c_obs)
        rec["t_obs"].append(t_obs.numpy())
        rec["c_est"].append(np.column_stack([pos, psi, *relative_polar(
            pos, psi, np.stack([cpu.sim.pole_ne, cpu.sim.goal_ne], 1))]))  # fmt: skip
        t_pos, t_psi = gpu.estimate
        rec["t_est"].append(np.column_stack([t_pos.numpy(), t_psi.numpy()]))
        actions = _policy(c_obs, rng)
        c_obs, c_r, c_te, c_tr, c_inf = cpu.step(actions)
        t_obs, t_r, t_te, t_tr, t_inf = gpu.step(torch.as_tensor(actions))
        rec["c_reward"].append(c_r)
        rec["t_reward"].append(t_r.numpy())
        rec["c_term"].append(c_te)
        rec["t_term"].append(t_te.numpy())
        rec["c_trunc"].append(c_tr)
        rec["t_trunc"].append(t_tr.numpy())
        done = c_te | c_tr
        final = np.full((N_BOATS, 4), np.nan)
        if done.any():
            final[done] = np.stack(list(c_inf["final_obs"][done]))
        rec["c_final"].append(final)
        rec["t_final"].append(np.where(done[:, None], t_inf["final_obs"].numpy(), np.nan))
        for k in INFO_KEYS + FLAG_KEYS:
            rec[f"c_{k}"].append(np.asarray(c_inf[k]))
            rec[f"t_{k}"].append(t_inf[k].numpy())
    return {k: np.stack(v) for k, v in rec.items()}


def test_replayed_episodes_end_every_way_and_restart(replayed: dict[str, np.ndarray]) -> None:
    done = replayed["c_term"] | replayed["c_trunc"]
    assert done.sum(axis=0).min() >= 2  # every boat finished at least two episodes
    assert replayed["c_reached_goal"].sum() >= 10 and replayed["c_collision"].sum() >= 3
    assert replayed["c_time_limit"].any() or replayed["c_out_of_area"].any()


def test_flags_equal_the_cpu_env(replayed: dict[str, np.ndarray]) -> None:
    np.testing.assert_array_equal(replayed["t_term"], replayed["c_term"])
    np.testing.assert_array_equal(replayed["t_trunc"], replayed["c_trunc"])
    for k in FLAG_KEYS:
        np.testing.assert_array_equal(replayed[f"t_{k}"], replayed[f"c_{k}"], err_msg=k)


def test_rewards_and_info_equal_the_cpu_env(replayed: dict[str, np.ndarray]) -> None:
    """float64 on torch-cpu: rewards within 1e-8 (measured 1.0e-9), distances within 1e-6 m
    (measured 2.2e-7 m), times equal; see the observations' test for why not closer."""
    assert np.abs(replayed["t_reward"] - replayed["c_reward"]).max() <= 1e-8
    for k in INFO_KEYS:
        bound = 0.0 if k.startswith("time") else 1e-8 if k.startswith("reward") else 1e-6
        np.testing.assert_allclose(replayed[f"t_{k}"], replayed[f"c_{k}"], rtol=0, atol=bound)


def test_observations_equal_the_cpu_env(replayed: dict[str, np.ndarray]) -> None:
    """The estimate and the observation from it in float64: within 1e-9 over the first 10
    decisions (measured 4e-13), then positions and ranges within 1e-6 m (measured 2.2e-7 m),
    the estimated heading within 1e-8 rad (4.3e-9) and bearings within 1e-7 rad (7.5e-9).
    The closed loop (filter → heading reference → autopilot) amplifies last-bit differences
    (torch's sin and cos, the C kernel's fused multiply-adds) over an episode: the CPU env on
    CasADi's VM differs from its compiled C kernel by as much (benchmarks/torch_env_equality.py).
    The float32 observations (the CPU env's type) are equal up to one
    float32 rounding step (or 1e-7 where the float64 numbers already differ by that)."""
    c_est, t_est, t_obs = replayed["c_est"], replayed["t_est"], replayed["t_obs"]
    expected = c_est[..., [3, 5, 4, 6]]  # r_pole, φ_pole, r_goal, φ_goal from the CPU estimate
    assert np.abs(t_est[:10] - c_est[:10, :, 0:3]).max() <= 1e-9
    assert np.abs(t_obs[:10] - expected[:10]).max() <= 1e-9
    assert np.abs(t_est[..., 0:2] - c_est[..., 0:2]).max() <= 1e-6  # m
    assert np.abs(t_est[..., 2] - c_est[..., 2]).max() <= 1e-8  # rad
    assert np.abs(t_obs[..., 0::2] - expected[..., 0::2]).max() <= 1e-6  # m
    assert np.abs(t_obs[..., 1::2] - expected[..., 1::2]).max() <= 1e-7  # rad

    def close32(got: np.ndarray, want: np.ndarray) -> bool:
        got, want = got.astype(np.float32), want.astype(np.float32)
        return bool(np.all(np.abs(got - want) <= np.maximum(np.spacing(np.abs(want)), 1e-7)))

    assert close32(t_obs, replayed["c_obs"])
    final_t, final_c = replayed["t_final"], replayed["c_final"]
    np.testing.assert_array_equal(np.isnan(final_t), np.isnan(final_c))
    ok = ~np.isnan(final_c)
    assert close32(final_t[ok], final_c[ok])


def test_committed_nav_kernel_is_what_the_generator_writes_today() -> None:
    assert DEFAULT_NAV_KERNEL_PATH.read_text() == default_nav_kernel_source(), (
        "regenerate it: python -m usvsim.nav.torch_nav_codegen"
    )


def test_generated_nav_step_equals_the_casadi_function() -> None:
    """One filter step from 512 random filter states, plant states and noise, sensors firing or
    not, against CasADi's evaluation."""
    rng = np.random.default_rng(2)
    n = 512
    nav = np.column_stack([
        rng.uniform(-300, 300, (n, 2)), rng.uniform(-4, 4, (n, 2)), rng.uniform(0.1, 3, n),
        rng.uniform(-0.5, 0.5, (n, 2)), rng.uniform(0.01, 1, n), rng.uniform(-9, 9, n),
        rng.uniform(-0.01, 0.01, n), rng.uniform(1e-4, 1e-2, n), rng.uniform(-1e-5, 1e-5, n),
        rng.uniform(1e-7, 1e-6, n), rng.uniform(-0.01, 0.01, n), rng.uniform(-0.3, 0.3, n),
    ])  # fmt: skip
    x = np.column_stack([rng.uniform(-300, 300, (n, 2)), rng.uniform(-9, 9, n),
                         rng.uniform(0, 4, n), rng.uniform(-1, 1, n), rng.uniform(-0.4, 0.4, n),
                         rng.uniform(-1e4, 3e4, n), rng.uniform(-0.5, 0.5, n)])  # fmt: skip
    e = np.column_stack([rng.standard_normal((n, 6)), rng.integers(0, 2, (n, 2))])
    expected = np.asarray(build_nav_step(NavConfig()).map(n)(nav.T, x.T, e.T)).T
    kernel = load_nav_kernel()
    assert kernel.origin == "committed"

    def cols(a: np.ndarray) -> list[torch.Tensor]:
        return [torch.as_tensor(c.copy()) for c in a.T]

    got = torch.stack(kernel.step(cols(nav), cols(x), cols(e)), 1).numpy()
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)


def test_noise_layout_is_the_navigators_draw_order() -> None:
    cfg, kernel = NavConfig(), load_nav_kernel()
    for first in (1, 2, 21):
        layout = noise_layout(kernel, first, 20)
        probe = np.arange(1.0, layout.draws + 1.0)[None, :]  # column c holds c + 1
        block = nav_noise_block(cfg, first, 20, probe)[0]
        index = np.array(layout.index)
        np.testing.assert_array_equal(np.where(index >= 0, index + 1.0, 0.0), block[:, :6])
        np.testing.assert_array_equal(np.array(layout.gps, dtype=float), block[:, 6])
        np.testing.assert_array_equal(np.array(layout.compass, dtype=float), block[:, 7])


def test_started_filter_equals_the_numpy_start() -> None:
    rng = np.random.default_rng(4)
    k = 9
    x = np.zeros((k, 8))
    x[:, 0:2] = rng.uniform(-100, 100, (k, 2))
    x[:, 2:6] = rng.uniform(-3, 3, (k, 4))
    seeds = [int(s) for s in rng.integers(2**63, size=k)]
    noise = BoatNoise(k)
    noise.seed(np.arange(k), seeds)
    expected = started_nav_rows(NavConfig(), x[:, 0:3], x[:, 3:6], noise)  # type: ignore[arg-type]
    replay = BoatNoise(k)
    replay.seed(np.arange(k), seeds)
    z = torch.as_tensor(replay.standard_normal((k, 7)))
    got = started_nav_state(load_nav_kernel(), torch.as_tensor(x.T.copy()), z).T.numpy()
    # velocity: NumPy's complex product, rounded its own way (one bit at most)
    np.testing.assert_allclose(got, expected, rtol=4e-16, atol=0)


def test_episode_draws_and_geometry_equal_the_cpu_envs() -> None:
    sc = Scenario(heading_offset_range_rad=(-0.5, 0.5))
    gens = boat_generators(3, 40)  # gymnasium's seeding: default_rng(seed + i)
    specs = [draw_episode(g, sc) for g in gens]
    again = [draw_episode(np.random.default_rng(40 + i), sc) for i in range(3)]
    assert specs == again
    geo = episode_geometry(sc, specs)

    def t(values: list[float]) -> torch.Tensor:
        return torch.tensor(values, dtype=torch.float64)

    poles = torch.tensor(sc.poles_ne, dtype=torch.float64)
    index = torch.tensor([s.pole_index for s in specs])
    pole, eta, goal = episode_geometry_torch(
        sc, poles, index, t([s.start_distance_m for s in specs]),
        t([s.start_bearing_rad for s in specs]), t([s.heading_offset_rad for s in specs]),
    )  # fmt: skip
    np.testing.assert_array_equal(pole.numpy(), geo.pole_ne)
    np.testing.assert_array_equal(eta.numpy(), geo.start_eta)
    np.testing.assert_array_equal(goal.numpy(), geo.goal_ne)


def test_device_draws_follow_the_scenario() -> None:
    env = TorchPoleAvoidanceEnv(4096)
    env.reset(seed=0)
    d = torch.linalg.vector_norm(env.state[:, 0:2] - env.pole_ne, dim=1).numpy()
    assert 50.0 <= d.min() and d.max() <= 100.0 and abs(d.mean() - 75.0) < 1.0  # U[50, 100]
    share = (env.pole_ne[:, 0] == 0.0).double().mean().item()
    assert abs(share - 0.5) < 0.04  # two poles, equally likely
    goal = torch.linalg.vector_norm(env.goal_ne - env.state[:, 0:2], dim=1).numpy()
    np.testing.assert_allclose(goal, 220.0, rtol=1e-12)


def test_spaces_are_the_cpu_envs() -> None:
    for kind in ("positional", "radar+goal"):
        env = TorchPoleAvoidanceEnv(2, observation=kind, action="categorical")
        cpu = PoleAvoidanceVectorEnv(2, observation=kind, action="categorical")  # type: ignore[arg-type]
        assert env.single_observation_space == cpu.single_observation_space
        assert env.single_action_space == cpu.single_action_space
        obs, _ = env.reset(seed=0)
        if isinstance(obs, dict):
            row: object = {k: v[0].numpy() for k, v in obs.items()}
        else:
            row = obs[0].numpy()
        assert env.single_observation_space.contains(row)


def test_categorical_actions_map_as_the_cpu_env() -> None:
    env = TorchPoleAvoidanceEnv(41, action="categorical")
    k = np.arange(41)
    got = env.heading_change_rad(torch.as_tensor(k)).numpy()
    np.testing.assert_array_equal(got, heading_change_rad("categorical", k, 41, np.radians(30)))


def test_device_noise_estimates_as_well_as_the_cpu_env() -> None:
    """Noise from the device generator: another draw, the same filter quality (position error
    RMS of 64 boats over 20 decisions within 25 % of the CPU env's on the same episodes)."""
    errors = []
    for noise in ("replay", "device"):
        env = TorchPoleAvoidanceEnv(64, episodes="numpy", noise=noise)  # type: ignore[arg-type]
        env.reset(seed=1)
        sq = []
        for _ in range(20):
            env.step(torch.zeros((64, 1), dtype=torch.float64) + 0.3)
            pos, _ = env.estimate
            sq.append(((pos - env.state[:, 0:2]) ** 2).sum(1))
        errors.append(float(torch.stack(sq).mean().sqrt()))
    assert 0.2 < errors[0] < 2.0  # m: the filter beats raw GNSS (1.5 m per axis)
    assert abs(errors[1] / errors[0] - 1.0) < 0.25


def test_same_seed_same_run_on_the_device() -> None:
    def run(seed: int) -> np.ndarray:
        env = TorchPoleAvoidanceEnv(8)
        obs, _ = env.reset(seed=seed)
        out = [obs]
        for _ in range(5):
            out.append(env.step(torch.full((8, 1), 0.5))[0])
        return torch.stack(out).numpy()

    np.testing.assert_array_equal(run(3), run(3))
    assert not np.array_equal(run(3), run(4))


def test_torch_env_runs_without_casadi_scipy_filterpy_or_gymnasium() -> None:
    """The GPU path: only torch and NumPy (the others hidden)."""
    code = (
        "import sys\n"
        "sys.modules.update(casadi=None, gymnasium=None, scipy=None, control=None,\n"
        "                   filterpy=None)\n"
        "import torch\n"
        "from usvsim.task.torch_env import TorchPoleAvoidanceEnv\n"
        "env = TorchPoleAvoidanceEnv(4, episodes='numpy')\n"
        "obs, _ = env.reset(seed=0)\n"
        "for _ in range(3):\n"
        "    obs, r, te, tr, info = env.step(torch.zeros((4, 1)))\n"
        "print(env.nav.origin, tuple(obs.shape), float(r.max()) < 0)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout.split()
    assert out == ["committed", "(4,", "4)", "True"]


def test_wrong_actions_and_options_are_refused() -> None:
    env = TorchPoleAvoidanceEnv(2)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"gaussian actions must be floats of shape \(2, 1\)"):
        env.step(torch.zeros(2))
    with pytest.raises(ValueError, match="observation must be one of"):
        TorchPoleAvoidanceEnv(2, observation="scene")
    with pytest.raises(ValueError, match="clutter"):
        TorchPoleAvoidanceEnv(2, radar=RadarConfig(clutter_probability=0.01))
    with pytest.raises(ValueError, match="needs episodes='numpy'"):
        TorchPoleAvoidanceEnv(2, noise="replay")
    assert isinstance(ca.SX, type)  # CasADi present in the test run (the generator needs it)


def test_perf_figures_stand_beside_the_c_path() -> None:
    figures = torch_env_rates("torch-cpu", sizes=(8,), seconds=0.1)
    rates = figures["env_steps_per_s"]["N=8"]
    assert set(rates) == {"C path", "float64", "float32"} and min(rates.values()) > 0
    ratio = figures["over_C_path"]["N=8"]["float64"]
    assert ratio == pytest.approx(rates["float64"] / rates["C path"], rel=0.01, abs=1e-3)


def test_radar_image_equals_render_radar() -> None:
    """Ranges near and beyond 200 m, bearings across the field of view's edges and ±π, a pole
    so close that its box wraps past ±π."""
    rng = np.random.default_rng(8)
    rho = np.concatenate([rng.uniform(0.0, 220.0, 500), [0.5, 1.2, 199.0, 201.5, 0.0]])
    phi = np.concatenate([rng.uniform(-4.0, 4.0, 500), [3.1, -3.1, 2.09, -2.1, 0.0]])
    for radius in (1.0, 3.0):
        expected = render_radar(rho, phi, radius, RadarConfig())
        grid = RadarGrid.build(RadarConfig(), torch.float64, torch.device("cpu"))
        got = radar_image(torch.as_tensor(rho), torch.as_tensor(phi), radius, grid)
        np.testing.assert_array_equal(got.numpy(), expected)
    assert expected[:, 0].any(axis=(1, 2)).sum() > 200  # most poles are in view


def test_goal_vector_equals_the_cpu_envs() -> None:
    assert GOAL_MEAN == GOAL_STANDARDIZATION.mean and GOAL_STD == GOAL_STANDARDIZATION.std
    x = np.random.default_rng(3).uniform(-50.0, 300.0, (64, 2))
    got = standardized_goal(torch.as_tensor(x[:, 0]), torch.as_tensor(x[:, 1])).numpy()
    np.testing.assert_array_equal(got, GOAL_STANDARDIZATION.apply(x))


def test_radar_goal_observations_equal_the_cpu_env() -> None:
    """radar+goal, 16 boats x 40 decisions replayed (restarts included): the images equal pixel
    for pixel, the goal vectors to one float32 step."""
    cpu = PoleAvoidanceVectorEnv(N_BOATS, observation="radar+goal")
    env = TorchPoleAvoidanceEnv(N_BOATS, observation="radar+goal", episodes="numpy", noise="replay")
    c_obs, _ = cpu.reset(seed=SEED)
    t_obs, _ = env.reset(seed=SEED)
    rng = np.random.default_rng(6)
    done = 0
    for _ in range(40):
        assert isinstance(t_obs, dict)
        np.testing.assert_array_equal(t_obs["radar"].numpy(), c_obs["radar"])
        want = c_obs["goal"]
        assert np.all(np.abs(t_obs["goal"].numpy() - want) <= np.spacing(np.abs(want)))
        b_goal = want[:, 1] * GOAL_STANDARDIZATION.std[1]
        a = np.clip(2.0 * b_goal + rng.normal(0.0, 0.5, N_BOATS), -1.0, 1.0)[:, None]
        c_obs, _, c_te, c_tr, _ = cpu.step(a)
        t_obs, _, t_te, t_tr, _ = env.step(torch.as_tensor(a))
        np.testing.assert_array_equal(t_te.numpy() | t_tr.numpy(), c_te | c_tr)
        done += int((c_te | c_tr).sum())
    assert done >= 10


def test_a_step_never_reads_a_tensor_back_to_the_host(monkeypatch: pytest.MonkeyPatch) -> None:
    """The device path (device episodes and noise) steps and restarts boats without reading a
    tensor's value on the host (each read would wait for a GPU): every way to read one raises."""
    env = TorchPoleAvoidanceEnv(32, observation="radar+goal")
    env.reset(seed=0)
    actions = torch.zeros((32, 1))  # straight at the pole: collisions within 20 decisions

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a tensor was read back to the host during a step")

    for name in ("__bool__", "item", "tolist", "numpy", "cpu", "__int__", "__float__"):
        monkeypatch.setattr(torch.Tensor, name, refuse)
    ended = []
    for _ in range(20):
        _, _, terminated, truncated, _ = env.step(actions)
        ended.append(terminated | truncated)
    monkeypatch.undo()
    assert bool(torch.stack(ended).any())  # restarts happened inside the watched steps
