"""``benchmarks/gpu_check.sh`` stage ``train-bench``: TRPO training iterations on the device.

Trains ``rl-categorical-positional``'s network (MLP 400-300, 41 logits) on the study task's torch
env (:mod:`learning.algorithms.device_loop`: env, rollouts, GAE, conjugate gradient and line
search on the device) for a few iterations at each N boats x 64 decisions, and records per N
the env steps per second of whole iterations (rollout + update, the first iteration left out),
of the rollout alone, and whether a rollout step waits for the device (CUDA sync debug mode).

Imports torch, NumPy and gymnasium (for the spaces; a small pure-Python wheel: gpu_check.sh
installs it from ``GPU_CHECK_WHEELS`` where it is missing) and no CasADi, SciPy or filterpy: the
TRPO hyperparameters are ``rl-categorical-positional``'s (``learning.experiments.setups.RL_TRPO``,
not importable here: setups needs CasADi), restated below, except the critic's minibatch, which
grows with the batch (B / 8 rows: 256 rows of a 65,536-boat batch would be 16,384 Adam steps).

    python benchmarks/gpu_check_train.py --device cuda --sizes 1024,8192,32768,65536

``--env ow-scene`` and ``--env ow-radar`` train the open-water setups' networks instead
(``rl-gaussian-scene-ow``: Deep Sets 64-64 per slot, MLP 400-300, the scene's fixed
standardisation; ``rl-gaussian-radar-ow``: its CNN with balanced goal fusion, the TRPO config
read from ``benchmarks/data/ow-radar/setup.pt``) on the torch open-water env with the episodes of
``benchmarks/data/openwater-table.npz`` (each boat cycling through them), the fixed reward
horizon. The records give Isaac Lab's three figures per N: env steps/s alone (the ``ow-bench``
stage), with the policy's inference (the rollout) and with training (whole iterations).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from gpu_check import record  # noqa: E402  (results.jsonl of the same run)

STEPS_PER_ENV = 64  # T, the setups'


def _config(n: int, iterations: int) -> Any:
    from learning.algorithms.networks import NetworkConfig
    from learning.algorithms.trpo import TRPOConfig

    return TRPOConfig(  # RL_TRPO of learning.experiments.setups
        iterations=iterations,
        num_envs=n,
        steps_per_env=STEPS_PER_ENV,
        gamma=0.99,
        gae_lambda=0.97,
        max_kl=0.02,
        cg_iters=10,
        cg_damping=0.1,
        fvp_fraction=0.25,
        critic_lr=1e-3,
        critic_epochs=5,
        critic_minibatch=max(256, n * STEPS_PER_ENV // 8),
        network=NetworkConfig(init_std_fraction=0.5),
    )


def _rollout_syncs(env: Any, agent: Any) -> str | None:
    """On a GPU: "none" if 3 rollout steps never wait for the device, else the first error."""
    import torch

    from learning.algorithms.device_rollout import DeviceNormalizer, DeviceRolloutCollector

    if env.device.type != "cuda":
        return None
    collector = DeviceRolloutCollector(env, 0.99, seed=1)
    agent.policy.to(env.device)
    torch.cuda.synchronize()
    torch.cuda.set_sync_debug_mode("error")
    try:
        collector.collect(agent.policy, DeviceNormalizer(agent.normalizer, env.device), 3)
        found = "none"
    except RuntimeError as err:
        found = str(err).splitlines()[0][:200]
    finally:
        torch.cuda.set_sync_debug_mode(0)
        agent.policy.cpu()
    return found


def _open_water_config(env: str, n: int, iterations: int) -> Any:
    """The TRPO config of the open-water setup behind ``env`` (``ow-scene`` restated from
    ``learning.experiments.setups.OW_TRPO``, which needs CasADi to import; ``ow-radar`` read from
    the committed setup file), with ``n`` boats and the critic's minibatch grown with the batch."""
    import dataclasses

    import torch

    from learning.algorithms.base import config_from_dict
    from learning.algorithms.networks import NetworkConfig
    from learning.algorithms.trpo import TRPOConfig

    if env == "ow-radar":
        state = torch.load(REPO / "benchmarks" / "data" / "ow-radar" / "setup.pt",
                           weights_only=False)  # fmt: skip
        config = config_from_dict(TRPOConfig, state["config"])
    else:
        config = dataclasses.replace(
            _config(n, iterations), observation_scaling="scene",
            network=NetworkConfig(init_std_fraction=0.5, set_encoder=(64, 64)),
        )  # fmt: skip
    batch = n * STEPS_PER_ENV
    minibatch = max(config.critic_minibatch, batch // 8)
    return dataclasses.replace(config, num_envs=n, iterations=iterations,
                               critic_minibatch=minibatch)  # fmt: skip


def bench(
    device: str, dtype: str, sizes: list[int], iterations: int, env_kind: str = "study"
) -> None:
    import torch

    from learning.algorithms.device_loop import train_on_device
    from learning.algorithms.trpo import TRPOAgent
    from usvsim.task.torch_env import TorchPoleAvoidanceEnv

    table = None
    if env_kind != "study":
        from usvsim.task.torch_openwater_episodes import load_table

        table = load_table(REPO / "benchmarks" / "data" / "openwater-table.npz")
    for i, n in enumerate(sizes):
        rows: list[tuple[float, float, float]] = []

        def make_env(num_envs: int) -> Any:
            if table is None:
                return TorchPoleAvoidanceEnv(num_envs, device=device, dtype=dtype,
                                             action="categorical")  # fmt: skip
            from usvsim.task.torch_openwater import TorchOpenWaterEnv

            return TorchOpenWaterEnv(
                num_envs, table=table, per_boat=max(1, table.n_episodes // num_envs),
                device=device, dtype=dtype,
                observation="scene" if env_kind == "ow-scene" else "radar+goal",
                reward_horizon="fixed", gamma=0.99,
            )  # fmt: skip

        def config(boats: int, its: int) -> Any:
            if table is None:
                return _config(boats, its)
            return _open_water_config(env_kind, boats, its)

        def callback(s: Any, agent: Any, rows: list[Any] = rows) -> None:
            rows.append((s.rollout_time_s, s.update_time_s, s.mean_return))

        try:
            t0 = time.perf_counter()
            agent = train_on_device(config(n, iterations), make_env, callback=callback)
            total = time.perf_counter() - t0
            syncs = None
            if i == 0:
                env = make_env(n)
                syncs = _rollout_syncs(env, TRPOAgent(
                    env.single_observation_space, env.single_action_space, config(n, 1)
                ))  # fmt: skip
        except torch.cuda.OutOfMemoryError as err:
            record(
                "train_bench", device=device, dtype=dtype, n=n, env=env_kind, error=str(err)[:200]
            )
            break
        b = n * STEPS_PER_ENV
        timed = rows[1:] or rows
        iteration_s = statistics.median(r + u for r, u, _ in timed)
        rollout_s = statistics.median(r for r, _, _ in timed)
        record(
            "train_bench", device=device, dtype=dtype, n=n, env=env_kind, batch=b,
            iterations=agent.iteration,
            total_s=round(total, 2), iteration_s=round(iteration_s, 4),
            train_env_steps_per_s=round(b / iteration_s),
            rollout_env_steps_per_s=round(b / rollout_s),
            update_share=round(1 - rollout_s / iteration_s, 3), rollout_syncs=syncs,
            mean_returns=[round(m, 2) for _, _, m in rows],
        )  # fmt: skip
        if device.startswith("cuda"):
            torch.cuda.empty_cache()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda")
    parser.add_argument("--dtype", default="float32", choices=["float32", "float64"])
    parser.add_argument("--sizes", default="1024,8192,32768,65536")
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--env", default="study", choices=["study", "ow-scene", "ow-radar"])
    args = parser.parse_args()
    try:
        import gymnasium  # noqa: F401
    except ImportError:
        record("train_bench", device=args.device, error="gymnasium missing (GPU_CHECK_WHEELS)")
        sys.exit(3)
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    bench(args.device, args.dtype, sizes, args.iterations, args.env)


if __name__ == "__main__":
    main()
