"""Expert-likeness in traffic (issue 41, "IL against RL of the same observation: compliance, path
distance to the expert, and side agreement, IQM across seeds").

The expert (``--expert``: ``sb-mpc`` on the true scene by default, or ``sb-mpc-expert``, the
human-like SB-MPC expert the COLREG demonstrations come from) and every helmsman drive the same
episodes of the COLREG suite (``--sets``, ``--episodes`` per set, the ``--split``: test by
default); per helmsman: success, collisions and COLREG compliance (the suite's scorer, Wilson
95 % intervals), the path distance to the expert's path and the lock-step distance (bootstrap
95 % intervals over episodes), and the side agreement over the expert's encounters (Wilson);
per ``--seeds`` group (checkpoints of one setup from different training seeds) the IQM of each
figure over the seeds with rliable's 95 % interval. Definitions and sources:
:mod:`usvsim.evaluation.colreg_likeness`; the runner:
:mod:`usvsim.evaluation.colreg_likeness_bench`.

Writes ``OUT/likeness.json`` and ``OUT/likeness.md`` (atomic; the table is generated from the
JSON's result) and prints the table::

    nice python benchmarks/colreg_likeness.py --helmsmen vo,sb-mpc-radar --sets imazu \\
        --episodes 5 --out usvsim-results/colreg-likeness
    python benchmarks/colreg_likeness.py --sets imazu --episodes 5 \\
        --seeds IL=runs/il/s0/best.pt,runs/il/s1/best.pt,runs/il/s2/best.pt \\
        --seeds RL=runs/rl/s0/best.pt,runs/rl/s1/best.pt,runs/rl/s2/best.pt

``--sets``: ``all``, ``imazu`` (the 22 problems), ``trafficgen`` (the three sets) or set names,
comma-separated. Bad input (an unknown helmsman, set or expert, a missing checkpoint) is one line
on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from functools import partial
from pathlib import Path
from typing import Any

from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_write_text
from usvsim.evaluation.colreg_likeness_bench import (
    EXPERT_SEED,
    HUMAN_EXPERT,
    likeness_markdown,
    run_likeness,
)
from usvsim.evaluation.colreg_suite import COLREG_SETS, ColregSet, select_colreg_sets
from usvsim.evaluation.seed_stats import BOOTSTRAP_REPS

FAMILIES = ("imazu", "trafficgen")  # --sets shorthands: every set named <family>-*


def chosen_sets(spec: str) -> tuple[ColregSet, ...]:
    """The sets of ``--sets`` (module docstring); ``UserError`` for an unknown name."""
    names: list[str] = []
    for item in (s.strip() for s in spec.split(",") if s.strip()):
        if item == "all":
            names += [s.name for s in COLREG_SETS]
        elif item in FAMILIES:
            names += [s.name for s in COLREG_SETS if s.name.startswith(item + "-")]
        else:
            names.append(item)
    if not names:
        raise UserError("--sets is empty; give all, imazu, trafficgen or set names")
    return select_colreg_sets(names)


def helmsmen(args: argparse.Namespace) -> tuple[dict[str, Any], dict[str, list[str]]]:
    """Label → factory of ``--helmsmen`` and every ``--seeds`` member, and group → labels.
    Every helmsman is built once here, so a bad name or file fails before anything runs."""
    from usvsim.helm.registry import make_helmsman

    factories: dict[str, Any] = {}
    for name in (h.strip() for h in args.helmsmen.split(",") if h.strip()):
        make_helmsman(name)
        factories[name] = partial(make_helmsman, name)
    groups: dict[str, list[str]] = {}
    for spec in args.seeds:
        group, sep, members = spec.partition("=")
        paths = [m.strip() for m in members.split(",") if m.strip()]
        if not sep or not group.strip() or len(paths) < 2:
            raise UserError(f"--seeds {spec!r}: write SETUP=file1,file2[,...] (two or more)")
        group = group.strip()
        if group in groups or group in factories:
            raise UserError(f"--seeds {group!r} is named twice")
        groups[group] = []
        for i, path in enumerate(paths):
            make_helmsman(path)
            label = f"{group}#{i}"
            factories[label] = partial(make_helmsman, path)
            groups[group].append(label)
    if not factories:
        raise UserError("nothing to compare: give --helmsmen or --seeds")
    return factories, groups


def parse(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--helmsmen", default="vo,sb-mpc-radar", help="comma-separated names/files")
    ap.add_argument("--seeds", action="append", default=[], metavar="SETUP=F1,F2,...",
                    help="one setup's seeds (repeatable): IQM across them")  # fmt: skip
    ap.add_argument("--sets", default="imazu", help="all, imazu, trafficgen or set names")
    ap.add_argument("--episodes", type=int, default=5, help="per set")
    ap.add_argument("--split", default="test", choices=("test", "validation"))
    ap.add_argument("--expert", default="sb-mpc", help=f"a helmsman's name or {HUMAN_EXPERT}")
    ap.add_argument("--expert-seed", type=int, default=EXPERT_SEED, help=f"{HUMAN_EXPERT}'s")
    ap.add_argument("--reactive-targets", action="store_true", help="targets steered by vo")
    ap.add_argument("--reps", type=int, default=BOOTSTRAP_REPS, help="rliable's resamples")
    ap.add_argument("--out", default="usvsim-results/colreg-likeness")
    ap.add_argument("--json", action="store_true", help="print the JSON instead of the table")
    args = ap.parse_args(argv)
    if args.episodes < 1 or args.reps < 1:
        raise UserError(f"--episodes and --reps must be >= 1, got {args.episodes}, {args.reps}")
    return args


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse(argv)
        sets = chosen_sets(args.sets)
        factories, groups = helmsmen(args)
        if args.expert != HUMAN_EXPERT:
            from usvsim.helm.registry import make_helmsman

            make_helmsman(args.expert)
        result = run_likeness(
            factories, sets, args.episodes, groups=groups, split=args.split,
            expert=args.expert, expert_seed=args.expert_seed,
            reactive_targets=args.reactive_targets, reps=args.reps,
            progress=lambda m: print(f"colreg_likeness: {m}", file=sys.stderr, flush=True),
        )  # fmt: skip
    except UserError as err:
        print(f"colreg_likeness: {err}", file=sys.stderr)
        return 2
    argv_used = sys.argv[1:] if argv is None else argv
    command = "python benchmarks/colreg_likeness.py " + shlex.join(argv_used)
    payload = result.to_json(command)
    table = likeness_markdown(payload)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "likeness.json", json.dumps(payload, indent=1, allow_nan=False) + "\n")
    atomic_write_text(out / "likeness.md", table)
    print(json.dumps(payload, indent=1) if args.json else table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
