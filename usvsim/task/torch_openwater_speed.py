"""Speed of the torch open-water env: decision steps/s on a device beside the C path's
(``usvsim perf --device``, ``benchmarks/gpu_check_openwater.py``)."""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np
import torch

from usvsim.task.torch_openwater import TorchOpenWaterEnv

__all__ = ["measure_openwater_steps", "torch_openwater_rates"]


def measure_openwater_steps(env: TorchOpenWaterEnv, seconds: float = 1.0, seed: int = 0) -> float:
    """Decision steps (boat decisions of 2 s, restarts included) per second of ``env``: random
    Gaussian actions drawn once, steps until ``seconds`` have passed (at least 2), a GPU
    synchronised before each clock reading."""
    sync = torch.cuda.synchronize if env.device.type == "cuda" else (lambda: None)
    gen = torch.Generator(device=env.device).manual_seed(seed)
    shape = (env.num_envs, 1) if env.action_kind == "gaussian" else (env.num_envs,)
    if env.action_kind == "gaussian":
        actions = torch.rand(shape, generator=gen, device=env.device, dtype=env.dtype) * 2 - 1
    else:
        actions = torch.randint(41, shape, generator=gen, device=env.device)
    env.reset(seed=seed)
    env.step(actions)  # warm-up
    sync()
    steps, start = 0, time.perf_counter()
    while steps < 2 or time.perf_counter() - start < seconds:
        env.step(actions)
        steps += 1
        if steps % 8 == 0 or env.device.type != "cuda":
            sync()
    sync()
    return env.num_envs * steps / (time.perf_counter() - start)


def torch_openwater_rates(
    device: str, sizes: tuple[int, ...] = (256, 1024), seconds: float = 1.0
) -> dict[str, Any]:
    """Decision steps/s of the torch open-water env (``OPEN_WATER_FAMILY``) on ``device`` in
    float64 and float32 beside the C path's ``OpenWaterVectorEnv`` with the same observation,
    measured in the same run (``usvsim perf --device``): scene at each of ``sizes`` boats,
    radar+goal at the first (its images cost a CPU ~10x the scene)."""
    from usvsim.task.openwater_env import OpenWaterVectorEnv  # the C path (CasADi, gymnasium)

    rows: dict[str, dict[str, float]] = {}
    runs = [("scene", n) for n in sizes] + [("radar+goal", sizes[0])]
    for observation, n in runs:
        cpu = OpenWaterVectorEnv(n, observation=observation)  # type: ignore[arg-type]
        cpu.reset(seed=0)
        actions = np.random.default_rng(0).uniform(-1.0, 1.0, (n, 1))
        steps, start = 0, time.perf_counter()
        while steps < 2 or time.perf_counter() - start < seconds:
            cpu.step(actions)
            steps += 1
        row = {"C path": n * steps / (time.perf_counter() - start)}
        for dtype in ("float64", "float32"):
            env = TorchOpenWaterEnv(
                n, device=device, dtype=dtype, per_boat=2, observation=observation
            )
            row[dtype] = measure_openwater_steps(env, seconds)
        rows[f"{observation} N={n}"] = row
    return {
        "device": device,
        "decision_steps_per_s": {k: {c: round(v) for c, v in r.items()} for k, r in rows.items()},
        "over_C_path": {
            k: {d: round(r[d] / r["C path"], 3) for d in ("float64", "float32")}
            for k, r in rows.items()
        },
        "load_average_1min": round(os.getloadavg()[0], 2) if hasattr(os, "getloadavg") else None,
    }
