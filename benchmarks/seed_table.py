"""A recommended setup's across-seed figures (issue 37) from its seeds' stress-suite JSONs, into
``usvsim/models/seeds/<setup>.json`` (:mod:`usvsim.evaluation.seed_stats`; needs rliable, the
``sweep`` extra). From the repository root, after ``usvsim sweep`` and one bench per split::

    usvsim bench --suite stress --helmsmen s0.pt,s1.pt,s2.pt --split validation --json \\
        --no-plots > validation.json                                  # then --split test
    python benchmarks/seed_table.py --setup il-categorical-scene-ow \\
        --validation validation.json --test test.json --rename s0=0,s1=1,s2=2

``--validation`` and ``--test`` take one or more JSONs (seeds benched in several runs);
``--rename`` maps each helmsman label of their rows to its seed. The command itself is written
into the file (``"command"``), with ``--provenance`` (how the seeds were trained and benched).
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from usvsim.common.errors import UserError
from usvsim.evaluation.seed_stats import SEEDS_DIR, seed_table, write_seed_table


def parse_rename(text: str) -> dict[str, int]:
    """``"a=0,b=1"`` -> ``{"a": 0, "b": 1}``; ``UserError`` for anything else."""
    out: dict[str, int] = {}
    for item in (t.strip() for t in text.split(",") if t.strip()):
        label, _, seed = item.rpartition("=")
        if not label or not seed.isdigit():
            raise UserError(f"--rename {item!r}: write LABEL=SEED, e.g. ilcs-seed0=0")
        out[label] = int(seed)
    if len(set(out.values())) != len(out):
        raise UserError(f"--rename {text!r}: a seed is given twice")
    return out


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--setup", required=True, help="the setup the seeds trained")
    parser.add_argument("--validation", nargs="+", type=Path, required=True,
                        help="stress JSONs of the validation split")  # fmt: skip
    parser.add_argument("--test", nargs="+", type=Path, required=True,
                        help="stress JSONs of the test split")  # fmt: skip
    parser.add_argument("--rename", required=True, help="LABEL=SEED,... (helmsman label -> seed)")
    parser.add_argument(
        "--rule-sets",
        choices=("all", "original"),
        default="all",
        help="the sets whose validation mean the seed rule reads "
        "(all: every set of the validation JSONs; original: the 22)",
    )
    parser.add_argument("--provenance", default="", help="how the seeds were trained and benched")
    parser.add_argument("--out", type=Path, help="default usvsim/models/seeds/SETUP.json")
    args = parser.parse_args(argv)
    try:
        table = seed_table(
            args.setup,
            [json.loads(p.read_text()) for p in args.validation],
            [json.loads(p.read_text()) for p in args.test],
            parse_rename(args.rename),
            rule_sets=args.rule_sets,
            command=shlex.join(["python", "benchmarks/seed_table.py", *argv]),
            provenance=args.provenance,
        )
    except (UserError, OSError, ValueError) as err:
        print(f"seed_table.py: {err}", file=sys.stderr)
        return 2
    out = args.out or SEEDS_DIR / f"{args.setup}.json"
    write_seed_table(table, out)
    seeds = " / ".join(f"{100 * v:.2f}" for v in table.validation_means.values())
    print(
        f"{out}: seeds {list(table.seeds)}; validation means {seeds} %; "
        f"rule picks seed {table.picked_seed}; 22 original sets: {table.original.cell()}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
