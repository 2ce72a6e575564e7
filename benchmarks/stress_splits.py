"""The stress suite on both splits, one ``usvsim bench --suite stress`` process per helmsman and
split, ``--jobs`` at a time; merged into ``OUT/stress-validation.json`` and
``OUT/stress-test.json`` (the format of ``usvsim bench --suite stress --json``, rows of every
helmsman; ``wall_s`` the sum of the processes' run times). The model cards' validation and test
figures (:mod:`usvsim.evaluation.model_cards`) come from these two files::

    python benchmarks/stress_splits.py --jobs 16 --out usvsim-results/stress-splits

Each process's own JSON stays in ``OUT/<split>/<helmsman>.json``, so a run cut short keeps every
finished helmsman (run again: finished ones are not run twice). The order is longest first (radar
policies), so the last processes to start are short ones.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SPLITS = ("validation", "test")


def _helmsmen() -> list[str]:
    from usvsim.helm.registry import available_helmsmen

    return list(available_helmsmen())


def _cost(name: str) -> int:
    """Rough relative run time: radar images cost most, then the scene policies."""
    return 3 if "radar" in name else 2 if ("scene" in name or name.startswith("vo")) else 1


def _run_one(
    name: str, split: str, out: Path, episodes: int, sets: str
) -> tuple[str, str, float, int]:
    target = out / split / f"{name}.json"
    if target.is_file():
        return name, split, 0.0, 0
    target.parent.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "usvsim.cli", "bench", "--suite", "stress", "--split", split]
    cmd += ["--helmsmen", name, "--stress-episodes", str(episodes), "--json", "--no-plots"]
    cmd += ["--out", str(out / split / f"{name}-files")] + (["--sets", sets] if sets else [])
    env = {**os.environ, "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env, check=False)
    if done.returncode == 0:
        partial = target.with_suffix(".json.part")
        partial.write_text(done.stdout)
        partial.replace(target)
    else:
        (out / split / f"{name}.err").write_text(done.stderr[-4000:])
    return name, split, time.perf_counter() - t0, done.returncode


def merge(out: Path, split: str) -> dict[str, Any] | None:
    """The split's per-helmsman files as one stress JSON (None if there are none)."""
    parts = [json.loads(p.read_text()) for p in sorted((out / split).glob("*.json"))]
    if not parts:
        return None
    return {
        "suite": "stress",
        "split": split,
        "sets": parts[0]["sets"],
        "helmsmen": [h for p in parts for h in p["helmsmen"]],
        "episodes_per_set": parts[0]["episodes_per_set"],
        "rows": [r for p in parts for r in p["rows"]],
        "wall_s": sum(p["wall_s"] for p in parts),
        "files": [],
        "interrupted": any(p["interrupted"] for p in parts),
        "skipped": [s for p in parts for s in p["skipped"]],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--helmsmen", default="", help="comma-separated; empty: every one")
    parser.add_argument("--splits", default="validation,test")
    parser.add_argument("--sets", default="", help="comma-separated stress sets; empty: all")
    parser.add_argument("--out", type=Path, default=Path("usvsim-results/stress-splits"))
    args = parser.parse_args(argv)
    names = [n for n in args.helmsmen.split(",") if n] or _helmsmen()
    splits = [s for s in args.splits.split(",") if s in SPLITS]
    jobs = sorted(((n, s) for n in names for s in splits), key=lambda j: -_cost(j[0]))
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        futures = [pool.submit(_run_one, n, s, args.out, args.episodes, args.sets) for n, s in jobs]
        for future in futures:
            name, split, wall, rc = future.result()
            print(f"{split:10s} {name:30s} {wall:7.1f} s  rc {rc}", flush=True)
    for split in splits:
        merged = merge(args.out, split)
        if merged is not None:
            (args.out / f"stress-{split}.json").write_text(json.dumps(merged, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
