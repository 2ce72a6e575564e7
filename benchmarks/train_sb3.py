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

``--peer SETUP ...`` (issue 17; rl-gaussian-positional, rl-gaussian-radar) instead runs usvsim's
TRPO and sb3-contrib's TRPO side by side on SETUP, one iteration (rollout + update of the
setup's batch) of each in turn, so that both see the same machine load::

    python benchmarks/train_sb3.py --peer rl-gaussian-positional --max-steps 102400
    python benchmarks/train_sb3.py --peer rl-gaussian-radar --max-steps 20480

Matched settings (:func:`sb3_trpo`): the same env (the native batch, fixed reward horizon), the
setup's nets (MLP 400-300 tanh; for radar usvsim's CNN as the features extractor,
:class:`UsvsimRadarFeatures`, separate policy and critic trunks, the goal standardised by
running statistics as usvsim's normaliser does), batch (N boats × T steps), γ, λ, δ, CG
iterations and damping, line-search decay and trials, critic epochs, minibatch and learning
rate, and the Fisher sub-sample (sb3-contrib's ``sub_sampling_factor`` = 1 / ``fvp_fraction``).
What differs is each library's own: sb3-contrib runs BatchNorm in train mode during its updates
and its own rollout buffer. Both are validated on the 15 episodes every
``--validate-every-iterations`` iterations (not timed); each stops at its first 15/15 or at
``--max-steps``. Printed (and written to ``peer.md``, ``peer.json``): env steps/s of each and
their ratio, env steps to the first 15/15 and their ratio, the load average during the run.
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

import gymnasium as gym
import numpy as np
import torch
from sb3_contrib import TRPO
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger
from stable_baselines3.common.policies import ActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from stable_baselines3.common.vec_env import VecEnvWrapper, VecNormalize
from torch import nn

from learning.algorithms.loop import IterationStats, train
from learning.algorithms.networks import CNNTrunk
from learning.algorithms.rollout import RolloutCollector
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.experiments.setups import get_setup
from learning.experiments.validation import validate
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.episodes import evaluate, validation_episodes
from usvsim.task.options import normalized_observation
from usvsim.task.sb3 import SB3Helmsman, make_sb3_vec_env

SETUP = "rl-gaussian-positional"
TRAINERS = ("sb3-ppo", "sb3-trpo", "sb3-trpo-full-fisher", "usvsim-trpo")
PEER_SETUPS = ("rl-gaussian-positional", "rl-gaussian-radar")


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


class FlatRadarObs(VecEnvWrapper):
    """radar+goal as one float32 vector [radar / 255 (C·H·W), goal]: sb3-contrib TRPO
    sub-samples its Fisher batch by ``observations[::k]``, which a dict observation does not
    allow; the image is scaled as SB3 scales image observations."""

    def __init__(self, venv: Any) -> None:
        radar, goal = venv.observation_space["radar"], venv.observation_space["goal"]
        self.image_shape = tuple(int(n) for n in radar.shape)
        size = int(np.prod(self.image_shape)) + int(goal.shape[0])
        space = gym.spaces.Box(-np.inf, np.inf, (size,), np.float32)
        super().__init__(venv, observation_space=space)

    @staticmethod
    def flat(obs: dict[str, np.ndarray]) -> np.ndarray:
        """A batch (N, ...) or one observation → (N, size) or (size,)."""
        radar = np.asarray(obs["radar"], np.float32) / np.float32(255.0)
        goal = np.asarray(obs["goal"], np.float32)
        radar = radar.reshape(len(radar), -1) if radar.ndim == 4 else radar.reshape(-1)
        return np.concatenate([radar, goal], axis=-1)

    def reset(self) -> np.ndarray:
        return self.flat(self.venv.reset())

    def step_wait(self) -> Any:
        obs, rewards, dones, infos = self.venv.step_wait()
        for info in infos:
            if "terminal_observation" in info:
                info["terminal_observation"] = self.flat(info["terminal_observation"])
        return self.flat(obs), rewards, dones, infos


class FlatRadarHelmsman(SB3Helmsman):
    """:class:`SB3Helmsman` for a model trained on :class:`FlatRadarObs` over a
    ``VecNormalize`` of the goal (whose running statistics it applies, not updates)."""

    def act(self, observation: Any) -> np.ndarray:
        goal_normalizer = self.model.get_env().venv
        obs = goal_normalizer.normalize_obs(normalized_observation(self.observation, observation))
        action, _ = self.model.predict(FlatRadarObs.flat(obs), deterministic=True)
        return np.asarray(action)


class UsvsimRadarFeatures(BaseFeaturesExtractor):
    """usvsim's radar trunk before its fully connected layers (:class:`CNNTrunk`) on a
    :class:`FlatRadarObs` vector: conv 10×7×7 stride 4 → ReLU → BatchNorm → flatten, ⊕ the goal
    × the balanced-fusion factor (3192 features for the study's image)."""

    def __init__(
        self, observation_space: gym.spaces.Box, image_shape: tuple[int, int, int], network: Any
    ) -> None:
        assert observation_space.shape is not None
        self.image_size = int(np.prod(image_shape))
        n_goal = int(observation_space.shape[0]) - self.image_size
        cnn = CNNTrunk(image_shape, "radar", ["goal"], n_goal, network)
        super().__init__(observation_space, cnn.conv_features + n_goal)
        self.image_shape = image_shape
        self.conv, self.norm, self.vector_scale = cnn.conv, cnn.norm, cnn.vector_scale

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        image = obs[:, : self.image_size].reshape(-1, *self.image_shape)
        x = self.norm(torch.relu(self.conv(image))).flatten(1)
        return torch.cat([x, self.vector_scale * obs[:, self.image_size :]], dim=-1)


def sb3_trpo(setup_name: str, seed: int, sub_sampling_factor: int | None = None) -> Any:
    """sb3-contrib TRPO with ``setup_name``'s nets and hyper-parameters on its env (batch,
    γ, λ, δ, CG, line-search decay, critic; Fisher sub-sample 1/round(1 / fvp_fraction) unless
    ``sub_sampling_factor``)."""
    setup = get_setup(setup_name)
    c = setup.algorithm_config
    assert isinstance(c, TRPOConfig)
    env: Any = make_sb3_vec_env(
        c.num_envs, setup.observation, setup.action, seed=seed, gamma=c.gamma
    )
    policy_kwargs: dict[str, Any] = {}
    if setup.observation != "positional":
        # the goal standardised by running statistics, as usvsim's normaliser does
        goal_normalizer = VecNormalize(
            env, norm_reward=False, norm_obs_keys=["goal"], clip_obs=c.obs_clip, gamma=c.gamma
        )
        env = FlatRadarObs(goal_normalizer)
        policy_kwargs = {
            "features_extractor_class": UsvsimRadarFeatures,
            "features_extractor_kwargs": {"image_shape": env.image_shape, "network": c.network},
            "share_features_extractor": False,  # usvsim: separate policy and critic trunks
        }
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
        line_search_shrinking_factor=c.line_search_decay,
        line_search_max_iter=c.line_search_steps,
        n_critic_updates=c.critic_epochs,
        target_kl=c.max_kl,
        sub_sampling_factor=sub_sampling_factor or round(1 / c.fvp_fraction),
        policy_kwargs=policy_kwargs,
        seed=seed,
    )
    return without_log_folder(model)


def without_log_folder(model: Any) -> Any:
    """``model`` with a logger that writes nothing: by default SB3 makes a new tempdir/SB3-<time>
    folder at each ``learn`` call, and the peer comparison calls it once per iteration."""
    model.set_logger(Logger(folder=None, output_formats=[]))
    return model


def run_sb3(trainer: str, seed: int, max_steps: int, every: int) -> dict[str, Any]:
    if trainer == "sb3-ppo":
        env = make_sb3_vec_env(8, seed=seed)
        model: Any = without_log_folder(PPO("MlpPolicy", env, seed=seed))
    else:
        model = sb3_trpo(SETUP, seed, 1 if trainer.endswith("full-fisher") else None)
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


class PeerRun:
    """One trainer of the peer comparison, one iteration (rollout + update) at a time."""

    def __init__(self, name: str, setup_name: str, seed: int) -> None:
        self.name, self.setup = name, get_setup(setup_name)
        config = self.setup.run_config(seed)
        assert isinstance(config, TRPOConfig)
        self.batch = config.batch_size
        if name == "usvsim-trpo":
            self.env = self.setup.make_vector_env(config.num_envs)
            space = self.env.single_observation_space, self.env.single_action_space
            self.agent: Any = TRPOAgent(*space, config)
            self.collector = RolloutCollector(self.env, seed=seed)
        else:
            self.model = sb3_trpo(setup_name, seed)
        self.steps, self.train_s = 0, 0.0
        self.first: dict[int, tuple[int, float]] = {}  # successes → (env steps, train s)
        self.best = 0

    def iteration(self) -> None:
        """One rollout of the batch and one update, timed."""
        t = time.perf_counter()
        if self.name == "usvsim-trpo":
            self.agent.update(
                self.collector.collect(self.agent.sample, self.batch // self.env.num_envs)
            )
        else:
            self.model.learn(self.batch, reset_num_timesteps=False)
        self.train_s += time.perf_counter() - t
        self.steps += self.batch

    def validate(self) -> int:
        """Successes on the 15 validation episodes (not timed); records the first 14 and 15."""
        if self.name == "usvsim-trpo":
            successes = int(validate(self.agent, self.setup)["successes"])
        else:
            radar = self.setup.observation != "positional"
            h = (FlatRadarHelmsman if radar else SB3Helmsman)(self.model, self.setup.observation)
            kinds = {"observation": self.setup.observation, "action": self.setup.action}
            successes = sum(r.success for r in evaluate(h, validation_episodes(), **kinds))
        self.best = max(self.best, successes)
        for k in (14, 15):
            if successes >= k and k not in self.first:
                self.first[k] = (self.steps, round(self.train_s, 1))
        return successes


def run_peer(setup_name: str, seed: int, max_steps: int, every_iterations: int) -> dict[str, Any]:
    """usvsim TRPO and sb3-contrib TRPO (matched: :func:`sb3_trpo`) on ``setup_name``, one
    iteration of each in turn (the one behind goes first), validated every
    ``every_iterations`` iterations; each stops at its first 15/15 or after ``max_steps``."""
    runs = [PeerRun("usvsim-trpo", setup_name, seed), PeerRun("sb3-trpo", setup_name, seed)]
    load = [os.getloadavg()[0]]
    active = list(runs)
    while active:
        for r in sorted(active, key=lambda r: (r.steps, r.name)):
            r.iteration()
            if r.steps // r.batch % every_iterations == 0 and r.validate() >= 15:
                active.remove(r)
            elif r.steps >= max_steps:
                active.remove(r)
        load.append(os.getloadavg()[0])
    us, peer = runs
    rate = {r.name: r.steps / r.train_s for r in runs}
    first = {r.name: r.first.get(15, (None, None)) for r in runs}
    steps_ratio = None
    if first["usvsim-trpo"][0] and first["sb3-trpo"][0]:
        steps_ratio = first["sb3-trpo"][0] / first["usvsim-trpo"][0]
    return {
        "setup": setup_name,
        "seed": seed,
        "load_average": [round(min(load), 2), round(max(load), 2)],
        "ratio_env_steps_per_s": round(rate[us.name] / rate[peer.name], 2),
        "ratio_env_steps_to_15": round(steps_ratio, 2) if steps_ratio else None,
        "runs": [
            {
                "trainer": r.name,
                "env_steps": r.steps,
                "train_s": round(r.train_s, 1),
                "env_steps_per_s": round(rate[r.name]),
                "first_14_steps": r.first.get(14, (None, None))[0],
                "first_15_steps": r.first.get(15, (None, None))[0],
                "first_15_train_s": r.first.get(15, (None, None))[1],
                "best_validation": r.best,
            }
            for r in runs
        ],
    }


def peer_table(results: list[dict[str, Any]]) -> str:
    head = (
        "| setup | trainer | env steps | training s | env steps/s | first 15/15 at (env steps, s) "
        "| best | usvsim / sb3-contrib: env steps/s | sb3-contrib / usvsim: env steps to 15/15 "
        "| load |\n|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for res in results:
        for r in res["runs"]:
            first = r["first_15_steps"]
            at = f"{first:,}, {r['first_15_train_s']}" if first else "not reached"
            ratio = res["ratio_env_steps_to_15"]
            lines.append(
                f"| {res['setup']} | {r['trainer']} | {r['env_steps']:,} | {r['train_s']} "
                f"| {r['env_steps_per_s']:,} | {at} | {r['best_validation']}/15 "
                f"| {res['ratio_env_steps_per_s']}× | {f'{ratio}×' if ratio else '—'} "
                f"| {res['load_average'][0]}-{res['load_average'][1]} |"
            )
    return head + "\n".join(lines) + "\n"


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
    parser.add_argument(
        "--peer",
        nargs="+",
        metavar="SETUP",
        choices=PEER_SETUPS,
        help="the peer comparison on these setups instead (module docstring)",
    )
    parser.add_argument("--validate-every-iterations", type=int, default=5, help="--peer")
    parser.add_argument("--trainers", nargs="+", choices=TRAINERS, default=list(TRAINERS))
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument("--max-steps", type=int, default=300_000)
    parser.add_argument("--validate-every", type=int, default=10_240, help="env steps")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument("--out", default="benchmark-results/train_sb3")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    if args.peer:
        main_peer(args)
        return
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


def main_peer(args: argparse.Namespace) -> None:
    """``--peer``: :func:`run_peer` per setup and seed; ``peer.md`` and ``peer.json``."""
    results = []
    for name in args.peer:
        for seed in args.seeds:
            results.append(run_peer(name, seed, args.max_steps, args.validate_every_iterations))
            print(peer_table(results[-1:]), flush=True)
    meta = {
        "threads": args.threads,
        "machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs",
        "max_steps": args.max_steps,
        "validate_every_iterations": args.validate_every_iterations,
    }
    out = Path(args.out)
    text = json.dumps({**meta, "results": results}, indent=2) + "\n"
    atomic_write_text(out / "peer.json", text)
    atomic_write_text(
        out / "peer.md", f"# usvsim TRPO and sb3-contrib TRPO\n\n{peer_table(results)}"
    )
    print(peer_table(results))


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
