"""The torch open-water env (scene) against the CPU env, set by set: the figures of
``docs/guide/gpu.md``.

For each open-water stress set, calm and in weather (``usvsim.evaluation.stress``: its
scenario as the family, fresh episodes from ``--seed``, not the test split) runs
``OpenWaterVectorEnv`` (the compiled C path) and ``TorchOpenWaterEnv`` on ``torch-cpu`` (the
CPU env's episodes and noise replayed) with the same actions (to the goal, away from a near
disc, plus noise) until every boat has finished at least one episode (at most
``--max-decisions``), and prints the largest differences (float32: over each boat's first
episode only, since float32 is another run: after a first episode that ends at another step,
the boats run different episodes): true position (m) and heading (rad), estimated position (m),
the float32 observations (in float32 steps), rewards, and
whether every flag and time agreed at every step (and on how many boats the first episode ended
at the same step)::

    python benchmarks/torch_openwater_equality.py [--sets a,b] [--dtype float32] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from usvsim.evaluation.stress import STRESS_SETS
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.torch_openwater import TorchOpenWaterEnv

FLAGS = ("reached_goal", "collision", "out_of_area", "time_limit", "is_success")
TIMES = ("time_s", "time_to_goal_s")


def open_water_sets() -> dict[str, Any]:
    """The open-water stress sets, calm and in weather: name → scenario."""
    return {
        s.name: s.scenario for s in STRESS_SETS if s.kind == "open-water" and s.scenario is not None
    }


def policy(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Steer to the goal, away from the nearest disc within 40 m, plus noise (scene obs)."""
    b_goal, r_near, b_near = obs[:, 1], obs[:, 4], obs[:, 5]
    away = np.where((r_near > 0) & (r_near < 40.0), -np.sign(b_near) * 0.8, 0.0)
    a = b_goal / np.radians(30.0) + away + rng.normal(0.0, 0.3, obs.shape[0])
    return np.clip(a, -1.0, 1.0)[:, None]


def compare(
    family: Any, n: int, max_decisions: int, seed: int, dtype: str = "float64"
) -> dict[str, Any]:
    """Largest differences between the two envs on ``family`` (module docstring)."""
    cpu = OpenWaterVectorEnv(n, observation="scene", family=family)
    dev = TorchOpenWaterEnv(n, family=family, per_boat=12, noise="replay", dtype=dtype,
                            observation_dtype="float64")  # fmt: skip
    o_cpu, _ = cpu.reset(seed=seed)
    o_dev, _ = dev.reset(seed=seed)
    rng = np.random.default_rng(seed)
    worst = {"position_m": 0.0, "heading_rad": 0.0, "estimate_m": 0.0, "reward": 0.0,
             "obs_float32_steps": 0.0, "distances_m": 0.0}  # fmt: skip
    finished = np.zeros(n, dtype=bool)
    first = np.ones(n, dtype=bool)  # boats in their first episode: differences measured there
    same_end = np.ones(n, dtype=bool)  # boats whose first episode ended at the same step
    same = True
    episodes = decisions = 0

    def obs_steps(a: np.ndarray, b: np.ndarray) -> float:
        if a.size == 0:
            return 0.0
        b32 = b.astype(np.float32)
        gap = np.abs(a.astype(np.float64) - b32.astype(np.float64))
        return float((gap / np.spacing(np.maximum(np.abs(a), np.abs(b32)))).max())

    worst["obs_float32_steps"] = obs_steps(o_cpu, o_dev.numpy())
    while decisions < max_decisions and not finished.all():
        actions = policy(o_cpu, rng)
        o_cpu, r_cpu, te_c, tr_c, i_cpu = cpu.step(actions)
        o_dev, r_dev, te_d, tr_d, i_dev = dev.step(torch.as_tensor(actions))
        decisions += 1
        x_cpu, x_dev = cpu.sim.inner.state.x, dev.state.numpy()
        est_cpu, est_dev = cpu.sim.inner.estimate[0], dev.estimate[0].numpy()
        dpsi = np.angle(np.exp(1j * (x_cpu[:, 2] - x_dev[:, 2])))
        d_cpu = np.stack([i_cpu["distance_to_obstacle_m"], i_cpu["distance_to_goal_m"]])
        d_dev = torch.stack([i_dev["distance_to_obstacle_m"], i_dev["distance_to_goal_m"]]).numpy()
        done_c, done_d = te_c | tr_c, te_d.numpy() | tr_d.numpy()
        m = first & (done_c == done_d)  # up to the end of each boat's first episode
        fin = np.isfinite(d_cpu) & m
        if m.any():
            for key, value in (
                ("position_m", np.abs(x_cpu[m, :2] - x_dev[m, :2]).max()),
                ("heading_rad", np.abs(dpsi[m]).max()),
                ("estimate_m", np.abs(est_cpu[m] - est_dev[m]).max()),
                ("reward", np.abs(r_cpu[m] - r_dev.numpy()[m]).max()),
                ("obs_float32_steps", obs_steps(o_cpu[m & ~done_c], o_dev.numpy()[m & ~done_c])),
                ("distances_m", np.abs(d_cpu[fin] - d_dev[fin]).max(initial=0.0)),
            ):
                worst[key] = max(worst[key], float(value))
        same_end &= ~first | (done_c == done_d)
        if dtype == "float32":  # float64: every step of every episode
            first &= ~(done_c | done_d)
        same &= bool(np.array_equal(te_c, te_d.numpy()) and np.array_equal(tr_c, tr_d.numpy()))
        same &= bool(np.array_equal(fin, np.isfinite(d_dev)))
        for key in FLAGS:
            same &= bool(np.array_equal(i_cpu[key], i_dev[key].numpy()))
        for key in TIMES:
            same &= bool(np.array_equal(i_cpu[key], i_dev[key].numpy()))
        done = te_c | tr_c
        finished |= done
        episodes += int(done.sum())
    return {"flags_and_times_equal": same, "decisions": decisions, "episodes_ended": episodes,
            "every_boat_finished": bool(finished.all()),
            "first_episode_ends_same_step": int(same_end.sum()), **worst}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", default="", help="comma-separated names (default: all)")
    parser.add_argument("--boats", type=int, default=8)
    parser.add_argument("--max-decisions", type=int, default=250)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--dtype", default="float64", choices=("float64", "float32"))
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    sets = open_water_sets()
    names = [s for s in args.sets.split(",") if s] or list(sets)
    unknown = [s for s in names if s not in sets]
    if unknown:
        parser.error(f"unknown sets {unknown}; open-water sets: {list(sets)}")
    torch.set_num_threads(1)
    rows = {}
    for name in names:
        start = time.perf_counter()
        rows[name] = compare(sets[name], args.boats, args.max_decisions, args.seed, args.dtype)
        rows[name]["seconds"] = round(time.perf_counter() - start, 1)
        if not args.json:
            r = rows[name]
            print(
                f"{name:20s} flags={'equal' if r['flags_and_times_equal'] else 'DIFFER'} "
                f"same-end={r['first_episode_ends_same_step']}/{args.boats} "
                f"dec={r['decisions']:3d} eps={r['episodes_ended']:3d} "
                f"pos={r['position_m']:.1e} m psi={r['heading_rad']:.1e} rad "
                f"est={r['estimate_m']:.1e} m obs32={r['obs_float32_steps']:.0f} step "
                f"r={r['reward']:.1e} d={r['distances_m']:.1e} m ({r['seconds']} s)",
                flush=True,
            )
    if args.json:
        print(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
