"""Speed of the torch pole-avoidance env: env steps/s on a device beside the C path's
(``usvsim perf --device``, ``benchmarks/gpu_check.py``), and the timing loops the torch
open-water env's figures share (:mod:`usvsim.task.torch_openwater_speed`)."""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np
import torch

from usvsim.task.torch_env import N_CATEGORIES, TorchPoleAvoidanceEnv

__all__ = ["c_path_steps", "measure_env_steps", "rates_table", "time_steps", "torch_env_rates"]


def measure_env_steps(env: TorchPoleAvoidanceEnv, seconds: float = 1.0) -> float:
    """Env steps (boat decisions) per second of ``env``: random actions drawn once, steps until
    ``seconds`` have passed (at least 2), a GPU synchronised before each clock reading."""
    gen = torch.Generator(device=env.device).manual_seed(0)
    if env.action_kind == "gaussian":
        actions = torch.rand((env.num_envs, 1), generator=gen, device=env.device) * 2.0 - 1.0
    else:
        actions = torch.randint(N_CATEGORIES, (env.num_envs,), generator=gen, device=env.device)
    return time_steps(env, actions, seconds, seed=0)


def time_steps(env: Any, actions: torch.Tensor, seconds: float, seed: int) -> float:
    """Boat decisions per second of a torch env (``num_envs``, ``device``, ``reset``, ``step``)
    stepping ``actions`` every step: reset with ``seed``, one warm-up step (and torch.compile's
    first call), then steps until ``seconds`` have passed (at least 2), a GPU synchronised before
    each clock reading (and every 8 steps between, so the host stays near the device)."""
    sync = torch.cuda.synchronize if env.device.type == "cuda" else (lambda: None)
    env.reset(seed=seed)
    env.step(actions)
    sync()
    steps, start = 0, time.perf_counter()
    while steps < 2 or time.perf_counter() - start < seconds:
        env.step(actions)
        steps += 1
        if steps % 8 == 0 or env.device.type != "cuda":
            sync()
    sync()
    return env.num_envs * steps / (time.perf_counter() - start)


def c_path_steps(cpu: Any, n: int, seconds: float) -> float:
    """Boat decisions per second of a CPU vector env of ``n`` boats (reset with seed 0, random
    Gaussian actions drawn once, steps until ``seconds`` have passed, at least 2)."""
    cpu.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (n, 1))
    steps, start = 0, time.perf_counter()
    while steps < 2 or time.perf_counter() - start < seconds:
        cpu.step(actions)
        steps += 1
    return n * steps / (time.perf_counter() - start)


def rates_table(device: str, key: str, rows: dict[str, dict[str, float]]) -> dict[str, Any]:
    """``rows`` (each the C path's rate and the torch env's in float64 and float32) as the
    figures ``usvsim perf --device`` prints: rounded under ``key``, each dtype over the C path,
    and the machine's load."""
    return {
        "device": device,
        key: {k: {c: round(v) for c, v in r.items()} for k, r in rows.items()},
        "over_C_path": {
            k: {d: round(r[d] / r["C path"], 3) for d in ("float64", "float32")}
            for k, r in rows.items()
        },
        "load_average_1min": round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None,
    }


def torch_env_rates(
    device: str, sizes: tuple[int, ...] = (256, 1024), seconds: float = 1.0
) -> dict[str, Any]:
    """Env steps/s of the torch env on ``device`` (float64 and float32) beside the C path's
    (:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`) at each of ``sizes`` boats,
    measured in the same run, interleaved; positional observation, random Gaussian actions,
    restarts included (``usvsim perf --device``)."""
    from usvsim.task.vector_env import PoleAvoidanceVectorEnv  # the C path (gymnasium)

    rows: dict[str, dict[str, float]] = {}
    for n in sizes:
        row = {"C path": c_path_steps(PoleAvoidanceVectorEnv(n), n, seconds)}
        for dtype in ("float64", "float32"):
            env = TorchPoleAvoidanceEnv(n, device=device, dtype=dtype)
            row[dtype] = measure_env_steps(env, seconds)
        rows[f"N={n}"] = row
    return rates_table(device, "env_steps_per_s", rows)
