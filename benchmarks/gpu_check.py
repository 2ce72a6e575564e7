"""Stages of ``benchmarks/gpu_check.sh``: the torch plant and the torch pole-avoidance env on a
GPU, their equality and their speed.

Needs torch and NumPy only (the repository on ``PYTHONPATH``; no CasADi, no install). Each stage
is one call of this script, run under its own time limit by the shell script, and appends its
results to ``$OUT/results.jsonl`` as they come (one JSON object per line), so a stage that runs
out of time keeps what it measured. ``report`` turns the lines into ``results.json`` and
``table.txt``.

Why this module is long: it runs alone on a bare GPU machine (torch and NumPy, no install), so
each stage's setup, its measurement and the report that reads every stage's lines live in one
file that is copied and run as it is.

Stages::

    python benchmarks/gpu_check.py env
    python benchmarks/gpu_check.py equality --device cuda
    python benchmarks/gpu_check.py bench --device cuda --dtype float32 --mode compile
    python benchmarks/gpu_check.py env-equality --device cuda
    python benchmarks/gpu_check.py env-bench --device cuda --dtype float32 --mode compile
    python benchmarks/gpu_check.py report

``equality``: N = 64 boats with heading and speed references redrawn every 5 s, 1,000 steps of
0.1 s in a current, on the device in float64 and float32 against torch on the CPU in float64
(itself tested equal to the C kernel in the CPU test suite: positions within 1e-6 m, headings
within 1e-8 rad). ``bench``: boat-substeps per second of :meth:`TorchPlant.advance` (no
trajectory kept) at each N, eager or through ``torch.compile`` (compile time reported; a
compiled run also checks its own equality first).

``env-equality``: the study task's torch env (:class:`usvsim.task.torch_env.TorchPoleAvoidanceEnv`,
positional), 16 boats x 40 decisions with the CPU env's episodes and noise replayed
(``episodes="numpy"``, ``noise="replay"``), on the device in float64 and float32 against the same
env on torch-cpu in float64 (itself tested against the C path in the CPU test suite):
observations, rewards and flags. ``env-bench``: env steps (boat decisions of 2 s, restarts
included) per second at each N, eager or with the plant + filter step compiled, positional or
radar(+goal) observation.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

N_EQUALITY, SEGMENTS, SEGMENT_STEPS = 64, 20, 50  # 1,000 steps of 0.1 s
CURRENT = (0.6, 1.0)  # m/s, rad
POSITION_TOL_M, HEADING_TOL_RAD = 1e-6, 1e-8  # float64 bars (issue 40)
# float32's stated tolerance over this episode (tests/usvsim/vessel/test_torch_plant.py)
POSITION_TOL_F32_M, HEADING_TOL_F32_RAD = 0.25, 0.01
TARGET_F32 = 2e9  # boat-substeps/s, plant float32 on one H200 (issue 40)


def _out_dir() -> Path:
    out = Path(os.environ.get("OUT") or "gpu-out")
    out.mkdir(parents=True, exist_ok=True)
    return out


def record(stage: str, **fields: Any) -> None:
    """Append one result line (flushed at once: a stage killed later keeps it)."""
    line = json.dumps({"stage": stage, "time": time.time(), **fields})
    with open(_out_dir() / "results.jsonl", "a") as fh:
        fh.write(line + "\n")
        fh.flush()
    print(line, flush=True)


def _sync(device: Any) -> None:
    import torch

    if device.type == "cuda":
        torch.cuda.synchronize(device)


def stage_env() -> None:
    import torch

    info: dict[str, Any] = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "torch": torch.__version__,
        "torch_cuda": torch.version.cuda,
        "cuda_available": torch.cuda.is_available(),
        "cpus": os.cpu_count(),
    }
    if torch.cuda.is_available():
        info["gpu"] = torch.cuda.get_device_name(0)
        info["gpu_memory_gib"] = round(torch.cuda.get_device_properties(0).total_memory / 2**30)
    try:
        import triton  # noqa: F401  (torch.compile's GPU code generator)

        info["triton"] = getattr(sys.modules["triton"], "__version__", "present")
    except ImportError:
        info["triton"] = None
    for name in ("casadi", "gymnasium"):
        try:
            __import__(name)
            info[name] = True
        except ImportError:
            info[name] = False
    t0 = time.perf_counter()
    from usvsim.vessel.torch_plant import TorchPlant

    plant = TorchPlant()
    info["usvsim_import_s"] = round(time.perf_counter() - t0, 2)
    info["kernel"] = plant.kernel.origin
    record("env", **info)


def episode(plant: Any, seed: int = 0) -> np.ndarray:
    """Trajectory (N, 1000, 13) as float64 NumPy: references redrawn every 5 s from ``seed``."""
    rng = np.random.default_rng(seed)
    eta = np.column_stack(
        [
            rng.uniform(-100.0, 100.0, (N_EQUALITY, 2)),
            rng.uniform(-np.pi, np.pi, N_EQUALITY),
        ]
    )
    state = plant.initial_state(eta, rng.uniform(1.0, 5.0, N_EQUALITY))
    parts = []
    for _ in range(SEGMENTS):
        psi_ref = rng.uniform(-np.pi, np.pi, N_EQUALITY)
        speed_ref = rng.uniform(1.0, 6.0, N_EQUALITY)
        state, traj = plant.step(state, psi_ref, speed_ref, n_steps=SEGMENT_STEPS)
        parts.append(traj.double().cpu().numpy())
    return np.concatenate(parts, axis=1)


def compare(got: np.ndarray, ref: np.ndarray, dtype: str) -> dict[str, Any]:
    """Largest position (m) and heading (rad, wrapped) differences, and whether they are within
    the dtype's tolerance (float64: the issue's bars; float32: the stated tolerance)."""
    pos = float(np.abs(got[..., 0:2] - ref[..., 0:2]).max())
    psi = float(np.abs((got[..., 2] - ref[..., 2] + np.pi) % (2 * np.pi) - np.pi).max())
    finite = bool(np.all(np.isfinite(got)))
    tol_pos, tol_psi = (
        (POSITION_TOL_M, HEADING_TOL_RAD)
        if dtype == "float64"
        else (POSITION_TOL_F32_M, HEADING_TOL_F32_RAD)
    )
    return {
        "max_position_diff_m": pos,
        "max_heading_diff_rad": psi,
        "finite": finite,
        "tolerance_m_rad": [tol_pos, tol_psi],
        "within_tolerance": finite and pos < tol_pos and psi < tol_psi,
    }


_REFERENCE: dict[str, np.ndarray] = {}


def reference() -> np.ndarray:
    """The torch-cpu float64 episode: computed once, kept in ``$OUT/reference.npy`` for the
    later stages."""
    if "ref" not in _REFERENCE:
        path = _out_dir() / "reference.npy"
        if path.exists():
            _REFERENCE["ref"] = np.load(path)
        else:
            from usvsim.vessel.torch_plant import TorchPlant

            t0 = time.perf_counter()
            _REFERENCE["ref"] = episode(TorchPlant(current=CURRENT, device="torch-cpu"))
            record("reference", seconds=round(time.perf_counter() - t0, 2), device="torch-cpu")
            np.save(path.with_suffix(".tmp.npy"), _REFERENCE["ref"])
            path.with_suffix(".tmp.npy").replace(path)
    return _REFERENCE["ref"]


def stage_equality(device: str, dtypes: list[str]) -> None:
    from usvsim.vessel.torch_plant import TorchPlant

    ref = reference()
    for dtype in dtypes:
        t0 = time.perf_counter()
        plant = TorchPlant(current=CURRENT, device=device, dtype=dtype)
        got = episode(plant)
        seconds = round(time.perf_counter() - t0, 2)
        # same seed, same episode: run it again (float64 only, to save time)
        again = bool(np.array_equal(episode(plant), got)) if dtype == "float64" else None
        record(
            "equality",
            device=device,
            dtype=dtype,
            mode="eager",
            boats=N_EQUALITY,
            steps=SEGMENTS * SEGMENT_STEPS,
            seconds=seconds,
            same_seed_same_episode=again,
            **compare(got, ref, dtype),
        )


def _rate(plant: Any, n: int, seconds: float) -> tuple[float, int]:
    """Boat-substeps per second of ``plant.advance`` on ``n`` boats, timed over about
    ``seconds`` after a warm-up; and the steps timed."""
    import torch

    gen = torch.Generator(device="cpu").manual_seed(0)
    eta = torch.zeros((n, 3), dtype=torch.float64)
    eta[:, 2] = (torch.rand(n, generator=gen, dtype=torch.float64) * 2 - 1) * math.pi
    state = plant.initial_state(eta)
    cols = tuple(c.contiguous() for c in torch.cat([state.x, state.c], 1).unbind(1))
    psi_ref = ((torch.rand(n, generator=gen, dtype=torch.float64) * 2 - 1) * math.pi).to(
        device=plant.device, dtype=plant.dtype
    )
    speed = torch.full_like(psi_ref, plant.cruise_speed_mps)
    w = (psi_ref, speed)
    cols = plant.advance(cols, w, 2)  # warm-up (compiles on the first call)
    _sync(plant.device)
    t0 = time.perf_counter()
    cols = plant.advance(cols, w, 2)
    _sync(plant.device)
    probe = max(time.perf_counter() - t0, 1e-6) / 2
    steps = int(min(max(seconds / probe, 3), 5000))
    t0 = time.perf_counter()
    cols = plant.advance(cols, w, steps)
    _sync(plant.device)
    elapsed = time.perf_counter() - t0
    if not bool(torch.isfinite(cols[0]).all()):
        raise FloatingPointError("the benchmark state went non-finite")
    return n * steps / elapsed, steps


def stage_bench(
    device: str, dtype: str, mode: str, sizes: list[int], seconds: float, backend: str
) -> None:
    import torch

    from usvsim.vessel.torch_plant import TorchPlant

    plant = TorchPlant(current=CURRENT, device=device, dtype=dtype)
    if mode == "compile":
        plant.step_function = torch.compile(plant.kernel.step, dynamic=True, backend=backend)
        t0 = time.perf_counter()
        # the compiled step's own equality first (a small N: the compiled code is shape-generic)
        got = episode(plant)
        record(
            "equality",
            device=device,
            dtype=dtype,
            mode=f"compile ({backend})",
            boats=N_EQUALITY,
            steps=SEGMENTS * SEGMENT_STEPS,
            seconds_incl_compile=round(time.perf_counter() - t0, 2),
            **compare(got, reference(), dtype),
        )
    for n in sizes:
        try:
            rate, steps = _rate(plant, n, seconds)
        except torch.cuda.OutOfMemoryError as err:
            record("bench", device=device, dtype=dtype, mode=mode, n=n, error=str(err)[:200])
            break
        record(
            "bench",
            device=device,
            dtype=dtype,
            mode=mode,
            backend=backend if mode == "compile" else None,
            n=n,
            steps=steps,
            boat_substeps_per_s=round(rate),
        )
        if device.startswith("cuda"):
            torch.cuda.empty_cache()


ENV_BOATS, ENV_DECISIONS = 16, 40
# float64 bars of the env against torch-cpu (the CPU suite's, tests/usvsim/task/test_torch_env.py)
ENV_TOL_M, ENV_TOL_RAD, ENV_TOL_REWARD = 1e-6, 1e-7, 1e-8
ENV_BARS = {"max_range_diff_m": ENV_TOL_M, "max_bearing_diff_rad": ENV_TOL_RAD,
            "max_reward_diff": ENV_TOL_REWARD}  # fmt: skip


def env_run(device: str, dtype: str) -> dict[str, np.ndarray]:
    """Observations (float64), rewards and done flags of the torch env over ENV_DECISIONS
    decisions (actions from a fixed seed: steer to the goal, away from the pole, plus noise)."""
    import torch

    from usvsim.task.torch_env import TorchPoleAvoidanceEnv

    env = TorchPoleAvoidanceEnv(
        ENV_BOATS, device=device, dtype=dtype, episodes="numpy", episodes_per_boat=8,
        noise="replay", observation_dtype="float64",
    )  # fmt: skip
    obs, _ = env.reset(seed=11)
    rng = np.random.default_rng(5)
    out: dict[str, list[np.ndarray]] = {"obs": [], "reward": [], "terminated": [], "truncated": []}
    for _ in range(ENV_DECISIONS):
        o = obs.double().cpu().numpy()
        away = np.where(o[:, 0] < 25.0, -np.sign(o[:, 1]) * 0.8, 0.0)
        a = np.clip(2.0 * o[:, 3] + away + rng.normal(0.0, 0.4, ENV_BOATS), -1.0, 1.0)
        obs, reward, terminated, truncated, _ = env.step(torch.as_tensor(a[:, None]))
        out["obs"].append(obs.double().cpu().numpy())
        out["reward"].append(reward.double().cpu().numpy())
        out["terminated"].append(terminated.cpu().numpy())
        out["truncated"].append(truncated.cpu().numpy())
    return {k: np.stack(v) for k, v in out.items()}


def stage_env_equality(device: str, dtypes: list[str]) -> None:
    t0 = time.perf_counter()
    ref = env_run("torch-cpu", "float64")
    record("env_reference", seconds=round(time.perf_counter() - t0, 2), device="torch-cpu")
    for dtype in dtypes:
        t0 = time.perf_counter()
        got = env_run(device, dtype)
        # a boat whose episode ends at another step is in another episode from then on: compare
        # each boat up to its first flag difference
        differs = (got["terminated"] != ref["terminated"]) | (got["truncated"] != ref["truncated"])
        first = np.where(differs.any(0), differs.argmax(0), ENV_DECISIONS)
        upto = (np.arange(ENV_DECISIONS)[:, None] < first[None, :])[..., None]
        diff = got["obs"] - ref["obs"]
        diff[..., 1::2] = (diff[..., 1::2] + np.pi) % (2 * np.pi) - np.pi  # bearings wrapped
        d_obs = np.where(upto, np.abs(diff), 0.0)
        d_reward = np.where(upto[..., 0], np.abs(got["reward"] - ref["reward"]), 0.0)
        flags_equal = not bool(differs.any())
        fields = {
            "max_range_diff_m": float(d_obs[..., 0::2].max()),
            "max_bearing_diff_rad": float(d_obs[..., 1::2].max()),
            "max_reward_diff": float(d_reward.max()),
            "flags_equal": flags_equal,
            "boats_flags_identical": int((first == ENV_DECISIONS).sum()),
            "flag_agreement": float(1.0 - differs.mean()),
            "episodes_ended": int((ref["terminated"] | ref["truncated"]).sum()),
        }
        boats_decisions = (ENV_BOATS, ENV_DECISIONS)
        record_equality("env_equality", device, dtype, boats_decisions, t0, fields, ENV_BARS)


def record_equality(
    stage: str,
    device: str,
    dtype: str,
    boats_decisions: tuple[int, int],
    t0: float,
    fields: dict[str, Any],
    bars: dict[str, float],
) -> None:
    """One equality line of a torch env against torch-cpu float64: ``fields`` (the largest
    differences and ``flags_equal``), the boats and decisions, the seconds since ``t0`` and, in
    float64, ``within_tolerance`` (the flags equal and each of ``bars``' fields at most its bar;
    None for float32, whose tolerance is stated elsewhere)."""
    within = None
    if dtype == "float64":
        within = bool(fields["flags_equal"] and all(fields[k] <= bar for k, bar in bars.items()))
    boats, decisions = boats_decisions
    record(
        stage, device=device, dtype=dtype, boats=boats, decisions=decisions,
        seconds=round(time.perf_counter() - t0, 2), within_tolerance=within, **fields,
    )  # fmt: skip


def stage_env_bench(
    device: str,
    dtype: str,
    mode: str,
    sizes: list[int],
    seconds: float,
    backend: str,
    observation: str = "positional",
) -> None:
    from usvsim.task.torch_env import TorchPoleAvoidanceEnv
    from usvsim.task.torch_env_speed import measure_env_steps

    def make_env(n: int) -> Any:
        return TorchPoleAvoidanceEnv(
            n, device=device, dtype=dtype, observation=observation,
            compile=mode == "compile", compile_backend=backend,
        )  # fmt: skip

    fields = dict(device=device, dtype=dtype, mode=mode, observation=observation,
                  backend=backend if mode == "compile" else None)  # fmt: skip
    bench_sizes("env_bench", sizes, make_env, lambda env: measure_env_steps(env, seconds), fields)


def bench_sizes(
    stage: str,
    sizes: list[int],
    make_env: Callable[[int], Any],
    measure: Callable[[Any], float],
    fields: dict[str, Any],
    names: tuple[str, str] = ("first_step_s", "env_steps_per_s"),
    peak_memory: bool = False,
) -> None:
    """A torch env's bench stage, one ``record(stage, **fields, n=…)`` line a size of ``sizes``
    boats: the seconds to build it (``make_env(n)``), reset it and take its first step of zero
    actions (torch.compile compiles then; ``names[0]``), at the first size whether a step waits
    for the device, ``measure(env)`` (steps/s; ``names[1]``) and with ``peak_memory`` the GPU's
    peak (GiB). A size that runs out of GPU memory records the error and ends the stage."""
    import torch

    cuda = fields["device"].startswith("cuda")
    for n in sizes:
        try:
            t0 = time.perf_counter()
            env = make_env(n)
            env.reset(seed=0)
            zeros = torch.zeros((n, 1), device=env.device, dtype=env.dtype)
            env.step(zeros)  # compiles on the first call
            _sync(env.device)
            first_s = time.perf_counter() - t0
            syncs = step_syncs(env, zeros) if n == sizes[0] else None
            rate = measure(env)
        except torch.cuda.OutOfMemoryError as err:
            record(stage, **fields, n=n, error=str(err)[:200])
            break
        peak = {}
        if peak_memory:
            gib = torch.cuda.max_memory_allocated() / 2**30 if env.device.type == "cuda" else None
            peak["peak_gib"] = None if gib is None else round(gib, 2)
        rates = {names[0]: round(first_s, 2), names[1]: round(rate)}
        record(stage, **fields, n=n, **rates, step_syncs=syncs, **peak)
        del env
        if cuda:
            torch.cuda.empty_cache()
            if peak_memory:
                torch.cuda.reset_peak_memory_stats()


def step_syncs(env: Any, actions: Any) -> str | None:
    """On a GPU: whether a step of ``actions`` waits for the device (torch's sync debug mode
    raises on every synchronising call): "none" or the error's first line; None elsewhere."""
    import torch

    if env.device.type != "cuda":
        return None
    torch.cuda.set_sync_debug_mode("error")
    try:
        for _ in range(3):
            env.step(actions)
        found = "none"
    except RuntimeError as err:
        found = str(err).splitlines()[0][:200]
    finally:
        torch.cuda.set_sync_debug_mode(0)
    return found


def _env_table(grouped: dict[str, list[dict[str, Any]]]) -> list[str]:
    text = [
        "",
        f"study task env (positional), {ENV_BOATS} boats x {ENV_DECISIONS} decisions with the "
        "CPU env's episodes and noise, against torch-cpu float64:",
    ]
    for e in grouped.get("env_equality", []):
        verdict = {True: "ok", False: "EXCEEDED", None: "stated, no bar"}[e["within_tolerance"]]
        text.append(
            f"  {e['device']:>9} {e['dtype']:>8} max |d range| {e['max_range_diff_m']:.3g} m, "
            f"|d bearing| {e['max_bearing_diff_rad']:.3g} rad, |d reward| "
            f"{e['max_reward_diff']:.3g}, flags {'equal' if e['flags_equal'] else 'differ'} "
            f"({e['boats_flags_identical']}/{ENV_BOATS} boats throughout; "
            f"{e['episodes_ended']} episodes ended): {verdict}"
        )
    rates = [b for b in grouped.get("env_bench", []) if "env_steps_per_s" in b]

    def column(b: dict[str, Any]) -> tuple[str, str, str]:
        return (b.get("observation", "positional"), b["mode"], b["dtype"])

    columns = sorted({column(b) for b in rates})
    text += ["", "study task env steps/s (one 2 s decision of one boat, 20 plant steps):"]
    text.append("  " + f"{'N':>10}" + "".join(f"{' '.join(c):>30}" for c in columns))
    for n in sorted({b["n"] for b in rates}):
        cells = []
        for c in columns:
            hit = [b for b in rates if b["n"] == n and column(b) == c]
            cells.append(f"{hit[-1]['env_steps_per_s']:>30.3e}" if hit else f"{'-':>30}")
        text.append("  " + f"{n:>10,}" + "".join(cells))
    for b in grouped.get("env_bench", []):
        if "error" in b:
            text.append(
                f"  env {b.get('observation', '')} {b['mode']} {b['dtype']} N={b['n']:,}: "
                f"{b['error']}"
            )
    for b in rates:
        if b.get("step_syncs") is not None:
            text.append(
                f"  host syncs in a step ({b.get('observation', 'positional')} {b['mode']} "
                f"{b['dtype']}, N={b['n']:,}): {b['step_syncs']}"
            )
    compiled = [b for b in rates if b["mode"] == "compile"]
    if compiled:
        text.append(f"  first step incl. compilation: {compiled[0]['first_step_s']} s")
    return text


def _train_table(grouped: dict[str, list[dict[str, Any]]]) -> list[str]:
    """The ``train-bench`` stage's lines (benchmarks/gpu_check_train.py)."""
    rows = grouped.get("train_bench", [])
    if not rows:
        return []
    text = [
        "",
        "TRPO training on the device (64 decisions an iteration; study: "
        "rl-categorical-positional's network, ow-scene / ow-radar: the open-water setups'):",
    ]
    for r in rows:
        if "error" in r:
            text.append(f"  {r.get('env', 'study')} N={r.get('n', '-')}: {r['error']}")
            continue
        text.append(
            f"  {r.get('env', 'study'):>8} N={r['n']:>8,} {r['dtype']}: "
            f"{r['train_env_steps_per_s']:.3e} env steps/s "
            f"training ({r['iteration_s']:.3g} s per iteration, update {r['update_share']:.0%}), "
            f"rollout alone {r['rollout_env_steps_per_s']:.3e}"
            + (
                f"; host syncs in a rollout step: {r['rollout_syncs']}"
                if r["rollout_syncs"]
                else ""
            )
        )
    return text


def stage_report() -> None:
    """results.jsonl -> results.json (every line, grouped) and table.txt."""
    out = _out_dir()
    path = out / "results.jsonl"
    lines = [json.loads(x) for x in path.read_text().splitlines() if x.strip()]
    grouped: dict[str, list[dict[str, Any]]] = {}
    for line in lines:
        grouped.setdefault(line["stage"], []).append(line)
    bench = grouped.get("bench", [])
    rates = [b for b in bench if "boat_substeps_per_s" in b]
    best32 = max((b["boat_substeps_per_s"] for b in rates if b["dtype"] == "float32"), default=0)
    summary = {
        "best_float32_boat_substeps_per_s": best32,
        "target_float32": TARGET_F32,
        "target_met": best32 >= TARGET_F32,
        "equality_all_within_tolerance": bool(grouped.get("equality"))
        and all(e["within_tolerance"] for e in grouped.get("equality", [])),
    }
    (out / "results.json").write_text(json.dumps({"summary": summary, **grouped}, indent=2))
    text = [_env_line(grouped), ""]
    text.append("equality, 64 boats x 1,000 steps, against torch-cpu float64:")
    for e in grouped.get("equality", []):
        tol = e["tolerance_m_rad"]
        text.append(
            f"  {e['device']:>9} {e['dtype']:>8} {e['mode']:<18} max |dpos| "
            f"{e['max_position_diff_m']:.3g} m, max |dpsi| {e['max_heading_diff_rad']:.3g} rad"
            f"  (tolerance {tol[0]:g} m, {tol[1]:g} rad: "
            + ("ok)" if e["within_tolerance"] else "EXCEEDED)")
            + {True: "; rerun identical", False: "; rerun DIFFERS", None: ""}[
                e.get("same_seed_same_episode")
            ]
        )
    columns = sorted({(b["mode"], b["dtype"]) for b in rates})
    sizes = sorted({b["n"] for b in rates})
    text += ["", "plant boat-substeps/s (one 0.1 s step of one boat):"]
    text.append("  " + f"{'N':>10}" + "".join(f"{m + ' ' + d:>20}" for m, d in columns))
    for n in sizes:
        cells = []
        for m, d in columns:
            hit = [b for b in rates if b["n"] == n and (b["mode"], b["dtype"]) == (m, d)]
            cells.append(f"{hit[-1]['boat_substeps_per_s']:>20.3e}" if hit else f"{'-':>20}")
        text.append("  " + f"{n:>10,}" + "".join(cells))
    for b in bench:
        if "error" in b:
            text.append(f"  {b['mode']} {b['dtype']} N={b['n']:,}: {b['error']}")
    from gpu_check_openwater import openwater_table  # the open-water stage's lines
    from gpu_check_ow_train import ow_train_table

    text += _env_table(grouped) + openwater_table(grouped) + _train_table(grouped)
    text += ow_train_table(grouped)
    best_env = max((b.get("env_steps_per_s", 0) for b in grouped.get("env_bench", [])), default=0)
    summary["best_env_steps_per_s"] = best_env
    summary["best_openwater_scene_decision_steps_per_s"] = max(
        (b.get("decision_steps_per_s", 0) for b in grouped.get("ow_bench", [])), default=0
    )
    summary["best_train_env_steps_per_s"] = max(
        (b.get("train_env_steps_per_s", 0) for b in grouped.get("train_bench", [])), default=0
    )
    (out / "results.json").write_text(json.dumps({"summary": summary, **grouped}, indent=2))
    for s in grouped.get("stage_end", []):
        if s.get("status") != "ok":
            text.append(f"stage {s['name']}: {s['status']} after {s.get('seconds', '?')} s")
    text.append("")
    text.append(
        f"best float32: {best32:.3e} boat-substeps/s; target {TARGET_F32:.0e}: "
        + ("met" if summary["target_met"] else "NOT met")
    )
    (out / "table.txt").write_text("\n".join(text) + "\n")
    print("\n".join(text))


def _env_line(grouped: dict[str, list[dict[str, Any]]]) -> str:
    env = (grouped.get("env") or [{}])[-1]
    return (
        f"{env.get('gpu', 'no GPU')}; torch {env.get('torch')} (CUDA {env.get('torch_cuda')}), "
        f"triton {env.get('triton')}, numpy {env.get('numpy')}, python {env.get('python')}, "
        f"casadi {env.get('casadi')}"
    )


def add_equality_stage(sub: Any, name: str) -> None:
    """An equality stage's command: ``--device``, ``--dtypes`` (comma-separated)."""
    eq = sub.add_parser(name)
    eq.add_argument("--device", default="cuda")
    eq.add_argument("--dtypes", default="float64,float32")


def add_bench_stage(sub: Any, name: str, sizes: str, observations: list[str] | None = None) -> None:
    """A bench stage's command: ``--device``, ``--dtype``, ``--mode``, ``--sizes`` (default
    ``sizes``), ``--seconds``, ``--backend`` (torch.compile's) and, with ``observations``,
    ``--observation`` (default the first)."""
    bench = sub.add_parser(name)
    bench.add_argument("--device", default="cuda")
    bench.add_argument("--dtype", default="float32", choices=["float32", "float64"])
    bench.add_argument("--mode", default="eager", choices=["eager", "compile"])
    bench.add_argument("--sizes", default=sizes)
    bench.add_argument("--seconds", type=float, default=1.0)
    bench.add_argument("--backend", default="inductor")  # torch.compile backend
    if observations:
        bench.add_argument("--observation", default=observations[0], choices=observations)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="stage", required=True)
    sub.add_parser("env")
    add_equality_stage(sub, "equality")
    add_bench_stage(sub, "bench", "1000,10000,100000,1000000,10000000")
    add_equality_stage(sub, "env-equality")
    add_bench_stage(sub, "env-bench", "1000,10000,100000,1000000",
                    ["positional", "radar", "radar+goal"])  # fmt: skip
    sub.add_parser("report")
    args = parser.parse_args()
    if args.stage == "env":
        stage_env()
    elif args.stage == "equality":
        stage_equality(args.device, args.dtypes.split(","))
    elif args.stage == "env-equality":
        stage_env_equality(args.device, args.dtypes.split(","))
    elif args.stage == "env-bench":
        sizes = [int(float(s)) for s in args.sizes.split(",")]
        stage_env_bench(
            args.device, args.dtype, args.mode, sizes, args.seconds, args.backend, args.observation
        )
    elif args.stage == "bench":
        sizes = [int(float(s)) for s in args.sizes.split(",")]
        stage_bench(args.device, args.dtype, args.mode, sizes, args.seconds, args.backend)
    else:
        stage_report()


if __name__ == "__main__":
    main()
