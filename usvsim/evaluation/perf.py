"""Throughput measurements for ``usvsim perf`` (figures, not adjectives).

A *boat-substep* is one 0.1 s plant step (autopilot + RK4) of one boat; a *decision step* is one
environment step (20 plant steps + navigation + observation) of one boat.
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
from usvsim.vessel.plant import Plant

__all__ = ["env_throughput", "measure_plant", "per_boat_loop_rate", "run_perf"]


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


def run_perf(seconds: float = 1.0, env: bool = True) -> dict[str, Any]:
    """All throughput figures as a JSON-ready dict."""
    plant = Plant("default")
    loop = per_boat_loop_rate(plant, seconds=seconds)
    n1 = measure_plant(plant, 1, seconds)
    n1024 = measure_plant(plant, 1024, seconds)
    result: dict[str, Any] = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "processor": platform.machine(),
        },
        "plant": {
            "backend": plant.backend,
            "boat_substeps_per_s": {"N=1": round(n1), "N=1024": round(n1024)},
            "per_boat_python_loop_boat_substeps_per_s": round(loop),
            "batched_N1024_over_loop": round(n1024 / loop, 1),
            "targets": {"N=1024": 2_000_000, "ratio": 100},
        },
    }
    if env:
        result["env"] = _env_figures(seconds)
    return result


def _env_figures(seconds: float) -> dict[str, Any]:
    figures: dict[str, Any] = {}
    for obs in ("positional", "radar+goal"):
        for n in (1, 256):
            figures[f"{obs} N={n}"] = round(env_throughput(obs, n, seconds))
    return {
        "decision_steps_per_s": figures,
        "targets": {"positional N=256": 50_000, "radar+goal N=256": 10_000},
    }


def env_throughput(observation: ObservationKind, n_envs: int, seconds: float = 2.0) -> float:
    """Decision steps per second (each: 20 plant steps + navigation + observation, all boats).

    Runs :class:`PoleAvoidanceVectorEnv` with uniformly random Gaussian actions (autoresets
    included) for about ``seconds`` after a short warm-up; returns ``n_envs × steps / time``.
    """
    env = PoleAvoidanceVectorEnv(n_envs, observation=observation, action="gaussian")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.0, 1.0, (64, n_envs, 1)).astype(np.float32)
    for k in range(3):
        env.step(actions[k])
    steps = 0
    start = time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds or steps == 0:
        env.step(actions[steps % 64])
        steps += 1
    return n_envs * steps / elapsed
