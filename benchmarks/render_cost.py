"""What rendering costs (issue 13): single-env steps per second with and without frames.

One env (N = 1), random actions from a seeded generator, autoreset by hand; three ways of
running it, interleaved in blocks of ``--block-s`` seconds so that machine load hits them
alike, ``--repeats`` times, medians reported::

    python benchmarks/render_cost.py
    python benchmarks/render_cost.py --observation radar+goal --repeats 5
    python benchmarks/render_cost.py --ppo-steps 12288   # also SB3 PPO training speed

==============  ==============================================================================
mode            what runs
==============  ==============================================================================
``plain``       ``render_mode=None``
``rgb_array``   ``render_mode="rgb_array"`` and ``env.render()`` after every step
``video/10``    ``gymnasium.wrappers.RecordVideo`` recording every 10th episode to MP4
                (moviepy; encoding included)
==============  ==============================================================================

``--ppo-steps S`` also trains SB3 PPO (default hyper-parameters, one env through SB3's
``make_vec_env``, fixed reward horizon, normalised observation) for S env steps with and
without ``RecordVideo`` every 10th episode, alternately, and reports the training speed of both
(moviepy imported beforehand, so its import is not counted).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from typing import Any

import gymnasium as gym
import numpy as np

import usvsim


def make(mode: str, observation: str, folder: str) -> Any:
    env = gym.make(
        usvsim.ENV_ID,
        observation=observation,
        render_mode=None if mode == "plain" else "rgb_array",
    )
    if mode == "video/10":
        env = gym.wrappers.RecordVideo(
            env, folder, episode_trigger=lambda e: e % 10 == 0, disable_logger=True
        )
    return env


def steps_per_s(env: Any, render: bool, seconds: float, rng: np.random.Generator) -> float:
    env.reset(seed=int(rng.integers(2**31)))
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 1).astype(np.float32))
        if render:
            env.render()
        n += 1
        if terminated or truncated:
            env.reset()
    return n / (time.perf_counter() - t0)


def ppo_rate(steps: int, video: bool) -> float:
    """SB3 PPO env steps per second over ``steps``, optionally recording every 10th episode."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    with tempfile.TemporaryDirectory() as folder:

        def record(env: Any) -> Any:
            return gym.wrappers.RecordVideo(
                env, folder, episode_trigger=lambda e: e % 10 == 0, disable_logger=True
            )

        env = make_vec_env(
            usvsim.ENV_ID,
            n_envs=1,
            seed=0,
            env_kwargs={"reward_horizon": "fixed", "normalize_observation": True},
            wrapper_class=record if video else None,
        )
        model = PPO("MlpPolicy", env, seed=0)
        t0 = time.perf_counter()
        model.learn(steps)
        rate = steps / (time.perf_counter() - t0)
        env.close()
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--observation", default="positional")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--block-s", type=float, default=3.0)
    parser.add_argument("--ppo-steps", type=int, default=0, help="0: no training measurement")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    modes = ("plain", "rgb_array", "video/10")
    rates: dict[str, list[float]] = {m: [] for m in modes}
    with tempfile.TemporaryDirectory() as folder:
        envs = {m: make(m, args.observation, folder) for m in modes}
        for _ in range(args.repeats):
            for m in modes:
                rates[m].append(steps_per_s(envs[m], m == "rgb_array", args.block_s, rng))
        for env in envs.values():
            env.close()
    med = {m: statistics.median(r) for m, r in rates.items()}
    report: dict[str, Any] = {
        "observation": args.observation,
        "steps_per_s_median": {m: round(v) for m, v in med.items()},
        "steps_per_s_runs": {m: [round(x) for x in r] for m, r in rates.items()},
        "ratio_rgb_array_to_plain": round(med["rgb_array"] / med["plain"], 3),
        "ratio_video10_to_plain": round(med["video/10"] / med["plain"], 3),
    }
    if args.ppo_steps:
        import moviepy.video.io.ImageSequenceClip  # noqa: F401  (its import is not training)
        import torch

        torch.set_num_threads(1)
        ppo: dict[str, list[float]] = {"plain": [], "video/10": []}
        for _ in range(args.repeats):
            for mode in ppo:
                ppo[mode].append(ppo_rate(args.ppo_steps, mode == "video/10"))
        report["ppo_steps_per_s_runs"] = {m: [round(x) for x in r] for m, r in ppo.items()}
        report["ppo_ratio_video10_to_plain"] = round(
            statistics.median(ppo["video/10"]) / statistics.median(ppo["plain"]), 3
        )
    report["load_average"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
