"""Point a model card at the seed its rule picked (issue 37): after ``train_il.py --finished
--ship`` or ``train_rl.py --finished --ship`` wrote that seed's ``best.pt`` as the shipped file
(same name, new weights), set the card's facts from the new file and its chain of runs::

    python benchmarks/seed_card.py radar-gaussian-gail-openwater \
        --run "usvsim train il-gaussian-radar-ow --seed 2 --iterations 391 ...=7883.9" \
        --note "Shipped by the seed rule of docs/notes/2026-12-seeds.md: seed 2 of 0-2."

``seed``, ``code_commit``, ``best_iteration`` and ``date`` come from the checkpoint
(:func:`usvsim.helm.registry.checkpoint_facts`, the fields ``check_cards`` compares), the
``validation.best_pt`` record from its validation record (the fields the card held before),
``runs`` from ``--run COMMAND=WALL_CLOCK_S`` (repeat, in the chain's order; ``--run-note``, as
many, gives each its note) and ``notes`` from ``--note``. The stress figures and recommended
marks are left to ``model_cards.py`` (they need the new file's stress runs). Bad input: one
line, exit 2.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

from learning.experiments.checkpoint import load_checkpoint
from usvsim.common.errors import UserError
from usvsim.evaluation.model_cards import TrainingRun, check_cards, load_cards, write_cards
from usvsim.helm.registry import checkpoint_facts

#: The validation record's fields a card keeps under ``validation.best_pt``.
BEST_PT_FIELDS = (
    "iteration", "successes", "n_episodes", "selection_successes",
    "family_successes", "family_n_episodes", "family_collisions", "family_min_distance_m",
    "crowded_successes", "crowded_n_episodes", "crowded_collisions", "crowded_min_distance_m",
    "radar_successes", "radar_n_episodes", "radar_collisions", "radar_min_distance_m",
)  # fmt: skip


def _run(text: str, note: str = "") -> TrainingRun:
    command, sep, seconds = text.rpartition("=")
    try:
        wall = float(seconds)
    except ValueError:
        wall = -1.0
    if not sep or not command.strip() or not wall >= 0:
        raise UserError(f"--run must be COMMAND=WALL_CLOCK_S with seconds >= 0, got {text!r}")
    return TrainingRun(command=command.strip(), wall_clock_s=wall, note=note)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", help="the shipped model's name (usvsim models)")
    parser.add_argument("--run", action="append", default=[], help="COMMAND=WALL_CLOCK_S")
    parser.add_argument("--run-note", action="append", default=[], help="a run's note, in order")
    parser.add_argument("--note", required=True, help="the card's notes")
    args = parser.parse_args(argv)
    try:
        if args.run_note and len(args.run_note) != len(args.run):
            raise UserError(f"give one --run-note per --run ({len(args.run)}), or none")
        notes = args.run_note or [""] * len(args.run)
        runs = tuple(_run(r, n) for r, n in zip(args.run, notes, strict=True))
        if not runs:
            raise UserError("give the chain's runs with --run COMMAND=WALL_CLOCK_S")
        cards = load_cards()
        if args.model not in cards:
            raise UserError(f"no model {args.model!r}; shipped: {', '.join(sorted(cards))}")
        card = cards[args.model]
        path = f"usvsim/models/{args.model}.pt"
        facts = checkpoint_facts(path)
        record = load_checkpoint(path).validation or {}
        best_pt = {k: record[k] for k in BEST_PT_FIELDS if k in record}
        validation = {**card.validation, "best_pt": best_pt}
        cards[args.model] = replace(
            card,
            seed=facts["seed"],
            code_commit=facts["code_commit"],
            best_iteration=facts["best_iteration"],
            date=facts["date"],
            runs=runs,
            validation=validation,
            notes=args.note,
        )
        write_cards(cards)
        check_cards()
    except UserError as err:
        print(f"seed_card: {err}", file=sys.stderr)
        return 2
    print(f"{args.model}: seed {facts['seed']}, commit {facts['code_commit']}, "
          f"best_pt iteration {facts['best_iteration']}, {len(runs)} run(s)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
