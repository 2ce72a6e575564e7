"""The open-water stage of ``benchmarks/gpu_check.sh``: the torch open-water env (scene) on a GPU.

Needs torch and NumPy only (the repository on ``PYTHONPATH``; no CasADi, SciPy or gymnasium):
the episodes come from a committed table (``benchmarks/data/openwater-table.npz``: 128 boats x
8 episodes of ``OPEN_WATER_FAMILY`` from seed 0, drawn by the CPU family, written by
``make-table`` where CasADi is installed); ``--weather`` takes
``benchmarks/data/openwater-weather-table.npz`` instead (``weather_family()``, the same size:
wind, gusts and waves per episode, calm ones among them; the weather plant's inputs in the
table); ``--colreg`` takes ``benchmarks/data/openwater-colreg-table.npz`` (``COLREG_FAMILY``, the
same size: Imazu- and trafficgen-like encounters, issue 41) and adds the COLREG reward terms
(``usvsim.task.torch_colreg``, default weights) to the env's reward. Results go to
``$OUT/results.jsonl`` as they come (stages ``ow_equality`` and ``ow_bench``;
``gpu_check.py report`` prints them)::

    python benchmarks/gpu_check_openwater.py make-table           # here, with CasADi
    python benchmarks/gpu_check_openwater.py equality --device cuda [--weather | --colreg]
    python benchmarks/gpu_check_openwater.py bench --device cuda --sizes 1000,10000,100000,1000000

``equality``: 16 boats x 40 decisions with the table's episodes and noise replayed, on the device
in float64 and float32 against the same env on torch-cpu in float64 (itself tested equal to the
CPU env in the CPU test suite): positions, headings, observations, rewards, flags.
Also the degraded radar images of 256 random scenes on the device against torch-cpu (the int64
SplitMix64 arithmetic). ``bench``: decision steps/s (one 2 s decision of one boat, 20 plant
steps, restarts included) at each N, float32, ``--observation scene`` or ``radar+goal``, eager
or ``--mode compile`` (plant + filter step through ``torch.compile``, the first step compiles);
at the first N whether a step waits for the device (CUDA's sync debug mode). Boat i's k-th
episode is table row (8 i + k) mod 1,024 (the table cycles).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from gpu_check import (  # noqa: E402  (results.jsonl of the same run)
    add_bench_stage,
    add_equality_stage,
    bench_sizes,
    record,
    record_equality,
)

TABLE = REPO / "benchmarks" / "data" / "openwater-table.npz"
WEATHER_TABLE = REPO / "benchmarks" / "data" / "openwater-weather-table.npz"
COLREG_TABLE = REPO / "benchmarks" / "data" / "openwater-colreg-table.npz"
TABLES = {"calm": TABLE, "weather": WEATHER_TABLE, "colreg": COLREG_TABLE}
TABLE_BOATS, PER_BOAT = 128, 8
EQ_BOATS, EQ_DECISIONS = 16, 40
# float64 on the device against torch-cpu float64: the same operations, another library's
# last bits (cuda's sin/cos), amplified by the closed loop as between the CPU backends
POSITION_TOL_M, HEADING_TOL_RAD, REWARD_TOL = 1e-6, 1e-8, 1e-8
BARS = {"max_position_diff_m": POSITION_TOL_M, "max_heading_diff_rad": HEADING_TOL_RAD,
        "max_reward_diff": REWARD_TOL}  # fmt: skip


def make_table() -> None:
    from usvsim.task.colreg_family import COLREG_FAMILY
    from usvsim.task.openwater_env import OPEN_WATER_FAMILY, weather_family
    from usvsim.task.torch_openwater_episodes import family_table

    TABLE.parent.mkdir(parents=True, exist_ok=True)
    families = ((TABLE, OPEN_WATER_FAMILY), (WEATHER_TABLE, weather_family()),
                (COLREG_TABLE, COLREG_FAMILY))  # fmt: skip
    for path, family in families:
        family_table(family, 0, TABLE_BOATS, PER_BOAT).save(path)
        print(f"wrote {path} ({path.stat().st_size:,} bytes)")


def _actions(obs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    b_goal, r_near, b_near = obs[:, 1], obs[:, 4], obs[:, 5]
    away = np.where((r_near > 0) & (r_near < 40.0), -np.sign(b_near) * 0.8, 0.0)
    a = b_goal / np.radians(30.0) + away + rng.normal(0.0, 0.3, obs.shape[0])
    return np.clip(a, -1.0, 1.0)[:, None]


def _colreg_reward(kind: str) -> Any:
    """The env's ``colreg_reward``: the default weights for the COLREG table, else None."""
    if kind != "colreg":
        return None
    from usvsim.task.colreg_reward import ColregRewardWeights

    return ColregRewardWeights()


def run(
    device: str, dtype: str, actions: list[np.ndarray] | None, kind: str = "calm"
) -> dict[str, Any]:
    """16 boats x 40 decisions on table ``kind`` (:data:`TABLES`); the actions from the first
    run's observations (None: make them)."""
    import torch

    from usvsim.task.torch_openwater import TorchOpenWaterEnv
    from usvsim.task.torch_openwater_episodes import load_table

    env = TorchOpenWaterEnv(EQ_BOATS, table=load_table(TABLES[kind]), per_boat=PER_BOAT,
                            device=device, dtype=dtype, noise="replay", observation_dtype="float64",
                            colreg_reward=_colreg_reward(kind))  # fmt: skip
    obs, _ = env.reset(seed=0)
    rng = np.random.default_rng(0)
    made: list[np.ndarray] = []
    keep: dict[str, list[np.ndarray]] = {k: [] for k in ("x", "obs", "reward", "done")}
    for k in range(EQ_DECISIONS):
        a = _actions(obs.cpu().numpy(), rng) if actions is None else actions[k]
        made.append(a)
        obs, r, te, tr, _ = env.step(torch.as_tensor(a, dtype=env.dtype, device=env.device))
        keep["x"].append(env.state.double().cpu().numpy())
        keep["obs"].append(obs.double().cpu().numpy())
        keep["reward"].append(r.double().cpu().numpy())
        keep["done"].append(np.stack([te.cpu().numpy(), tr.cpu().numpy()]))
    return {"actions": made, **{k: np.stack(v) for k, v in keep.items()}}


def radar_check(device: str) -> dict[str, Any]:
    """Degraded radar images of 256 random scenes on ``device`` against torch-cpu (the int64
    SplitMix64 draws and the difference array): pixels that differ."""
    import torch

    from usvsim.task.radar import RadarConfig
    from usvsim.task.torch_scene_radar import SceneRadarGrid, render_scene_torch

    rng = np.random.default_rng(0)
    n, j = 256, 10
    arrays = (rng.uniform(0, 220, (n, j)), rng.uniform(-4, 4, (n, j)),
              np.where(rng.random((n, j)) < 0.4, 1.0, rng.uniform(1, 30, (n, j))),
              rng.random((n, j)) < 0.8)  # fmt: skip
    levels = np.stack([rng.uniform(0, 0.01, n), rng.uniform(0, 0.5, n), rng.uniform(0, 0.2, n),
                       rng.uniform(0, 40, n)], 1)  # fmt: skip
    keys = rng.integers(-(2**63), 2**63 - 1, n, dtype=np.int64)
    images = []
    for dev in ("torch-cpu", device):
        d = torch.device("cpu" if dev == "torch-cpu" else dev)
        grid = SceneRadarGrid(RadarConfig(), torch.float64, d)
        t = [torch.as_tensor(a, device=d) for a in (*arrays, levels, keys)]
        images.append(render_scene_torch(*t[:4], grid, t[4], t[5]).cpu().numpy())
    return {"radar_pixels_differ": int((images[0] != images[1]).sum()),
            "radar_pixels_lit": int((images[0] > 0).sum())}  # fmt: skip


def stage_equality(device: str, dtypes: list[str], kind: str = "calm") -> None:
    t0 = time.perf_counter()
    if kind == "calm":
        record("ow_radar", device=device, **radar_check(device))
    ref = run("torch-cpu", "float64", None, kind)
    for dtype in dtypes:
        got = run(device, dtype, ref["actions"], kind)
        dpsi = np.angle(np.exp(1j * (got["x"][..., 2] - ref["x"][..., 2])))
        same_done = np.array_equal(got["done"], ref["done"])
        fields = {
            "max_position_diff_m": float(np.abs(got["x"][..., :2] - ref["x"][..., :2]).max()),
            "max_heading_diff_rad": float(np.abs(dpsi).max()),
            "max_obs_diff": float(np.abs(got["obs"] - ref["obs"]).max()),
            "max_reward_diff": float(np.abs(got["reward"] - ref["reward"]).max()),
            "flags_equal": bool(same_done),
            "episodes_ended": int(ref["done"].any(axis=1).sum()),
            "weather": kind == "weather",
            "table": kind,
        }
        record_equality("ow_equality", device, dtype, (EQ_BOATS, EQ_DECISIONS), t0, fields, BARS)


def stage_bench(
    device: str,
    dtype: str,
    sizes: list[int],
    seconds: float,
    observation: str = "scene",
    mode: str = "eager",
    backend: str = "inductor",
    kind: str = "calm",
) -> None:
    from usvsim.task.torch_openwater import TorchOpenWaterEnv
    from usvsim.task.torch_openwater_episodes import load_table
    from usvsim.task.torch_openwater_speed import measure_openwater_steps

    table = load_table(TABLES[kind])

    def make_env(n: int) -> Any:
        return TorchOpenWaterEnv(n, table=table, per_boat=PER_BOAT, device=device, dtype=dtype,
                                 observation=observation, compile=mode == "compile",
                                 compile_backend=backend,
                                 colreg_reward=_colreg_reward(kind))  # fmt: skip

    fields = dict(device=device, dtype=dtype, observation=observation, mode=mode,
                  weather=kind == "weather", table=kind)  # fmt: skip
    bench_sizes(
        "ow_bench", sizes, make_env, lambda env: measure_openwater_steps(env, seconds), fields,
        names=("setup_s", "decision_steps_per_s"), peak_memory=True,
    )  # fmt: skip


def openwater_table(grouped: dict[str, list[dict[str, Any]]]) -> list[str]:
    """The ``ow_equality`` and ``ow_bench`` lines for ``gpu_check.py report``'s table."""
    text: list[str] = []
    if grouped.get("ow_equality"):
        text += ["", f"open-water env (scene), {EQ_BOATS} boats x {EQ_DECISIONS} decisions of the "
                 "table's episodes and noise, against torch-cpu float64:"]  # fmt: skip
    for e in grouped.get("ow_equality", []):
        verdict = {True: "ok", False: "EXCEEDED", None: "stated, no bar"}[e["within_tolerance"]]
        sea = e.get("table", "weather" if e.get("weather") else "calm")
        text.append(
            f"  {sea:>7} {e['device']:>9} {e['dtype']:>8} "
            f"max |dpos| {e['max_position_diff_m']:.3g} m, "
            f"|dpsi| {e['max_heading_diff_rad']:.3g} rad, |dobs| {e['max_obs_diff']:.3g}, "
            f"|dreward| {e['max_reward_diff']:.3g}, flags "
            f"{'equal' if e['flags_equal'] else 'differ'} ({e['episodes_ended']} episodes "
            f"ended): {verdict}"
        )
    for r in grouped.get("ow_radar", []):
        text.append(
            f"  radar images ({r['device']} vs torch-cpu, 256 degraded scenes): "
            f"{r['radar_pixels_differ']} of {r['radar_pixels_lit']} lit pixels differ"
        )
    rows = grouped.get("ow_bench", [])
    if rows:
        text += ["", "open-water env decision steps/s (one 2 s decision of one boat):"]
    for b in rows:
        if "error" in b:
            text.append(f"  {b['observation']:>10} N={b['n']:>10,} {b['dtype']}: {b['error']}")
            continue
        text.append(
            f"  {b['observation']:>10} "
            f"{b.get('table', 'weather' if b.get('weather') else 'calm'):>7} "
            f"{b.get('mode', 'eager'):>7} N={b['n']:>10,} {b['dtype']}: "
            f"{b['decision_steps_per_s']:.3e} (first step {b['setup_s']} s)"
            + (f" (peak {b['peak_gib']} GiB)" if b.get("peak_gib") is not None else "")
            + (f"; host syncs in a step: {b['step_syncs']}" if b.get("step_syncs") else "")
        )
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="stage", required=True)
    sub.add_parser("make-table")
    add_equality_stage(sub, "equality")
    add_bench_stage(sub, "bench", "1000,10000,100000,1000000", ["scene", "radar+goal"])
    for name in ("equality", "bench"):
        group = sub.choices[name].add_mutually_exclusive_group()
        group.add_argument("--weather", action="store_true", help="the weather table")
        group.add_argument("--colreg", action="store_true",
                           help="the COLREG table, with the COLREG reward terms")  # fmt: skip
    args = parser.parse_args()
    if args.stage == "make-table":
        make_table()
        return
    kind = "weather" if args.weather else "colreg" if args.colreg else "calm"
    if args.stage == "equality":
        stage_equality(args.device, args.dtypes.split(","), kind)
    else:
        sizes = [int(float(s)) for s in args.sizes.split(",")]
        stage_bench(args.device, args.dtype, sizes, args.seconds, args.observation, args.mode,
                    args.backend, kind)  # fmt: skip


if __name__ == "__main__":
    main()
