"""Throughput measurements for ``usvsim perf`` (figures, not adjectives).

A *boat-substep* is one 0.1 s plant step (autopilot + RK4) of one boat; a *decision step* is one
environment step (20 plant steps + navigation + observation) of one boat.

Why this module is long: it is the one home of every figure ``usvsim perf`` prints (plant
kernels, torch plant, envs, open water, the profile), all timed by the same few helpers.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from usvsim.task.observations import ObservationKind
from usvsim.task.vector_env import PoleAvoidanceVectorEnv
from usvsim.vessel.codegen import BatchStepper
from usvsim.vessel.plant import Plant

__all__ = [
    "env_throughput",
    "kernel_rates",
    "measure_plant",
    "open_water_env_throughput",
    "open_water_figures",
    "open_water_speed_table",
    "open_water_throughput",
    "per_boat_loop_rate",
    "profile_steps",
    "run_perf",
    "scene_radar_rates",
    "stress_set_throughput",
    "torch_plant_rates",
]


def _timed_rate(work: Callable[[], int], seconds: float) -> float:
    """Call ``work`` (returns units done) repeatedly for about ``seconds``; units per second."""
    work()  # warm-up (compilation, caches)
    done, start = 0, time.perf_counter()
    while True:
        done += work()
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            return done / elapsed


def measure_plant(plant: Plant, n_boats: int, seconds: float = 1.0) -> float:
    """Boat-substeps per second of the batched plant at ``n_boats`` (20 substeps per call)."""
    rng = np.random.default_rng(0)
    eta = np.column_stack([np.zeros((n_boats, 2)), rng.uniform(-np.pi, np.pi, n_boats)])
    state = plant.initial_state(eta)
    psi_ref = rng.uniform(-np.pi, np.pi, n_boats)

    def work() -> int:
        nonlocal state
        state, _ = plant.step(state, psi_ref, n_steps=20)
        return n_boats * 20

    return _timed_rate(work, seconds)


def kernel_rates(n_boats: int = 1024, seconds: float = 1.0, rounds: int = 3) -> dict[str, float]:
    """Boat-substeps per second of the default plant with each kernel, measured in the same run.

    ``soa`` (structure-of-arrays C, the default), ``scalar`` (CasADi-generated scalar C) and
    ``casadi_map`` (CasADi's ``Function.map(N, "thread", 2)`` in its virtual machine): each gets
    ``rounds`` turns of ``seconds / rounds``, interleaved so that a change of machine load hits
    all alike; the median turn is reported.
    """
    plants = {
        "soa": Plant("default", backend="soa"),
        "scalar": Plant("default", backend="scalar"),
        "casadi_map": Plant("default", backend="casadi"),
    }
    turns: dict[str, list[float]] = {name: [] for name in plants}
    for _ in range(rounds):
        for name, plant in plants.items():
            turns[name].append(measure_plant(plant, n_boats, seconds / rounds))
    return {name: float(np.median(rates)) for name, rates in turns.items()}


DTYPES = ("float64", "float32")  # the torch plant's number types, measured side by side


def torch_plant_rates(
    device: str, sizes: tuple[int, ...] | None = None, seconds: float = 1.0, rounds: int = 3
) -> dict[str, Any]:
    """Boat-substeps per second of the torch plant (:class:`usvsim.vessel.torch_plant.TorchPlant`
    on ``device``, float64 and float32, at each of ``sizes`` boats; default N = 1024 on the CPU,
    also 2^20 on a GPU) beside the C kernel's at N = 1024, in the same run: ``rounds``
    interleaved turns of ``seconds / rounds`` each, the median reported (issue 40)."""
    import torch

    from usvsim.vessel.torch_plant import TorchPlant, torch_device

    on_gpu = torch_device(device).type == "cuda"  # a one-line UserError where no GPU is seen
    sizes = sizes or ((1024, 2**20) if on_gpu else (1024,))
    c_plant = Plant("default")
    plants = {dtype: TorchPlant("default", device=device, dtype=dtype) for dtype in DTYPES}
    turns: dict[str, list[float]] = {}
    for _ in range(rounds):
        turns.setdefault("C kernel N=1024", []).append(
            measure_plant(c_plant, 1024, seconds / rounds)
        )
        for dtype, plant in plants.items():
            for n in sizes:
                rate = measure_torch_plant(plant, n, seconds / rounds, torch.cuda.synchronize)
                turns.setdefault(f"{dtype} N={n}", []).append(rate)
    rates = {name: float(np.median(r)) for name, r in turns.items()}
    c_rate = rates["C kernel N=1024"]
    return {
        "device": device,
        "boat_substeps_per_s": {name: round(rate) for name, rate in rates.items()},
        "over_C_kernel_N=1024": {
            name: float(f"{rate / c_rate:.3g}")
            for name, rate in rates.items()
            if "C kernel" not in name
        },
        "load_average_1min": _load_average(),
    }


def measure_torch_plant(
    plant: Any, n_boats: int, seconds: float, synchronize: Callable[[], None]
) -> float:
    """Boat-substeps per second of a :class:`usvsim.vessel.torch_plant.TorchPlant` at
    ``n_boats`` (20 substeps per call, no trajectory kept; ``synchronize`` waits for a GPU)."""
    import torch

    rng = np.random.default_rng(0)
    eta = np.column_stack([np.zeros((n_boats, 2)), rng.uniform(-np.pi, np.pi, n_boats)])
    state = plant.initial_state(eta)
    psi_ref = torch.as_tensor(
        rng.uniform(-np.pi, np.pi, n_boats), dtype=plant.dtype, device=plant.device
    )
    on_gpu = plant.device.type == "cuda"

    def work() -> int:
        nonlocal state
        state, _ = plant.step(state, psi_ref, n_steps=20, trajectory=False)
        if on_gpu:
            synchronize()
        return n_boats * 20

    return _timed_rate(work, seconds)


def per_boat_loop_rate(plant: Plant, n_boats: int = 32, seconds: float = 1.0) -> float:
    """Boat-substeps per second of a plain Python loop calling the CasADi Function per boat."""
    rng = np.random.default_rng(0)
    state = plant.initial_state(np.zeros((n_boats, 3)))
    s = np.concatenate([state.x, state.c], axis=1)
    w = np.column_stack(
        [
            rng.uniform(-np.pi, np.pi, n_boats),
            np.full(n_boats, 3.0),
            np.zeros(n_boats),
            np.zeros(n_boats),
        ]
    )
    fn, gains = plant.step_function, plant.gains

    def work() -> int:
        for i in range(n_boats):
            s[i] = np.asarray(fn(s[i], w[i], gains)).ravel()
        return n_boats

    return _timed_rate(work, seconds)


def _load_average() -> float | None:
    """The 1-minute load average (figures depend on it), None where the OS has none."""
    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


def run_perf(seconds: float = 1.0, env: bool = True, device: str = "cpu") -> dict[str, Any]:
    """All throughput figures as a JSON-ready dict; with a torch ``device`` (``torch-cpu``,
    ``cuda``) also the torch plant's beside the C kernel's (:func:`torch_plant_rates`)."""
    plant = Plant("default")
    loop = per_boat_loop_rate(plant, seconds=seconds)
    n1 = measure_plant(plant, 1, seconds)
    n1024 = measure_plant(plant, 1024, seconds)
    kernels = kernel_rates(1024, 3.0 * seconds)
    stepper = BatchStepper(plant.step_function)  # the plant's choice of kernel, to name it
    result: dict[str, Any] = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "processor": platform.machine(),
        },
        "plant": {
            "backend": plant.backend,
            "kernel": stepper.kernel,
            "build": stepper.build,
            "boat_substeps_per_s": {"N=1": round(n1), "N=1024": round(n1024)},
            "per_boat_python_loop_boat_substeps_per_s": round(loop),
            "batched_N1024_over_loop": round(n1024 / loop, 1),
            # the same run, interleaved: the kernels side by side (issue 17)
            "kernels_N=1024_boat_substeps_per_s": {k: round(v) for k, v in kernels.items()},
            "soa_over_scalar": round(kernels["soa"] / kernels["scalar"], 2),
            "soa_over_casadi_map": round(kernels["soa"] / kernels["casadi_map"], 1),
            "load_average_1min": _load_average(),
            "targets": {"N=1024": 20_000_000, "ratio": 100, "soa_over_casadi_map": 3},
        },
    }
    if device != "cpu":
        result["torch_plant"] = torch_plant_rates(device, seconds=3.0 * seconds)
    if env:
        result["env"] = _env_figures(seconds)
        result["open_water"] = open_water_figures(seconds)
        result["everything_set"] = _everything_figures(seconds)
        result["scene_radar"] = scene_radar_rates(256, seconds)
    return result


def scene_radar_rates(n_boats: int = 256, seconds: float = 1.0) -> dict[str, Any]:
    """Degraded scene radar images per second, the compiled kernel against the NumPy path in the
    same run (:func:`usvsim.task.scene_radar.render_scene`): ``n_boats`` boats, each with 4
    islets and vessels (4-20 m) and 4 poles within 200 m, clutter, speckle, misses and noise."""
    from usvsim.task.scene_radar import RadarDegradation, RadarStreams, render_scene

    rng = np.random.default_rng(0)
    shape = (n_boats, 8)
    rho, phi = rng.uniform(5.0, 200.0, shape), rng.uniform(-np.pi, np.pi, shape)
    radius = np.concatenate([rng.uniform(4.0, 20.0, (n_boats, 4)), np.ones((n_boats, 4))], 1)
    ok = np.ones(shape, dtype=bool)
    q = RadarDegradation(*(np.full(n_boats, x) for x in (0.001, 0.5, 0.2, 40.0)))
    streams = RadarStreams(n_boats)
    streams.seed(range(n_boats), range(n_boats))
    rates: dict[str, float] = {}
    for backend in ("compiled", "numpy"):

        def frame(b: Any = backend) -> int:
            keys = streams.frame_keys(slice(None))
            return render_scene(rho, phi, radius, ok, None, q, keys, backend=b).shape[0]

        try:
            rates[backend] = _timed_rate(frame, seconds)
        except ValueError:  # no C compiler: no compiled figure
            continue
    figures: dict[str, Any] = {f"{k} images/s": round(v) for k, v in rates.items()}
    if len(rates) == 2:
        figures["compiled_over_numpy"] = round(rates["compiled"] / rates["numpy"], 1)
    return figures


def open_water_figures(seconds: float) -> dict[str, Any]:
    """The open-water batch at N = 256: the study's one pole, and a busy scene (6 static
    discs, 3 vessels per boat), positional and radar (issue 16)."""
    figures: dict[str, Any] = {}
    for obs in ("positional", "radar+goal", "scene"):
        for label, statics, vessels in (("1 pole", 0, 0), ("6 obstacles + 3 vessels", 5, 3)):
            if obs == "scene" and statics == 0:
                continue
            rate = open_water_throughput(obs, 256, statics, vessels, seconds)
            figures[f"{obs} N=256, {label}"] = round(rate)
    return {"decision_steps_per_s": figures}


def open_water_throughput(
    observation: ObservationKind, n_boats: int, n_extra: int, n_vessels: int, seconds: float = 2.0
) -> float:
    """Decision steps per second of :class:`usvsim.task.openwater_batch.OpenWaterBatch` with
    the study's pole plus ``n_extra`` static discs and ``n_vessels`` vessels per boat (random
    Gaussian actions; boats keep going after their episode ends, as the cost per step is the
    same)."""
    from dataclasses import replace

    from usvsim.task.openwater import OpenWaterScenario, draw_open_water
    from usvsim.task.openwater_batch import OpenWaterBatch

    sc = replace(
        OpenWaterScenario(),
        n_extra_range=(n_extra, n_extra),
        islet_probability=0.5,
        n_vessels_range=(n_vessels, n_vessels),
    )
    sim = OpenWaterBatch(n_boats, observation=observation)
    sim.reset(None, draw_open_water(sc, 0, n_boats))
    return _decision_rate(sim.step, n_boats, seconds)


def stress_set_throughput(
    set_name: str, observation: ObservationKind, n_boats: int = 256, seconds: float = 2.0
) -> float:
    """Decision steps per second of :class:`usvsim.task.openwater_batch.OpenWaterBatch` on
    ``n_boats`` episodes of the stress set ``set_name`` (e.g. ``everything``: obstacles,
    vessels, current, GNSS and radar degradation at once; random Gaussian actions, boats keep
    going after their episode ends)."""
    from usvsim.evaluation.stress import select_sets, stress_episodes
    from usvsim.task.openwater_batch import OpenWaterBatch

    (stress_set,) = select_sets([set_name])
    sim = OpenWaterBatch(n_boats, observation=observation)
    sim.reset(None, list(stress_episodes(stress_set, n_boats)))
    return _decision_rate(sim.step, n_boats, seconds)


def _everything_figures(seconds: float) -> dict[str, Any]:
    """The ``everything`` stress set beside the study's task, same observation, same run
    (issue 17: the former at >= 50 % of the latter)."""
    figures: dict[str, Any] = {}
    kinds: tuple[ObservationKind, ...] = ("positional", "radar+goal", "scene")
    for kind in kinds:
        study = env_throughput(kind, 256, seconds)
        everything = stress_set_throughput("everything", kind, 256, seconds)
        figures[kind] = {
            "everything N=256": round(everything),
            "study task N=256": round(study),
            "ratio": round(everything / study, 3),
        }
    return {"decision_steps_per_s": figures, "target_ratio": 0.5}


PROFILE_WORKLOADS: tuple[tuple[str, str, ObservationKind], ...] = (
    ("study task", "", "positional"),
    ("study task", "", "radar+goal"),
    ("OpenWater-v0", "", "scene"),  # the training env on its family (issue 40)
    ("OpenWater-v0", "", "radar+goal"),
    ("everything set", "everything", "positional"),
    ("everything set", "everything", "radar+goal"),
    ("everything set", "everything", "scene"),
)


def profile_steps(seconds: float = 2.0, n_boats: int = 256, top: int = 8) -> dict[str, Any]:
    """Where a decision step's time goes (``usvsim perf --profile``): cProfile over about
    ``seconds`` of steps of each :data:`PROFILE_WORKLOADS` entry (the study task's vector env
    and ``OpenWater-v0`` on its family, with autoresets; the ``everything`` stress set on the
    open-water batch), at ``n_boats``.

    Per workload: steps/s under the profiler (slower than without it), ms per step, and the
    ``top`` functions by their own time (``tottime``) with calls and ms per step and share of
    the step.
    """
    import cProfile
    import pstats

    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.0, 1.0, (64, n_boats, 1)).astype(np.float32)
    result: dict[str, Any] = {}
    for label, set_name, kind in PROFILE_WORKLOADS:
        if set_name:
            from usvsim.evaluation.stress import select_sets, stress_episodes
            from usvsim.task.openwater_batch import OpenWaterBatch

            sim = OpenWaterBatch(n_boats, observation=kind)
            sim.reset(None, list(stress_episodes(select_sets([set_name])[0], n_boats)))
            step: Callable[[Any], Any] = sim.step
        else:
            env = _make_env(label, kind, n_boats)
            env.reset(seed=0)
            step = env.step
        for k in range(3):
            step(actions[k])
        profiler = cProfile.Profile()
        steps, start = 0, time.perf_counter()
        profiler.enable()
        while time.perf_counter() - start < seconds or steps == 0:
            step(actions[steps % 64])
            steps += 1
        profiler.disable()
        elapsed = time.perf_counter() - start
        table = pstats.Stats(profiler).stats  # type: ignore[attr-defined]
        total = sum(row[2] for row in table.values())
        rows = sorted(table.items(), key=lambda item: -item[1][2])[:top]
        result[f"{label}, {kind}"] = {
            "decision_steps_per_s_profiled": round(n_boats * steps / elapsed),
            "ms_per_step": round(1e3 * elapsed / steps, 3),
            "top": [
                {
                    "function": _function_name(where),
                    "calls_per_step": round(row[1] / steps, 2),
                    "ms_per_step": round(1e3 * row[2] / steps, 3),
                    "share": round(row[2] / total, 3),
                }
                for where, row in rows
            ],
        }
    return result


def _function_name(where: tuple[str, int, str]) -> str:
    """``package/module.py:line(function)`` from a pstats key, or the built-in's name."""
    path, line, name = where
    if path == "~":
        return name
    parts = path.replace("\\", "/").split("/")
    for anchor in ("usvsim", "learning", "baselines", "numpy"):
        if anchor in parts:
            path = "/".join(parts[len(parts) - 1 - parts[::-1].index(anchor) :])
            break
    else:
        path = parts[-1]
    return f"{path}:{line}({name})"


def _make_env(label: str, kind: ObservationKind, n_envs: int) -> Any:
    """The study task's vector env or, for ``label`` ``OpenWater-v0``, the open-water one."""
    if label == "OpenWater-v0":
        from usvsim.task.openwater_env import OpenWaterVectorEnv

        return OpenWaterVectorEnv(n_envs, observation=kind, action="gaussian")
    return PoleAvoidanceVectorEnv(n_envs, observation=kind, action="gaussian")


OPEN_WATER_SPEED_TARGET = 150_000  # decision steps/s at N = 256 on 2 cores (issue 40)


def open_water_speed_table(
    sizes: tuple[int, ...] = (64, 256, 1024), seconds: float = 2.0, rounds: int = 5
) -> dict[str, Any]:
    """Decision steps per second of ``OpenWater-v0`` (scene and radar+goal, on its family,
    random Gaussian actions, autoresets drawing new episodes included) beside the study task's
    env (positional) at each of ``sizes`` boats, measured in the same run: per size, ``rounds``
    interleaved turns of ``seconds / rounds`` for each env (a change of machine load hits all
    alike), the median turn reported, with each open-water rate as a share of the study's
    (``benchmarks/openwater_speed.py`` prints it; issue 40's bar: 150,000 at N = 256)."""
    workloads: tuple[tuple[str, ObservationKind], ...] = (
        ("study task", "positional"),
        ("OpenWater-v0", "scene"),
        ("OpenWater-v0", "radar+goal"),
    )
    rows = []
    for n in sizes:
        envs = {f"{label} {kind}": _make_env(label, kind, n) for label, kind in workloads}
        turns: dict[str, list[float]] = {name: [] for name in envs}
        for env in envs.values():
            env.reset(seed=0)
        for _ in range(rounds):
            for name, env in envs.items():
                turns[name].append(_decision_rate(env.step, n, seconds / rounds))
        rates = {name: float(np.median(r)) for name, r in turns.items()}
        study = rates["study task positional"]
        rows.append(
            {
                "n_boats": n,
                "decision_steps_per_s": {name: round(r) for name, r in rates.items()},
                "over_study_task": {
                    name: round(r / study, 3)
                    for name, r in rates.items()
                    if name != "study task positional"
                },
            }
        )
    return {
        "rows": rows,
        "target_N=256": OPEN_WATER_SPEED_TARGET,
        "load_average_1min": _load_average(),
        "cpus": os.cpu_count(),
    }


def _env_figures(seconds: float) -> dict[str, Any]:
    figures: dict[str, Any] = {}
    for obs in ("positional", "radar+goal"):
        for n in (1, 256):
            figures[f"{obs} N={n}"] = round(env_throughput(obs, n, seconds))
    trained: tuple[ObservationKind, ...] = ("scene", "radar+goal")  # issue 18's training env
    for kind in trained:
        rate = open_water_env_throughput(kind, 256, seconds)
        figures[f"OpenWater-v0 {kind} N=256 (family)"] = round(rate)
    from usvsim.task.noise_kernel import load_kernel

    return {
        "decision_steps_per_s": figures,
        # issue 17's bars (the first ones, of the study's task, were 50,000 and 10,000)
        "targets": {"positional N=256": 200_000, "radar+goal N=256": 100_000},
        "sensor_noise": "numpy" if load_kernel() is None else "compiled",
    }


def env_throughput(observation: ObservationKind, n_envs: int, seconds: float = 2.0) -> float:
    """Decision steps per second (each: 20 plant steps + navigation + observation, all boats).

    Runs :class:`PoleAvoidanceVectorEnv` with uniformly random Gaussian actions (autoresets
    included) for about ``seconds`` after a short warm-up; returns ``n_envs × steps / time``.
    """
    env = PoleAvoidanceVectorEnv(n_envs, observation=observation, action="gaussian")
    env.reset(seed=0)
    return _decision_rate(env.step, n_envs, seconds)


def open_water_env_throughput(
    observation: ObservationKind, n_envs: int, seconds: float = 2.0
) -> float:
    """Decision steps per second of :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` on
    its training family (random Gaussian actions, autoresets that draw new episodes included)."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv

    env = OpenWaterVectorEnv(n_envs, observation=observation, action="gaussian")
    env.reset(seed=0)
    return _decision_rate(env.step, n_envs, seconds)


def _decision_rate(step: Callable[[Any], Any], n_boats: int, seconds: float) -> float:
    """``n_boats × steps / time`` of ``step`` fed uniformly random Gaussian actions for about
    ``seconds``, after 3 warm-up steps."""
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.0, 1.0, (64, n_boats, 1)).astype(np.float32)
    for k in range(3):
        step(actions[k])
    steps = 0
    start = time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds or steps == 0:
        step(actions[steps % 64])
        steps += 1
    return n_boats * steps / elapsed
