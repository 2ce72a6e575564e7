"""The open-water task on torch (torch-cpu) against the CPU env (``OpenWaterVectorEnv``, scene)
and its NumPy pieces."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import torch

from usvsim.evaluation.stress import STRESS_SETS
from usvsim.task.observations import SCENE_FEATURES, SCENE_K, scene_observation
from usvsim.task.openwater import vessel_motion
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, ScenarioMixture, weather_family
from usvsim.task.scene_distances import PackedDiscs, judge_period
from usvsim.task.torch_openwater import TorchOpenWaterEnv
from usvsim.task.torch_openwater_episodes import family_table, load_table
from usvsim.task.torch_scene import (
    SCENE_FEATURES as TORCH_SCENE_FEATURES,
)
from usvsim.task.torch_scene import (
    SCENE_K as TORCH_SCENE_K,
)
from usvsim.task.torch_scene import (
    TorchDiscs,
    judge_period_torch,
    scene_observation_torch,
    vessel_motion_torch,
)

# every open-water stress set, the weather sets included
OPEN_WATER_SETS = {
    s.name: s.scenario for s in STRESS_SETS if s.kind == "open-water" and s.scenario is not None
}
WEATHER_SETS = sorted(k for k, v in OPEN_WATER_SETS.items() if v.weather is not None)
FLAGS = ("reached_goal", "collision", "out_of_area", "time_limit", "is_success")
TIMES = ("time_s", "time_to_goal_s")


def _policy(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """To the goal, away from the nearest disc within 40 m, plus noise (scene observation)."""
    b_goal, r_near, b_near = obs[:, 1], obs[:, 4], obs[:, 5]
    away = np.where((r_near > 0) & (r_near < 40.0), -np.sign(b_near) * 0.8, 0.0)
    a = b_goal / np.radians(30.0) + away + rng.normal(0.0, 0.3, obs.shape[0])
    return np.clip(a, -1.0, 1.0)[:, None]


def _float32_steps(want: np.ndarray, got: np.ndarray) -> float:
    """Largest difference of ``got`` (float64) rounded to float32 from ``want`` (float32), in
    float32 steps."""
    got32 = got.astype(np.float32)
    gap = np.abs(want.astype(np.float64) - got32.astype(np.float64))
    return float((gap / np.spacing(np.maximum(np.abs(want), np.abs(got32)))).max())


def _run_pair(family: object, n: int, max_decisions: int, seed: int) -> dict[str, float]:
    """Both envs with the same seed and actions until every boat has finished an episode;
    asserts flags and times equal at every step, returns the largest differences."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    cpu = OpenWaterVectorEnv(n, observation="scene", family=family)  # type: ignore[arg-type]
    dev = TorchOpenWaterEnv(n, family=family, per_boat=12, noise="replay",
                            observation_dtype="float64")  # fmt: skip
    o_cpu, _ = cpu.reset(seed=seed)
    o_dev, _ = dev.reset(seed=seed)
    rng = np.random.default_rng(seed)
    worst = {"position_m": 0.0, "heading_rad": 0.0, "reward": 0.0, "distances_m": 0.0,
             "obs_steps": _float32_steps(o_cpu, o_dev.numpy()), "ended": 0.0}  # fmt: skip
    finished = np.zeros(n, dtype=bool)
    for _ in range(max_decisions):
        actions = _policy(o_cpu, rng)
        o_cpu, r_cpu, te_c, tr_c, i_cpu = cpu.step(actions)
        o_dev, r_dev, te_d, tr_d, i_dev = dev.step(torch.as_tensor(actions))
        np.testing.assert_array_equal(te_d.numpy(), te_c)
        np.testing.assert_array_equal(tr_d.numpy(), tr_c)
        for key in FLAGS + TIMES:
            np.testing.assert_array_equal(i_dev[key].numpy(), i_cpu[key], err_msg=key)
        x_cpu, x_dev = cpu.sim.inner.state.x, dev.state.numpy()
        d_cpu = np.stack([i_cpu["distance_to_obstacle_m"], i_cpu["distance_to_goal_m"]])
        d_dev = torch.stack([i_dev["distance_to_obstacle_m"], i_dev["distance_to_goal_m"]]).numpy()
        np.testing.assert_array_equal(np.isfinite(d_dev), np.isfinite(d_cpu))
        fin = np.isfinite(d_cpu)
        for key, value in (
            ("position_m", np.abs(x_cpu[:, :2] - x_dev[:, :2]).max()),
            ("heading_rad", np.abs(np.angle(np.exp(1j * (x_cpu[:, 2] - x_dev[:, 2])))).max()),
            ("reward", np.abs(r_cpu - r_dev.numpy()).max()),
            ("distances_m", np.abs(d_cpu[fin] - d_dev[fin]).max(initial=0.0)),
            ("obs_steps", _float32_steps(o_cpu, o_dev.numpy())),
        ):
            worst[key] = max(worst[key], float(value))
        finished |= te_c | tr_c
        worst["ended"] += float((te_c | tr_c).sum())
        if finished.all():
            break
    assert finished.all(), "every boat should finish an episode within the decisions given"
    return worst


def _assert_equal_figures(worst: dict[str, float]) -> None:
    assert worst["position_m"] <= 1e-6
    assert worst["heading_rad"] <= 1e-8
    assert worst["distances_m"] <= 1e-6
    assert worst["reward"] <= 1e-8
    assert worst["obs_steps"] <= 1.0  # float32 observations: identical or one rounding apart


def test_every_set_at_once_equals_the_cpu_env() -> None:
    """One run over a mixture of every open-water stress set, calm and in weather (each boat's
    episodes from all of them): flags and times identical, trajectories and rewards to
    rounding."""
    names = sorted(OPEN_WATER_SETS)
    mixture = ScenarioMixture(
        members=tuple(OPEN_WATER_SETS[k] for k in names),
        weights=(1.0,) * len(names),
        names=tuple(names),
    )
    worst = _run_pair(mixture, 12, 220, seed=3)
    assert worst["ended"] >= 12
    _assert_equal_figures(worst)


def test_the_training_family_equals_the_cpu_env() -> None:
    worst = _run_pair(OPEN_WATER_FAMILY, 6, 220, seed=1)
    _assert_equal_figures(worst)


def test_the_weather_family_equals_the_cpu_env() -> None:
    """``weather_family()``: calm episodes among the windy ones (each weather stress set alone:
    the slow test below)."""
    assert WEATHER_SETS  # the weather sets are among OPEN_WATER_SETS
    _assert_equal_figures(_run_pair(weather_family(), 6, 220, seed=2))


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(OPEN_WATER_SETS))
def test_each_set_equals_the_cpu_env(name: str) -> None:
    _assert_equal_figures(_run_pair(OPEN_WATER_SETS[name], 8, 250, seed=7))


def test_float32_stays_near_the_cpu_env() -> None:
    """float32 is another run: over the first 15 decisions of 8 boats (before any episode ends)
    the true positions stay within 0.5 m and headings within 0.02 rad of the float64 CPU env."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    fam = OPEN_WATER_SETS["everything"]
    cpu = OpenWaterVectorEnv(8, observation="scene", family=fam)
    dev = TorchOpenWaterEnv(8, family=fam, noise="replay", dtype="float32")
    o_cpu, _ = cpu.reset(seed=2)
    dev.reset(seed=2)
    rng = np.random.default_rng(2)
    worst_p = worst_psi = 0.0
    for _ in range(15):
        a = _policy(o_cpu, rng)
        o_cpu, *_ = cpu.step(a)
        dev.step(torch.as_tensor(a, dtype=torch.float32))
        x_cpu, x_dev = cpu.sim.inner.state.x, dev.state.double().numpy()
        worst_p = max(worst_p, float(np.abs(x_cpu[:, :2] - x_dev[:, :2]).max()))
        dpsi = np.angle(np.exp(1j * (x_cpu[:, 2] - x_dev[:, 2])))
        worst_psi = max(worst_psi, float(np.abs(dpsi).max()))
    assert worst_p < 0.5
    assert worst_psi < 0.02


def _random_discs(rng: np.random.Generator, n: int, k: int, m: int) -> PackedDiscs:
    return PackedDiscs(
        rng.uniform(-80, 80, (n, k, 2)), rng.uniform(1, 20, (n, k)), rng.random((n, k)) < 0.7,
        rng.uniform(-80, 80, (n, m, 2)), rng.uniform(-4, 4, (n, m)), rng.uniform(0, 4, (n, m)),
        np.where(rng.random((n, m)) < 0.5, 0.0, rng.uniform(-0.01, 0.01, (n, m))),
        np.full((n, m), 5.0), rng.random((n, m)) < 0.7,
    )  # fmt: skip


def _torch_discs(d: PackedDiscs) -> TorchDiscs:
    return TorchDiscs(*(torch.as_tensor(a) for a in vars(d).values()))


def test_scene_pieces_equal_their_numpy_originals() -> None:
    """vessel motion, the judge (the reference NumPy path) and the scene observation on random
    scenes: the same numbers (to rounding) and the same flags."""
    assert (TORCH_SCENE_K, TORCH_SCENE_FEATURES) == (SCENE_K, SCENE_FEATURES)
    rng = np.random.default_rng(0)
    n, k, m, steps = 64, 5, 3, 20
    d = _random_discs(rng, n, k, m)
    t = rng.uniform(0, 300, (n, steps))
    pos, vel = vessel_motion(d.vessel_p0_ne[:, :, None], d.vessel_course_rad[:, :, None],
                             d.vessel_speed_mps[:, :, None], d.vessel_turn_radps[:, :, None],
                             t[:, None, :])  # fmt: skip
    args = (d.vessel_p0_ne[:, :, None], d.vessel_course_rad[:, :, None],
            d.vessel_speed_mps[:, :, None], d.vessel_turn_radps[:, :, None],
            t[:, None, :])  # fmt: skip
    tp, tv = vessel_motion_torch(*(torch.as_tensor(a) for a in args))
    np.testing.assert_allclose(tp.numpy(), pos, rtol=0, atol=1e-10)
    np.testing.assert_allclose(tv.numpy(), vel, rtol=0, atol=1e-12)
    traj = rng.uniform(-60, 60, (n, steps, 2))
    goal = traj[:, 7] + rng.uniform(-15, 15, (n, 2))  # some boats reach it
    want = judge_period(traj, t, d, goal, 1.0, 1.0, 10.0, backend="numpy")
    got = judge_period_torch(torch.as_tensor(traj[..., 0]), torch.as_tensor(traj[..., 1]),
                             torch.as_tensor(t), _torch_discs(d), torch.as_tensor(goal), 1.0,
                             1.0, 10.0)  # fmt: skip
    for name in ("collision", "reached_goal", "end_step", "first_goal_step"):
        np.testing.assert_array_equal(getattr(got, name).numpy(), getattr(want, name), name)
    assert want.collision.any() and want.reached_goal.any() and not want.reached_goal.all()
    for name in ("nearest_m", "distance_to_obstacle_m", "distance_to_goal_m"):
        np.testing.assert_allclose(getattr(got, name).numpy(), getattr(want, name), atol=1e-10)
    # the scene observation at one time per boat, fewer valid discs than slots for some boats
    tt = torch.as_tensor(t[:, 0])
    centres, velocity = _torch_discs(d).at(tt)
    own_p, own_psi, own_v = (rng.uniform(-50, 50, (n, 2)), rng.uniform(-4, 4, n),
                             rng.uniform(-3, 3, (n, 2)))  # fmt: skip
    radii = np.concatenate([d.radii_m, d.vessel_radius_m], 1)
    ok = np.concatenate([d.static_ok, d.vessel_ok], 1)
    want_obs = scene_observation(own_p, own_psi, own_v, goal, centres.numpy(), radii,
                                 velocity.numpy(), ok)  # fmt: skip
    got_obs = scene_observation_torch(*(torch.as_tensor(a) for a in (
        own_p, own_psi, own_v, goal, centres.numpy(), radii, velocity.numpy(), ok)))  # fmt: skip
    assert _float32_steps(want_obs, got_obs.numpy()) <= 1.0
    assert (want_obs[:, 4 + 6 * 7 :] == 0).any()  # empty slots exist and stay zeros


def test_same_seed_same_episodes_as_the_cpu_env() -> None:
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    cpu = OpenWaterVectorEnv(4, observation="scene", family=OPEN_WATER_SETS["moving-vessels"])
    cpu.reset(seed=9)
    table = family_table(OPEN_WATER_SETS["moving-vessels"], 9, 4, 3)
    np.testing.assert_array_equal(table.goal_ne[::3], cpu.sim.goal_ne)
    np.testing.assert_array_equal(table.time_limit_s[::3], cpu.sim.time_limit)
    np.testing.assert_array_equal(table.start_eta[::3, :2], cpu.sim.inner.state.x[:, :2])


@pytest.mark.parametrize("family", [OPEN_WATER_FAMILY, weather_family()], ids=["calm", "weather"])
def test_a_saved_table_runs_the_same(tmp_path: object, family: object) -> None:
    path = tmp_path / "table.npz"  # type: ignore[operator]
    table = family_table(family, 4, 6, 4)
    table.save(path)
    assert load_table(path).in_weather == (family is not OPEN_WATER_FAMILY) == table.in_weather
    runs = []
    for env in (TorchOpenWaterEnv(6, family=family, per_boat=4),
                TorchOpenWaterEnv(6, table=load_table(path), per_boat=4)):  # fmt: skip
        obs, _ = env.reset(seed=4)
        for _ in range(3):
            obs, *_ = env.step(torch.zeros((6, 1), dtype=torch.float64))
        runs.append(obs.numpy())
    np.testing.assert_array_equal(runs[0], runs[1])


def test_device_runs_repeat_with_the_seed() -> None:
    def run(seed: int) -> np.ndarray:
        env = TorchOpenWaterEnv(8, family=OPEN_WATER_SETS["everything"])
        obs, _ = env.reset(seed=seed)
        for _ in range(2):
            obs, *_ = env.step(torch.full((8, 1), 0.3, dtype=torch.float64))
        return obs.numpy()

    np.testing.assert_array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))


def test_wrong_options_are_refused() -> None:
    with pytest.raises(ValueError, match="observation must be one of"):
        TorchOpenWaterEnv(2, observation="radar+nav")
    with pytest.raises(ValueError, match="reward_horizon"):
        TorchOpenWaterEnv(2, reward_horizon="forever")  # type: ignore[arg-type]
    env = TorchOpenWaterEnv(2, family=OPEN_WATER_SETS["two-obstacles"])
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"gaussian actions must be floats of shape \(2, 1\)"):
        env.step(torch.zeros(2))


def test_fixed_horizon_equals_the_cpu_env() -> None:
    """``reward_horizon="fixed"``: the terminating steps' rewards as the CPU env's."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    fam = replace(OPEN_WATER_SETS["start-short"], time_factor=1.0)
    cpu = OpenWaterVectorEnv(6, observation="scene", family=fam, reward_horizon="fixed")
    dev = TorchOpenWaterEnv(6, family=fam, noise="replay", reward_horizon="fixed")
    o_cpu, _ = cpu.reset(seed=8)
    dev.reset(seed=8)
    rng = np.random.default_rng(8)
    ended = 0
    for _ in range(36):
        a = _policy(o_cpu, rng)
        o_cpu, r_cpu, te, tr, _ = cpu.step(a)
        _, r_dev, te_d, tr_d, _ = dev.step(torch.as_tensor(a))
        np.testing.assert_array_equal(te_d.numpy(), te)
        np.testing.assert_array_equal(tr_d.numpy(), tr)
        np.testing.assert_allclose(r_dev.numpy(), r_cpu, rtol=1e-9, atol=1e-9)
        ended += int(te.sum())
    assert ended >= 3
    assert not math.isnan(float(r_dev.sum()))


@pytest.mark.parametrize(("observation", "weather"), [("scene", False), ("radar+goal", True)])
def test_a_step_never_reads_a_tensor_back_to_the_host(
    monkeypatch: pytest.MonkeyPatch, observation: str, weather: bool
) -> None:
    """Device noise: steps with restarts, GNSS faults and radar degradation (and weather) read
    no tensor on the host."""
    fam = replace(OPEN_WATER_SETS["start-short"], gnss_outlier_probability_range=(0.05, 0.05),
                  gnss_dropout_probability=1.0, current_speed_range_mps=(0.3, 0.6))  # fmt: skip
    fam = replace(fam, radar_clutter_range=(0.001, 0.001), radar_missed_range=(0.2, 0.2))
    if weather:
        fam = replace(fam, weather=OPEN_WATER_SETS["everything"].weather)
    env = TorchOpenWaterEnv(16, family=fam, observation=observation)  # at the pole: collisions
    env.reset(seed=0)
    actions = torch.zeros((16, 1), dtype=torch.float64)

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a tensor was read back to the host during a step")

    for name in ("__bool__", "item", "tolist", "numpy", "cpu", "__int__", "__float__"):
        monkeypatch.setattr(torch.Tensor, name, refuse)
    ended = []
    for _ in range(12):
        _, _, terminated, truncated, _ = env.step(actions)
        ended.append(terminated | truncated)
    monkeypatch.undo()
    assert bool(torch.stack(ended).any())


def test_perf_figures_stand_beside_the_c_path() -> None:
    from usvsim.task.torch_openwater_speed import torch_openwater_rates

    figures = torch_openwater_rates("torch-cpu", sizes=(8,), seconds=0.1)
    assert set(figures["decision_steps_per_s"]) == {"scene N=8", "radar+goal N=8"}
    rates = figures["decision_steps_per_s"]["radar+goal N=8"]
    assert set(rates) == {"C path", "float64", "float32"} and min(rates.values()) > 0
    ratio = figures["over_C_path"]["radar+goal N=8"]["float32"]
    assert ratio == pytest.approx(rates["float32"] / rates["C path"], rel=0.01, abs=1e-3)


def test_env_runs_from_a_table_without_casadi_scipy_or_gymnasium(tmp_path: object) -> None:
    """The GPU path: a table drawn here, the env run where only torch and NumPy are there."""
    import subprocess
    import sys

    path = tmp_path / "table.npz"  # type: ignore[operator]
    family_table(OPEN_WATER_SETS["everything"], 0, 4, 2).save(path)
    code = (
        "import sys\n"
        "sys.modules.update(casadi=None, gymnasium=None, scipy=None, control=None,\n"
        "                   filterpy=None)\n"
        "import torch\n"
        "from usvsim.task.torch_openwater import TorchOpenWaterEnv\n"
        "from usvsim.task.torch_openwater_episodes import load_table\n"
        f"env = TorchOpenWaterEnv(4, table=load_table({str(path)!r}), per_boat=2)\n"
        "obs, _ = env.reset(seed=0)\n"
        "for _ in range(3):\n"
        "    obs, r, te, tr, info = env.step(torch.zeros((4, 1), dtype=torch.float64))\n"
        "print(tuple(obs.shape), float(r.max()) < 0)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout.split()
    assert out == ["(4,", "52)", "True"]


@pytest.mark.parametrize(
    "name", ["everything", pytest.param("radar-noise", marks=pytest.mark.slow)]
)
def test_radar_goal_observations_equal_the_cpu_env(name: str) -> None:
    """radar+goal over whole episodes (degraded radar: clutter, speckle, misses, noise; restarts
    included): every image pixel for pixel, goal vectors within one float32 step."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv
    from usvsim.task.torch_observations import GOAL_STD

    fam = OPEN_WATER_SETS[name]
    cpu = OpenWaterVectorEnv(6, observation="radar+goal", family=fam)
    dev = TorchOpenWaterEnv(6, family=fam, noise="replay", observation="radar+goal")
    o_cpu, _ = cpu.reset(seed=4)
    o_dev, _ = dev.reset(seed=4)
    rng = np.random.default_rng(4)
    ended = lit = 0
    for _ in range(36):
        np.testing.assert_array_equal(o_dev["radar"].numpy(), o_cpu["radar"])
        assert _float32_steps(o_cpu["goal"], o_dev["goal"].double().numpy()) <= 1.0
        lit += int((o_cpu["radar"] > 0).sum())
        b_goal = o_cpu["goal"][:, 1] * GOAL_STD[1]
        a = np.clip(b_goal / np.radians(30.0) + rng.normal(0, 0.3, 6), -1, 1)[:, None]
        o_cpu, _, te, tr, _ = cpu.step(a)
        o_dev, _, te_d, tr_d, _ = dev.step(torch.as_tensor(a))
        np.testing.assert_array_equal(te_d.numpy() | tr_d.numpy(), te | tr)
        ended += int((te | tr).sum())
    assert ended >= 2 and lit > 0


def test_scene_radar_equals_render_scene() -> None:
    """300 random scenes (poles, islets, a boat inside an islet, bearings past ±π), clean and
    degraded from random frame keys: pixel for pixel; mix64 bit for bit."""
    from usvsim.task.radar import RadarConfig
    from usvsim.task.scene_radar import RadarDegradation, mix64, render_scene, stream_keys
    from usvsim.task.torch_scene_radar import SceneRadarGrid, mix64_torch, render_scene_torch

    rng = np.random.default_rng(0)
    z = rng.integers(0, 2**63, 1000, dtype=np.uint64) * np.uint64(2) + np.uint64(1)
    np.testing.assert_array_equal(
        mix64_torch(torch.as_tensor(z.view(np.int64))).numpy(), mix64(z).view(np.int64)
    )
    n, j = 300, 10
    rho, phi = rng.uniform(0, 220, (n, j)), rng.uniform(-4, 4, (n, j))
    radius = np.where(rng.random((n, j)) < 0.4, 1.0, rng.uniform(1, 30, (n, j)))
    ok = rng.random((n, j)) < 0.8
    levels = [np.where(rng.random(n) < 0.5, rng.uniform(0, 0.01, n), 0.0) for _ in range(3)]
    levels.append(np.where(rng.random(n) < 0.5, rng.uniform(0, 40, n), 0.0))
    keys = stream_keys(rng.integers(0, 2**62, n).tolist(), rng.integers(0, 100, n))
    grid = SceneRadarGrid(RadarConfig(), torch.float64, torch.device("cpu"))
    t = [torch.as_tensor(a) for a in (rho, phi, radius, ok)]
    clean = render_scene(rho, phi, radius, ok)
    np.testing.assert_array_equal(render_scene_torch(*t, grid).numpy(), clean)
    degraded = render_scene(rho, phi, radius, ok, None, RadarDegradation(*levels), keys)
    got = render_scene_torch(
        *t, grid, torch.as_tensor(np.stack(levels, 1)), torch.as_tensor(keys.view(np.int64))
    )
    np.testing.assert_array_equal(got.numpy(), degraded)
    assert (degraded != clean).any() and (clean > 0).any()


def test_positional_observations_equal_the_cpu_env() -> None:
    """positional (the nearest disc by pole-equivalent range; a pole 1 km astern where nothing
    is around): within one float32 step of the CPU env's, flags identical."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    # some boats see nothing
    fam = replace(OPEN_WATER_SETS["moving-vessels"], n_vessels_range=(0, 2))
    cpu = OpenWaterVectorEnv(8, observation="positional", family=fam)
    dev = TorchOpenWaterEnv(8, family=fam, noise="replay", observation="positional",
                            observation_dtype="float64")  # fmt: skip
    o_cpu, _ = cpu.reset(seed=5)
    o_dev, _ = dev.reset(seed=5)
    rng = np.random.default_rng(5)
    nothing = 0
    for _ in range(30):
        assert _float32_steps(o_cpu, o_dev.numpy()) <= 1.0
        nothing += int((o_cpu[:, 0] == 1000.0).sum())
        a = np.clip(o_cpu[:, 3] / np.radians(30.0) + rng.normal(0, 0.3, 8), -1, 1)[:, None]
        o_cpu, _, te, tr, _ = cpu.step(a)
        o_dev, _, te_d, tr_d, _ = dev.step(torch.as_tensor(a))
        np.testing.assert_array_equal(te_d.numpy(), te)
        np.testing.assert_array_equal(tr_d.numpy(), tr)
    assert nothing > 0


@pytest.mark.slow
def test_the_compiled_weather_step_is_one_graph_with_the_same_numbers() -> None:
    """``compile=True`` (backend eager: dynamo's trace, no code generation): the same rewards
    and observations as the eager env over 3 decisions in weather, from one graph (the inputs
    stacked: before, nearly every plant step of a decision compiled anew and, past torch's limit
    of 8, fell back to eager)."""
    import torch._dynamo

    torch._dynamo.reset()
    torch._dynamo.utils.counters.clear()
    runs = []
    for compile_ in (False, True):
        env = TorchOpenWaterEnv(4, family=weather_family(), per_boat=2, compile=compile_,
                                compile_backend="eager")  # fmt: skip
        obs, _ = env.reset(seed=3)
        for _ in range(3):
            obs, r, *_ = env.step(torch.zeros((4, 1), dtype=torch.float64))
        runs.append((obs.numpy(), r.numpy()))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert torch._dynamo.utils.counters["stats"]["unique_graphs"] == 1


def test_info_scene_beside_a_radar_observation_equals_the_cpu_env() -> None:
    """``info_observation="scene"`` (an asymmetric GAIL's view) beside radar+goal: the scene of
    the observation returned, restarts included, as the CPU env's (float32 observations from
    simulations within ~1e-8 of each other: relative 1e-6)."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    fam = OPEN_WATER_SETS["moving-vessels"]
    cpu = OpenWaterVectorEnv(6, observation="radar+goal", family=fam, info_observation="scene")
    dev = TorchOpenWaterEnv(6, family=fam, noise="replay", observation="radar+goal",
                            info_observation="scene", per_boat=16)  # fmt: skip
    _, i_cpu = cpu.reset(seed=2)
    _, i_dev = dev.reset(seed=2)
    rng = np.random.default_rng(2)
    ended = 0
    for _ in range(60):
        np.testing.assert_allclose(i_dev["observation_scene"].numpy(), i_cpu["observation_scene"],
                                   rtol=1e-6, atol=1e-6)  # fmt: skip
        a = rng.uniform(-1, 1, (6, 1))
        _, _, te, tr, i_cpu = cpu.step(a)
        _, _, _, _, i_dev = dev.step(torch.as_tensor(a))
        ended += int((te | tr).sum())
    assert ended >= 1
    with pytest.raises(ValueError, match="info_observation"):
        TorchOpenWaterEnv(2, family=fam, info_observation="radar")
