"""The ``usvsim bench`` command: run the benchmark, write its files, print the table or JSON."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from usvsim.common.fileio import check_writable_dir
from usvsim.evaluation.bench import BenchArgs, format_table, run_bench, to_json, write_results
from usvsim.evaluation.bench_sweep import load_sweep, with_sweep_columns

__all__ = ["run_bench_command"]

INTERRUPTED = 130  # exit status after Ctrl-C / SIGTERM


def run_bench_command(args: BenchArgs) -> int:
    """The ``usvsim bench`` command (module docstring); 130 after Ctrl-C (results so far kept)."""
    check_writable_dir(args.out, "--out")  # before the evaluation, not after it
    import torch  # here: the classical helmsmen need no torch until a learned one is named

    torch.set_num_threads(args.threads)  # BenchArgs.threads: the same figures on any machine
    if args.suite == "stress":
        return _run_stress_command(args)
    if args.suite == "colreg":
        return _run_colreg_command(args)
    result = run_bench(args)
    files = write_results(result, Path(args.out), plots=args.plots)
    sweep = load_sweep(args.sweep) if args.sweep else None
    if args.json:
        text = to_json(result, [str(f) for f in files])
        if sweep is not None:  # the sweep's across-seed figures under "sweep"
            text = json.dumps({**json.loads(text), "sweep": sweep.to_json()}, indent=2)
        print(text)
    else:
        print(f"usvsim bench — scenario {args.scenario}")
        table = format_table(result.rows)
        print(table if sweep is None else with_sweep_columns(table, result.rows, sweep))
        print(
            f"evaluated in {result.wall_s:.1f} s; results in {args.out}/ "
            f"({', '.join(f.name for f in files[:2])}, {max(len(files) - 2, 0)} path plots)"
        )
    if result.interrupted:
        kept = f"{len(result.rows)} sets written to {args.out}/" if result.rows else "nothing"
        print(f"usvsim bench: interrupted; {kept}", file=sys.stderr, flush=True)
        return INTERRUPTED
    return 0


def _run_stress_command(args: BenchArgs) -> int:
    """``usvsim bench --suite stress`` (:mod:`usvsim.evaluation.stress`)."""
    from usvsim.evaluation.seed_stats import seed_tables_for, with_seed_columns
    from usvsim.evaluation.stress import run_stress_args, stress_json, write_stress

    result = run_stress_args(args)
    files = write_stress(result, Path(args.out), plots=args.plots)
    # the across-seed figures of the shipped models' setups (usvsim/models/seeds/), if any
    seeds = {h: t for h, t in seed_tables_for(result.helmsmen).items() if t.split == result.split}
    if args.json:
        text = stress_json(result, [str(f) for f in files])
        if seeds:  # under "seeds", by helmsman
            payload = {**json.loads(text), "seeds": {h: t.to_json() for h, t in seeds.items()}}
            text = json.dumps(payload, indent=2, allow_nan=False)
        print(text)
    else:
        print(f"usvsim bench — stress suite, {result.episodes_per_set} episodes per set")
        print(with_seed_columns(format_table(result.rows), result.rows, seeds, result.split))
        written = ", ".join(f.name for f in files)
        print(f"ran in {result.wall_s:.1f} s; results in {args.out}/ ({written})")
    if result.interrupted:
        kept = f"{len(result.rows)} rows written to {args.out}/" if result.rows else "nothing"
        print(f"usvsim bench: interrupted; {kept}", file=sys.stderr, flush=True)
        return INTERRUPTED
    return 0


def _run_colreg_command(args: BenchArgs) -> int:
    """``usvsim bench --suite colreg`` (:mod:`usvsim.evaluation.colreg_suite`)."""
    from usvsim.evaluation.colreg_report import colreg_json, colreg_table, write_colreg
    from usvsim.evaluation.colreg_suite import run_colreg_args

    result = run_colreg_args(args)
    files = write_colreg(result, Path(args.out), plots=args.plots)
    if args.json:
        print(colreg_json(result, [str(f) for f in files]))
    else:
        print(f"usvsim bench — COLREG suite, {result.episodes_per_set} episodes per set")
        print(colreg_table(result))
        written = ", ".join(f.name for f in files)
        print(f"ran in {result.wall_s:.1f} s; results in {args.out}/ ({written})")
    if result.interrupted:
        kept = f"{len(result.rows)} rows written to {args.out}/" if result.rows else "nothing"
        print(f"usvsim bench: interrupted; {kept}", file=sys.stderr, flush=True)
        return INTERRUPTED
    return 0
