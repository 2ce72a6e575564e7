"""What the COLREG reward terms (issue 41, :mod:`usvsim.task.colreg_reward`) cost per decision,
against the open-water env's step in the same run.

Two :class:`usvsim.task.openwater_env.OpenWaterVectorEnv` of ``--n`` boats on the training
family of ``rl-gaussian-radar-colreg`` (the open-water family with half COLREG encounters,
:func:`usvsim.task.colreg_family.colreg_training_family`), the same seed and actions, one with
the COLREG reward and one without, stepped in alternating blocks; reported: CPU time
(``time.process_time``) per step of each, the reward terms' own time (inside the env with the
reward) and their share of its step, with the machine's load (``os.getloadavg``).
``--reactive``: the env with the reward also steers its targets with vo
(:class:`usvsim.evaluation.colreg_rollout.TrainingReactiveTargets`), whose time is reported too;
``--reference`` adds a third env, the same with the targets steered as before the compiled vo
(vo's NumPy path, ``VOHelmsman(backend="numpy")``, on every target slot, empty ones included:
the same numbers), stepped and timed in the same blocks::

    nice python benchmarks/colreg_reward_cost.py --n 256 --steps 100 --observation radar+goal
    nice python benchmarks/colreg_reward_cost.py --n 64 --steps 100 --reactive
    nice python benchmarks/colreg_reward_cost.py --n 256 --steps 20 --reactive --reference
"""

from __future__ import annotations

import argparse
import json
import os
import time
from typing import Any

import numpy as np

from baselines.velocity_obstacle import VOHelmsman
from usvsim.evaluation.colreg_rollout import TrainingReactiveTargets
from usvsim.task.colreg_family import colreg_training_family
from usvsim.task.colreg_reward import ColregRewardWeights
from usvsim.task.openwater_env import OpenWaterVectorEnv


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=256, help="boats")
    ap.add_argument("--steps", type=int, default=100, help="timed steps per env")
    ap.add_argument("--block", type=int, default=10, help="steps per alternating block")
    ap.add_argument("--observation", default="radar+goal")
    ap.add_argument("--reactive", action="store_true", help="targets steered by vo, timed")
    ap.add_argument("--reference", action="store_true", help="also vo's NumPy path, timed")
    args = ap.parse_args()
    hook = TrainingReactiveTargets() if args.reactive else None
    family = colreg_training_family()
    envs: dict[str, OpenWaterVectorEnv] = {
        "off": OpenWaterVectorEnv(args.n, observation=args.observation, family=family),
        "on": OpenWaterVectorEnv(
            args.n,
            observation=args.observation,
            family=family,
            colreg_reward=ColregRewardWeights(),
            on_decision=hook,
        ),
    }
    hooks = {"on": hook}
    if args.reactive and args.reference:
        hooks["numpy"] = TrainingReactiveTargets(EverySlot(VOHelmsman(backend="numpy")))
        envs["numpy"] = OpenWaterVectorEnv(
            args.n,
            observation=args.observation,
            family=family,
            colreg_reward=ColregRewardWeights(),
            on_decision=hooks["numpy"],
        )
    terms_s = [0.0]
    on: Any = envs["on"]
    inner = on.colreg.from_batch

    def timed(*a: Any) -> Any:
        t = time.process_time()
        out = inner(*a)
        terms_s[0] += time.process_time() - t
        return out

    on.colreg.from_batch = timed
    hook_s = dict.fromkeys(hooks, 0.0)
    for key, h in hooks.items():
        if h is not None:
            h.steer = _timed(h.steer, hook_s, key)  # type: ignore[method-assign]
    rngs = {k: np.random.default_rng(1) for k in envs}
    for env in envs.values():
        env.reset(seed=0)
    cpu = dict.fromkeys(envs, 0.0)
    load0 = os.getloadavg()[0]
    for block in range(-1, args.steps // args.block):  # block -1: warm-up, not timed
        for key, env in envs.items():
            if block == 0 and key == "on":
                terms_s[0] = 0.0
            if block == 0 and key in hook_s:
                hook_s[key] = 0.0
            t = time.process_time()
            for _ in range(args.block):
                env.step(rngs[key].uniform(-1, 1, (args.n, 1)))
            if block >= 0:
                cpu[key] += time.process_time() - t
    steps = args.block * (args.steps // args.block)
    out = {
        "n": args.n,
        "observation": args.observation,
        "steps": steps,
        "step_off_ms": 1e3 * cpu["off"] / steps,
        "step_on_ms": 1e3 * cpu["on"] / steps,
        "terms_ms": 1e3 * terms_s[0] / steps,
        "terms_share_of_step": terms_s[0] / cpu["on"],
        "reactive_targets_ms": 1e3 * hook_s["on"] / steps if hook is not None else None,
        "reactive_targets_numpy_ms": (1e3 * hook_s["numpy"] / steps if "numpy" in hook_s else None),
        "step_numpy_ms": 1e3 * cpu["numpy"] / steps if "numpy" in cpu else None,
        "load_1min": [load0, os.getloadavg()[0]],
    }
    print(json.dumps(out, indent=1))


class EverySlot:
    """A helmsman asked for every target slot (its ``act`` takes no ``boats``)."""

    def __init__(self, helmsman: Any) -> None:
        self.helmsman = helmsman

    def reset(self, n_boats: int) -> None:
        self.helmsman.reset(n_boats)

    def act(self, observation: Any) -> Any:
        return self.helmsman.act(observation)


def _timed(fn: Any, total_s: dict[str, float], key: str) -> Any:
    """``fn`` adding its CPU time to ``total_s[key]``."""

    def timed(*a: Any) -> Any:
        t = time.process_time()
        out = fn(*a)
        total_s[key] += time.process_time() - t
        return out

    return timed


if __name__ == "__main__":
    main()
