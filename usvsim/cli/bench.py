"""The ``usvsim bench`` command: run the benchmark, write its files, print the table or JSON."""

from __future__ import annotations

from pathlib import Path

from usvsim.evaluation.bench import BenchArgs, format_table, run_bench, to_json, write_results

__all__ = ["run_bench_command"]


def run_bench_command(args: BenchArgs) -> int:
    """The ``usvsim bench`` command (module docstring)."""
    result = run_bench(args)
    files = write_results(result, Path(args.out), plots=not args.no_plots)
    if args.json:
        print(to_json(result, [str(f) for f in files]))
        return 0
    print(f"usvsim bench — scenario {args.scenario}")
    print(format_table(result.rows))
    print(
        f"evaluated in {result.wall_s:.1f} s; results in {args.out}/ "
        f"({', '.join(f.name for f in files[:2])}, {len(files) - 2} path plots)"
    )
    return 0
