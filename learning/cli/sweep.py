"""``usvsim sweep``: train setups × seeds × hyperparameters under Ray Tune, then the across-seed
statistics (:mod:`learning.experiments.sweep`, :mod:`learning.experiments.sweep_report`).

This module is the command line only: options, the sweep's definition from flags or a JSON file,
messages and exit codes (0: every trial finished; 1: a trial crashed; 130: interrupted by
Ctrl-C or SIGTERM, run the same command again to continue). Every numeric option has a range
(``bounds`` metadata, checked before anything runs; the same ranges hold for a ``--config`` file).
``--tensorboard DIR``: each trial also writes its ``log.csv`` rows as TensorBoard scalars into
``DIR/<trial>`` (named as its run folder; :mod:`learning.experiments.run_log`).
"""

from __future__ import annotations

import dataclasses
import json
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from usvsim.common.options import bounds

__all__ = ["SweepArgs", "run", "spec_of"]

INTERRUPTED = 130  # exit status of an interrupted sweep (as a shell's after Ctrl-C)

# the options that define the sweep (the rest say where and how it runs)
_SPEC_OPTIONS = (
    "setups",
    "seeds",
    "grid",
    "random",
    "search",
    "samples",
    "search_seed",
    "iterations",
    "validate_every",
    "stop_after",
    "n_envs",
    "time_budget_s",
    "threads",
    "heldout",
    "ship_rule",
    "device",
)


@dataclass(frozen=True)
class SweepArgs:
    """Train setups x seeds x hyperparameters on Ray Tune; across-seed statistics (rliable)."""

    setups: str = "positional"  # setups or groups, a,b: positional radar rl il open-water colreg
    seeds: str = "0-4"  # a range 0-4 or a list 0,2,7
    name: str = ""  # sweep name; default <setups>-seeds<seeds>
    config: str = ""  # JSON file with the sweep's fields (SweepSpec); then no definition flags
    grid: str = ""  # FIELD=V1,V2;FIELD=... every combination, e.g. max_kl=0.01,0.02
    random: str = ""  # FIELD=DIST;... e.g. max_kl=loguniform:0.005:0.05 (search random/optuna)
    search: Literal["grid", "random", "optuna"] = "grid"  # optuna: TPE on validation only
    samples: int = field(  # random: draws per setup x seed x grid point; optuna: trials
        default=1, metadata=bounds(ge=1, le=100_000)
    )
    search_seed: int = field(  # seeds the random draws and Optuna's sampler
        default=0, metadata=bounds(ge=0, lt=2**32)
    )
    iterations: int = field(default=0, metadata=bounds(ge=0))  # budget per trial; 0: the setup's
    validate_every: int = field(default=0, metadata=bounds(ge=0))  # 0: the setup's
    stop_after: int = field(  # stop a trial after this many consecutive 15/15; 0: never
        default=3, metadata=bounds(ge=0)
    )
    n_envs: int = field(  # boats per batch; 0: the setup's
        default=0, metadata=bounds(ge=1, le=65_536, zero_ok=True)
    )
    time_budget_s: float = field(  # wall-clock limit per trial, s; 0: none
        default=0.0, metadata=bounds(ge=0)
    )
    threads: int = field(default=1, metadata=bounds(ge=1, le=1024))  # torch threads = CPUs/trial
    heldout: int = field(  # held-out episodes per best.pt (for the report only)
        default=200, metadata=bounds(ge=1, le=100_000)
    )
    ship_rule: str = "median-validation"  # which seed ships: median-validation or seed:K
    device: Literal["cpu", "torch-cpu", "cuda"] = "cpu"  # where trials train (usvsim train)
    gpus_per_trial: float = field(  # GPU share a trial asks Ray for; 0: 1 with --device cuda
        default=0.0, metadata=bounds(ge=0, le=64)
    )
    max_concurrent: int = field(  # trials at once; 0: one per CPU (threads CPUs each)
        default=0, metadata=bounds(ge=0, le=100_000)
    )
    address: str = ""  # an existing Ray cluster, e.g. ray://head:10001; "": local Ray
    out: str = ""  # sweep folder; default usvsim-results/sweep/<name>
    report_only: bool = False  # only (re)write the report from the trials run so far
    shipped: bool = True  # evaluate usvsim's shipped models for the comparison
    tensorboard: str = ""  # also each trial's TensorBoard scalars in DIR/<trial>; "": none


def _fail(message: str) -> SystemExit:
    return SystemExit(f"usvsim sweep: {message}")


def _pairs(text: str, flag: str) -> list[tuple[str, str]]:
    out = []
    for item in filter(None, (t.strip() for t in text.split(";"))):
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise _fail(f"bad {flag} item {item!r}; allowed: FIELD=VALUE[;FIELD=VALUE]")
        out.append((key.strip(), value.strip()))
    return out


def spec_of(args: SweepArgs) -> Any:
    """The :class:`learning.experiments.sweep.SweepSpec` that ``args`` define."""
    from learning.experiments.sweep import (
        Distribution,
        SweepSpec,
        expand_setups,
        parse_seeds,
    )

    try:
        if args.config:
            defaults = SweepArgs()
            given = [k for k in _SPEC_OPTIONS if getattr(args, k) != getattr(defaults, k)]
            if given:
                flags = ", ".join("--" + k.replace("_", "-") for k in given)
                raise _fail(f"--config defines the sweep; drop {flags}")
            data = json.loads(Path(args.config).read_text())
            data.setdefault("name", args.name or Path(args.config).stem)
            return SweepSpec.from_json(data)
        setups = expand_setups([s.strip() for s in args.setups.split(",") if s.strip()])
        seeds = parse_seeds(args.seeds)
        grid = tuple(
            (k, tuple(json.loads(v) if _is_json(v) else v for v in values.split(",")))
            for k, values in _pairs(args.grid, "--grid")
        )
        rand = tuple((k, Distribution.parse(v)) for k, v in _pairs(args.random, "--random"))
        name = args.name or f"{args.setups.replace(',', '+')}-seeds{args.seeds}"
        options = {k: getattr(args, k) for k in _SPEC_OPTIONS[4:]}
        return SweepSpec(name, setups, seeds, grid, rand, **options)
    except (ValueError, OSError) as err:
        raise _fail(str(err)) from None


def _is_json(text: str) -> bool:
    try:
        json.loads(text)
    except json.JSONDecodeError:
        return False
    return True


def _print_summary(report: dict[str, Any], root: Path) -> None:
    for r in report["arms"]:
        ci = r["heldout_iqm_ci95"]
        ci_text = f" [{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]" if ci else ""
        iqm = r["heldout_iqm"]
        print(
            f"{r['arm']}: {len(r['seeds'])} seeds, held-out IQM "
            f"{'-' if iqm != iqm else f'{100 * iqm:.1f} %'}{ci_text}, "
            f"15/15 reached by {r['reached_15_of_15']}, shipped seed {r['shipped_seed']}"
        )
    print(f"report: {root / 'report.md'} (and report.json, PNGs)")


def run(args: SweepArgs) -> int:
    """Run ``usvsim sweep`` (module docstring)."""
    from learning.experiments.sweep import SweepRun, run_sweep
    from learning.experiments.sweep_report import write_report
    from usvsim.common.options import check_bounds

    check_bounds(args)  # the ranges of the fields (usvsim.cli checked them already)
    if args.tensorboard:
        from learning.experiments.run_log import check_tensorboard

        check_tensorboard()
    spec = spec_of(args)
    root = Path(args.out or f"usvsim-results/sweep/{spec.name}")
    if args.report_only:
        if not (root / "trials.json").is_file():
            raise _fail(f"{root} holds no sweep (no trials.json)")
        _print_summary(write_report(root, compare_shipped=args.shipped), root)
        return 0
    gpus = args.gpus_per_trial or (1.0 if spec.device == "cuda" else 0.0)
    if spec.device == "cuda" and not args.address:
        import torch

        if not torch.cuda.is_available():
            raise _fail("--device cuda: torch sees no CUDA GPU here (use cpu or torch-cpu)")
    where = SweepRun(
        root,
        address=args.address,
        max_concurrent=args.max_concurrent,
        tensorboard=args.tensorboard,
        gpus_per_trial=gpus,
    )
    print(
        f"usvsim sweep {spec.name}: {len(spec.setups)} setups x {len(spec.seeds)} seeds"
        f"{' x grid' if spec.grid else ''} ({spec.search}), folder {root}; "
        f"{'Ray cluster ' + args.address if args.address else 'local Ray'}",
        flush=True,
    )
    try:
        trials = run_sweep(spec, dataclasses.replace(where, say=_say))
    except ValueError as err:
        raise _fail(str(err)) from None
    report = write_report(root, compare_shipped=args.shipped)
    _print_summary(report, root)
    crashed = [t["dir"] for t in trials if t["status"] == "crashed"]
    pending = [t["dir"] for t in trials if t["status"] == "not run"]
    if crashed:
        print(f"crashed: {', '.join(crashed)} (errors in {root / 'trials.json'})", file=sys.stderr)
    if pending:
        print(
            f"interrupted: {len(pending)} trial(s) not finished; run the same command to continue",
            file=sys.stderr,
        )
        return INTERRUPTED
    return 1 if crashed else 0


def _say(line: str) -> None:
    print(line, flush=True)
