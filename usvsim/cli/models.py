"""The ``usvsim models`` command: the shipped models' cards as a table, or as JSON."""

from __future__ import annotations

from usvsim.evaluation.model_cards import ModelsArgs, models_report

__all__ = ["run_models_command"]


def run_models_command(args: ModelsArgs) -> int:
    """Print the cards (:func:`usvsim.evaluation.model_cards.models_report`); a card that is
    missing or disagrees with its file is a ``UserError`` (one line, exit 2)."""
    print(models_report(args))
    return 0
