"""An open-water radar setup trained on a GPU against its shipped validation figures (issue 40).

Issue 40 asks for one open-water radar setup trained to its shipped validation figures in at most
5 minutes of GPU time. ``make`` (here, with CasADi) writes what the GPU machine needs into
``benchmarks/data/ow-radar/`` (torch and NumPy only there, gymnasium for the spaces):

- ``train.npz``: 8,192 episodes of ``rl-gaussian-radar-ow``'s training family (the open-water
  family, 30 % of it at the harshest radar), seed 0, packed
  (:mod:`usvsim.task.torch_openwater_episodes`); the torch env's boats cycle through it;
- ``val.npz``: the three open-water validation sets of :mod:`learning.experiments.validation`
  (family 100, crowded 50, harsh radar 50 episodes, in that order: one batch of 200 boats);
- ``setup.pt``: the setup's TRPO config, and the shipped model
  ``radar-gaussian-trpo-openwater-continued`` (this setup's recipe trained on: its policy and
  normaliser) with its validation figures measured here on the CPU.

``run --device cuda`` then (each line a record in ``$OUT/results.jsonl``, stage ``ow_train``):

1. the shipped model on the three validation sets on the device
   (:func:`learning.algorithms.device_eval.first_episode_outcomes`, float64, each episode's noise
   replayed): the same figures as the CPU's (on torch-cpu: 85, 41 and 42 on both, 2026-12-06),
   so the device's validation is the CPU's;
2. ``rl-gaussian-radar-ow`` from new networks with the setup's TRPO config at ``--n-envs`` boats
   x 64 decisions an iteration (float32), validated on the three sets every ``--eval-every``
   seconds of training, until ``--seconds`` of training have passed: elapsed time, iteration,
   env steps and the three sets' successes at each validation, and whether and when they reached
   the shipped model's.

    python benchmarks/gpu_check_ow_train.py make
    python benchmarks/gpu_check_ow_train.py run --device cuda --seconds 300 --n-envs 1024

``--val-limit K`` validates on the first K episodes of each set (a dry run on a CPU).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from gpu_check import record  # noqa: E402  (results.jsonl of the same run)

DATA = REPO / "benchmarks" / "data" / "ow-radar"
SETUP, SHIPPED = "rl-gaussian-radar-ow", "radar-gaussian-trpo-openwater-continued"
SETS = ("family", "crowded", "radar")
TRAIN_BOATS, TRAIN_PER_BOAT = 128, 64  # the training table: 8,192 episodes
MAX_DECISIONS = 400  # a validation episode's limit (the family's longest is under 300)


def make() -> None:
    """Write the tables and ``setup.pt`` (module docstring); CasADi needed."""
    import torch

    from learning.experiments.checkpoint import load_agent, load_checkpoint
    from learning.experiments.setups import get_setup
    from learning.experiments.validation import (
        crowded_validation_episodes,
        family_validation_episodes,
        open_water_summary,
        radar_validation_episodes,
    )
    from usvsim.helm.registry import model_path
    from usvsim.task.torch_openwater_episodes import family_table, pack_episodes

    setup = get_setup(SETUP)
    DATA.mkdir(parents=True, exist_ok=True)
    family_table(setup.training_family, 0, TRAIN_BOATS, TRAIN_PER_BOAT).save(DATA / "train.npz")
    sets = {"family": family_validation_episodes(), "crowded": crowded_validation_episodes(),
            "radar": radar_validation_episodes()}  # fmt: skip
    pack_episodes([e for name in SETS for e in sets[name]]).save(DATA / "val.npz")
    path = model_path(SHIPPED)
    agent = load_agent(load_checkpoint(path), path)
    cpu = open_water_summary(agent, setup)
    state = {
        "config": dataclasses.asdict(setup.algorithm_config),
        "shipped": SHIPPED,
        # float16 as shipped (the file's weights: no rounding), 2.8 MB
        "policy": {
            k: v.half() if v.is_floating_point() else v
            for k, v in agent.policy.state_dict().items()
        },
        "normalizer": agent.normalizer.state_dict(),
        "cpu_validation": {name: int(cpu[f"{name}_successes"]) for name in SETS},
        "n_episodes": {name: int(cpu[f"{name}_n_episodes"]) for name in SETS},
    }
    tmp = DATA / "setup.pt.tmp"
    torch.save(state, tmp)
    tmp.replace(DATA / "setup.pt")
    total = sum(p.stat().st_size for p in DATA.iterdir())
    print(f"wrote {DATA} ({total:,} bytes); {SHIPPED} on the CPU: {state['cpu_validation']}")


def _spaces() -> tuple[Any, Any]:
    import numpy as np
    from gymnasium import spaces

    from usvsim.task.observations import observation_space

    return observation_space("radar+goal"), spaces.Box(-1.0, 1.0, (1,), dtype=np.float32)


def _validate(agent: Any, device: str, sizes: dict[str, int], limit: int) -> dict[str, int]:
    """The three validation sets' successes of ``agent`` on ``device`` (one batch, float64, each
    episode's noise replayed); ``sizes`` the sets' episodes in ``val.npz``, ``limit`` the first
    episodes of each to run (0: all)."""
    import dataclasses as dc

    import numpy as np
    import torch

    from learning.algorithms.device_eval import first_episode_outcomes
    from learning.algorithms.device_rollout import DeviceNormalizer
    from usvsim.task.torch_openwater import TorchOpenWaterEnv
    from usvsim.task.torch_openwater_episodes import load_table

    table = load_table(DATA / "val.npz")
    starts = np.cumsum([0, *(sizes[k] for k in SETS)])
    take = {k: min(sizes[k], limit or sizes[k]) for k in SETS}
    rows = np.concatenate([np.arange(s, s + take[k]) for s, k in zip(starts, SETS, strict=False)])
    picked = {f.name: None if (v := getattr(table, f.name)) is None else v[rows]
              for f in dc.fields(table)}  # fmt: skip
    table = type(table)(**picked)
    kinds = dict(dtype="float64", observation="radar+goal", noise="replay")
    env = TorchOpenWaterEnv(len(rows), table=table, per_boat=1, device=device, **kinds)
    obs, _ = env.reset(seed=0)
    agent.policy.to(env.device)
    normalise = DeviceNormalizer(agent.normalizer, torch.device(env.device))
    got = first_episode_outcomes(agent.policy, normalise, env, obs, (-1.0, 1.0), MAX_DECISIONS)
    agent.policy.to("cpu")
    ends = np.cumsum([0, *(take[k] for k in SETS)])
    return {k: int(got["is_success"][ends[i] : ends[i + 1]].sum()) for i, k in enumerate(SETS)}


def run(
    device: str, seconds: float, n_envs: int, eval_every_s: float, seed: int, limit: int = 0
) -> None:
    import torch

    from learning.algorithms.base import config_from_dict
    from learning.algorithms.device_loop import train_on_device
    from learning.algorithms.trpo import TRPOAgent, TRPOConfig
    from usvsim.task.torch_openwater import TorchOpenWaterEnv
    from usvsim.task.torch_openwater_episodes import load_table

    state = torch.load(DATA / "setup.pt", weights_only=False)
    config = config_from_dict(TRPOConfig, state["config"])
    obs_space, act_space = _spaces()
    shipped = TRPOAgent(obs_space, act_space, config)
    shipped.policy.load_state_dict(state["policy"])
    shipped.normalizer.load_state_dict(state["normalizer"])
    t0 = time.perf_counter()
    sizes = state["n_episodes"]
    on_device = _validate(shipped, device, sizes, limit)
    seconds_taken = round(time.perf_counter() - t0, 1)
    record("ow_train", device=device, kind="shipped", model=state["shipped"],
           device_validation=on_device, cpu_validation=state["cpu_validation"],
           n_episodes=sizes, val_limit=limit, seconds=seconds_taken)  # fmt: skip
    target = state["cpu_validation"] if not limit else on_device  # the bar: the shipped model's
    table = load_table(DATA / "train.npz")
    config = dataclasses.replace(config, num_envs=n_envs, iterations=10**9, seed=seed)

    def make_env(n: int) -> Any:
        return TorchOpenWaterEnv(n, table=table, per_boat=max(1, table.n_episodes // n),
                                 device=device, dtype="float32", observation="radar+goal",
                                 reward_horizon="fixed", gamma=config.gamma)  # fmt: skip

    clock = {"train_s": 0.0, "last": time.perf_counter(), "next_eval": eval_every_s}
    reached: dict[str, float | None] = {"at_s": None}

    def callback(stats: Any, agent: Any) -> bool:
        now = time.perf_counter()
        clock["train_s"] += now - clock["last"]
        done = clock["train_s"] >= seconds
        if clock["train_s"] >= clock["next_eval"] or done:
            clock["next_eval"] += eval_every_s
            got = _validate(agent, device, sizes, limit)
            met = all(got[k] >= target[k] for k in SETS)
            if met and reached["at_s"] is None:
                reached["at_s"] = round(clock["train_s"], 1)
            record("ow_train", device=device, kind="training", n_envs=n_envs,
                   train_s=round(clock["train_s"], 1), iteration=stats.iteration,
                   env_steps=stats.env_steps, mean_return=round(stats.mean_return, 2),
                   validation=got, shipped=target, reached_shipped=met)  # fmt: skip
        clock["last"] = time.perf_counter()  # validation time is not training time
        return done

    try:
        agent = train_on_device(config, make_env, callback=callback)
    except torch.cuda.OutOfMemoryError as err:  # type: ignore[attr-defined]
        record("ow_train", device=device, kind="error", n_envs=n_envs, error=str(err)[:200])
        return
    record("ow_train", device=device, kind="summary", n_envs=n_envs, iterations=agent.iteration,
           env_steps=agent.env_steps, train_s=round(clock["train_s"], 1),
           env_steps_per_s=round(agent.env_steps / max(clock["train_s"], 1e-9)),
           reached_shipped_at_s=reached["at_s"])  # fmt: skip


def ow_train_table(grouped: dict[str, list[dict[str, Any]]]) -> list[str]:
    """The ``ow_train`` lines for ``gpu_check.py report``'s table."""
    rows = grouped.get("ow_train", [])
    if not rows:
        return []
    text = ["", f"{SETUP} trained on the device (validation successes family/crowded/radar):"]
    for r in rows:
        if r["kind"] == "shipped":
            text.append(f"  {r['model']}: device {r['device_validation']}, CPU "
                        f"{r['cpu_validation']} ({r['seconds']} s)")  # fmt: skip
        elif r["kind"] == "training":
            mark = " REACHED" if r["reached_shipped"] else ""
            text.append(f"  {r['train_s']:>7} s it {r['iteration']:>5} {r['env_steps']:>11,} "
                        f"steps: {r['validation']}{mark}")  # fmt: skip
        elif r["kind"] == "summary":
            text.append(f"  N={r['n_envs']:,}: {r['env_steps_per_s']:.3e} env steps/s training; "
                        f"shipped figures reached at {r['reached_shipped_at_s']} s")  # fmt: skip
        else:
            text.append(f"  N={r.get('n_envs')}: {r.get('error')}")
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="stage", required=True)
    sub.add_parser("make")
    r = sub.add_parser("run")
    r.add_argument("--device", default="cuda")
    r.add_argument("--seconds", type=float, default=300.0, help="training time (s)")
    r.add_argument("--n-envs", type=int, default=1024)
    r.add_argument("--eval-every", type=float, default=30.0, help="training seconds between")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--val-limit", type=int, default=0, help="first K episodes of each set")
    args = parser.parse_args()
    if args.stage == "make":
        make()
    else:
        run(args.device, args.seconds, args.n_envs, args.eval_every, args.seed, args.val_limit)


if __name__ == "__main__":
    main()
