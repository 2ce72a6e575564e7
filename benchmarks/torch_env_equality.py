"""The torch env's distance from the CPU env, beside the CPU env's two backends' own distance.

Runs the study task's CPU env (``PoleAvoidanceVectorEnv``, the compiled C kernel), the same env
on CasADi's virtual machine (``backend="casadi"``) and the torch env on ``torch-cpu`` in float64
(the CPU env's episodes and noise replayed), 16 boats x 160 decisions with the same actions, and
prints the largest differences from the compiled CPU env: estimated position (m) and heading
(rad), rewards, and whether the done flags agree. The figures of ``docs/guide/gpu.md``::

    python benchmarks/torch_env_equality.py [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from usvsim.task.torch_env import TorchPoleAvoidanceEnv
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

N_BOATS, N_DECISIONS, SEED = 16, 160, 11


def policy(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """tests/usvsim/task/test_torch_env.py's actions: to the goal, away from a near pole, noise."""
    r_pole, b_pole, b_goal = obs[:, 0], obs[:, 1], obs[:, 3]
    away = np.where(r_pole < 25.0, -np.sign(b_pole) * 0.8, 0.0)
    a = 1.5 * b_goal / np.radians(30.0) * rng.uniform(-0.5, 1.5, obs.shape[0]) + away
    return np.clip(a + rng.normal(0.0, 0.4, obs.shape[0]), -1.0, 1.0)[:, None]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    ref = PoleAvoidanceVectorEnv(N_BOATS)
    vm = PoleAvoidanceVectorEnv(N_BOATS, backend="casadi")
    tor = TorchPoleAvoidanceEnv(
        N_BOATS, episodes="numpy", episodes_per_boat=12, noise="replay",
        observation_dtype="float64",
    )  # fmt: skip
    obs, _ = ref.reset(seed=SEED)
    vm.reset(seed=SEED)
    tor.reset(seed=SEED)
    rng = np.random.default_rng(5)
    worst: dict[str, dict[str, Any]] = {
        name: {"position_m": 0.0, "heading_rad": 0.0, "reward": 0.0, "flags_equal": True}
        for name in ("casadi VM", "torch-cpu float64")
    }
    ended = 0
    for _ in range(N_DECISIONS):
        actions = policy(obs, rng)
        obs, reward, term, trunc, _ = ref.step(actions)
        ended += int((term | trunc).sum())
        pos, psi = ref.sim.estimate
        _, v_reward, v_term, v_trunc, _ = vm.step(actions)
        _, t_reward, t_term, t_trunc, _ = tor.step(torch.as_tensor(actions))
        t_pos, t_psi = tor.estimate
        others = {
            "casadi VM": (*vm.sim.estimate, v_reward, v_term, v_trunc),
            "torch-cpu float64": (
                t_pos.numpy(),
                t_psi.numpy(),
                t_reward.numpy(),
                t_term.numpy(),
                t_trunc.numpy(),
            ),
        }
        for name, (o_pos, o_psi, o_reward, o_term, o_trunc) in others.items():
            w = worst[name]
            w["position_m"] = max(w["position_m"], float(np.abs(o_pos - pos).max()))
            w["heading_rad"] = max(w["heading_rad"], float(np.abs(o_psi - psi).max()))
            w["reward"] = max(w["reward"], float(np.abs(o_reward - reward).max()))
            w["flags_equal"] &= bool(
                np.array_equal(o_term, term) and np.array_equal(o_trunc, trunc)
            )
    result = {"boats": N_BOATS, "decisions": N_DECISIONS, "episodes_ended": ended, **worst}
    if args.json:
        print(json.dumps(result, indent=2))
        return
    print(f"{N_BOATS} boats x {N_DECISIONS} decisions ({ended} episodes ended), largest "
          "differences from the CPU env (compiled C kernel):")  # fmt: skip
    for name, w in worst.items():
        print(
            f"  {name:<18} estimate {w['position_m']:.2g} m, {w['heading_rad']:.2g} rad; "
            f"reward {w['reward']:.2g}; flags {'equal' if w['flags_equal'] else 'DIFFER'}"
        )


if __name__ == "__main__":
    main()
