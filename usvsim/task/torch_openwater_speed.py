"""Speed of the torch open-water env: decision steps/s on a device beside the C path's
(``usvsim perf --device``, ``benchmarks/gpu_check_openwater.py``)."""

from __future__ import annotations

from typing import Any

import torch

from usvsim.task.torch_env_speed import c_path_steps, rates_table, time_steps
from usvsim.task.torch_openwater import TorchOpenWaterEnv

__all__ = ["measure_openwater_steps", "torch_openwater_rates"]


def measure_openwater_steps(env: TorchOpenWaterEnv, seconds: float = 1.0, seed: int = 0) -> float:
    """Decision steps (boat decisions of 2 s, restarts included) per second of ``env``: random
    Gaussian actions drawn once, steps until ``seconds`` have passed (at least 2), a GPU
    synchronised before each clock reading (:func:`usvsim.task.torch_env.time_steps`)."""
    gen = torch.Generator(device=env.device).manual_seed(seed)
    shape = (env.num_envs, 1) if env.action_kind == "gaussian" else (env.num_envs,)
    if env.action_kind == "gaussian":
        actions = torch.rand(shape, generator=gen, device=env.device, dtype=env.dtype) * 2 - 1
    else:
        actions = torch.randint(41, shape, generator=gen, device=env.device)
    return time_steps(env, actions, seconds, seed)


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
        row = {"C path": c_path_steps(cpu, n, seconds)}
        for dtype in ("float64", "float32"):
            env = TorchOpenWaterEnv(
                n, device=device, dtype=dtype, per_boat=2, observation=observation
            )
            row[dtype] = measure_openwater_steps(env, seconds)
        rows[f"{observation} N={n}"] = row
    return rates_table(device, "decision_steps_per_s", rows)
