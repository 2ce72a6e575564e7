"""Stable-Baselines3 on usvsim (issue 13): SB3 PPO out of the box, and sb3-contrib TRPO as a peer.

Three trainers on the same task, gaussian actions and positional observations
(rl-gaussian-positional), validated on the study's 15 validation episodes
(:func:`usvsim.evaluation.episodes.validation_episodes`) every ``--validate-every`` env steps::

    pip install -c constraints.txt -e ".[sb3]"
    python benchmarks/train_sb3.py                               # all three, seed 0
    python benchmarks/train_sb3.py --trainers sb3-ppo --seeds 0 1 2 --out /tmp/sb3

==============  ==========================================================================
trainer         what runs
==============  ==========================================================================
``sb3-ppo``     SB3 ``PPO("MlpPolicy", env)`` with SB3's default hyper-parameters on
                :func:`usvsim.task.sb3.make_sb3_vec_env` (8 boats, fixed reward horizon,
                normalised observation): what a user gets out of the box
``sb3-trpo``    sb3-contrib ``TRPO`` with usvsim's networks (MLP 400-300 tanh, tanh-bounded
                Gaussian mean, initial σ 0.5, orthogonal init) and rl-gaussian-positional's
                hyper-parameters (32 boats × 64 steps, γ, λ, δ, CG, critic, Fisher sub-sample
                1/4) on the same adapter: the peer row
``sb3-trpo-full-fisher``  the same with sb3-contrib's default ``sub_sampling_factor=1``
                (Fisher-vector products on the whole batch)
``usvsim-trpo``  usvsim's TRPO, ``usvsim train rl-gaussian-positional`` (its setup as it is)
==============  ==========================================================================

Reported per trainer and seed: env steps and training wall-clock to the first 15/15 (and first
≥ 14/15), env steps per second of training (rollouts and updates; validation time excluded),
and the best validation. The run stops at the first 15/15 or after ``--max-steps``.
Writes ``train_sb3.md`` and ``train_sb3.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import torch
from sb3_contrib import TRPO
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.policies import ActorCriticPolicy
from torch import nn

from learning.algorithms.loop import IterationStats, train
from learning.algorithms.trpo import TRPOConfig
from learning.experiments.setups import get_setup
from learning.experiments.validation import validate
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.episodes import evaluate, validation_episodes
from usvsim.task.sb3 import SB3Helmsman, make_sb3_vec_env

SETUP = "rl-gaussian-positional"
TRAINERS = ("sb3-ppo", "sb3-trpo", "sb3-trpo-full-fisher", "usvsim-trpo")


class UsvsimMlpPolicy(ActorCriticPolicy):
    """SB3's MLP actor-critic shaped like usvsim's (:mod:`learning.algorithms.networks`):
    separate 400-300 tanh trunks, orthogonal init (√2, head 0.01, value 1: SB3's ``ortho_init``
    is the same), Gaussian mean ``tanh(z)`` within the action bounds, initial σ 0.5."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("net_arch", {"pi": [400, 300], "vf": [400, 300]})
        kwargs.setdefault("activation_fn", nn.Tanh)
        kwargs.setdefault("log_std_init", math.log(0.5))
        super().__init__(*args, **kwargs)

    def _build(self, lr_schedule: Any) -> None:
        super()._build(lr_schedule)
        self.action_net = nn.Sequential(self.action_net, nn.Tanh())  # same parameters, bounded


class Progress:
    """Validation bookkeeping shared by the trainers; training time excludes validation."""

    def __init__(self, max_steps: int) -> None:
        self.max_steps = max_steps
        self.t0 = time.perf_counter()
        self.validation_s = 0.0
        self.curve: list[tuple[int, int, float]] = []  # (env steps, successes, train s)
        self.first: dict[int, tuple[int, float]] = {}  # successes threshold → (steps, train s)

    def train_s(self) -> float:
        return time.perf_counter() - self.t0 - self.validation_s

    def record(self, steps: int, successes_fn: Callable[[], int]) -> bool:
        """Validate at ``steps``; True when training should stop."""
        train_s = self.train_s()
        t = time.perf_counter()
        successes = successes_fn()
        self.validation_s += time.perf_counter() - t
        self.curve.append((steps, successes, round(train_s, 2)))
        for k in (14, 15):
            if successes >= k and k not in self.first:
                self.first[k] = (steps, round(train_s, 2))
        return successes >= 15 or steps >= self.max_steps

    def row(self, trainer: str, seed: int, steps: int) -> dict[str, Any]:
        train_s = self.train_s()
        return {
            "trainer": trainer,
            "seed": seed,
            "env_steps": steps,
            "train_s": round(train_s, 1),
            "env_steps_per_s": round(steps / train_s),
            "first_14_steps": self.first.get(14, (None, None))[0],
            "first_15_steps": self.first.get(15, (None, None))[0],
            "first_15_train_s": self.first.get(15, (None, None))[1],
            "best_validation": max((s for _, s, _ in self.curve), default=0),
            "curve": self.curve,
        }


def sb3_successes(model: Any) -> int:
    return sum(r.success for r in evaluate(SB3Helmsman(model), validation_episodes()))


class ValidateEvery(BaseCallback):
    def __init__(self, progress: Progress, every: int) -> None:
        super().__init__()
        self.progress, self.every, self.next_at = progress, every, every

    def _on_step(self) -> bool:
        if self.num_timesteps < self.next_at:
            return True
        self.next_at += self.every
        return not self.progress.record(self.num_timesteps, lambda: sb3_successes(self.model))


def run_sb3(trainer: str, seed: int, max_steps: int, every: int) -> dict[str, Any]:
    if trainer == "sb3-ppo":
        env = make_sb3_vec_env(8, seed=seed)
        model: Any = PPO("MlpPolicy", env, seed=seed)
    else:
        c = get_setup(SETUP).algorithm_config
        assert isinstance(c, TRPOConfig)
        env = make_sb3_vec_env(c.num_envs, seed=seed, gamma=c.gamma)
        model = TRPO(
            UsvsimMlpPolicy,
            env,
            learning_rate=c.critic_lr,
            n_steps=c.steps_per_env,
            batch_size=c.critic_minibatch,
            gamma=c.gamma,
            gae_lambda=c.gae_lambda,
            cg_max_steps=c.cg_iters,
            cg_damping=c.cg_damping,
            n_critic_updates=c.critic_epochs,
            target_kl=c.max_kl,
            sub_sampling_factor=1 if trainer.endswith("full-fisher") else round(1 / c.fvp_fraction),
            seed=seed,
        )
    progress = Progress(max_steps)
    model.learn(max_steps, callback=ValidateEvery(progress, every))
    return progress.row(trainer, seed, model.num_timesteps)


def run_usvsim(seed: int, max_steps: int, every: int) -> dict[str, Any]:
    setup = get_setup(SETUP)
    config = setup.run_config(seed, iterations=math.ceil(max_steps / 2048))
    batch = config.num_envs * config.steps_per_env
    progress = Progress(max_steps)
    steps = 0

    def callback(s: IterationStats, agent: Any) -> bool:
        nonlocal steps
        steps = s.iteration * batch
        if steps % every:
            return False
        return progress.record(steps, lambda: int(validate(agent, setup)["successes"]))

    train(config, setup.make_vector_env, callback=callback)
    return progress.row("usvsim-trpo", seed, steps)


def table(rows: list[dict[str, Any]]) -> str:
    head = (
        "| trainer | seed | env steps to first ≥ 14/15 | env steps to first 15/15 "
        "| training s to 15/15 | env steps/s | best validation |\n|---|---|---|---|---|---|---|\n"
    )
    return head + "".join(
        f"| {r['trainer']} | {r['seed']} | {r['first_14_steps'] or '—'} | "
        f"{r['first_15_steps'] or '—'} | {r['first_15_train_s'] or '—'} | "
        f"{r['env_steps_per_s']:,} | {r['best_validation']}/15 |\n"
        for r in rows
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trainers", nargs="+", choices=TRAINERS, default=list(TRAINERS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--max-steps", type=int, default=300_000)
    parser.add_argument("--validate-every", type=int, default=10_240, help="env steps")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument("--out", default="benchmark-results/train_sb3")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    rows = []
    for trainer in args.trainers:
        for seed in args.seeds:
            if trainer == "usvsim-trpo":
                row = run_usvsim(seed, args.max_steps, args.validate_every)
            else:
                row = run_sb3(trainer, seed, args.max_steps, args.validate_every)
            rows.append(row)
            print(table([row]).splitlines()[-1], flush=True)
    load = os.getloadavg()
    meta = {
        "setup": SETUP,
        "threads": args.threads,
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
        "load_average_at_end": [round(x, 2) for x in load],
        "validate_every": args.validate_every,
    }
    out = Path(args.out)
    atomic_write_text(out / "train_sb3.json", json.dumps({**meta, "rows": rows}, indent=2) + "\n")
    md = f"# SB3 on {SETUP}\n\n{table(rows)}\n{json.dumps(meta)}\n"
    atomic_write_text(out / "train_sb3.md", md)
    print(md)


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
