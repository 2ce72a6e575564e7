"""A model card's training command reproduces the card's first validation figures (issue 37).

The card of a small positional model records the command that trained it. Run again here (same
setup and seed, CPU, one thread), it must reach the card's best validation (15/15 on the study's
15 validation episodes), and the new file's stress-suite validation figures on the card's sets
must not differ from the card's at a family-wise 95 % over its three sets (Newcombe's interval
of the difference of two proportions at 1 − 0.05 / 3 per set, Bonferroni, 100 episodes per set
each, contains 0: three checks at 95 % each would fail a faithful reproduction about one time in
seven). The recorded figures come from an older
code revision (the card's ``code_commit``), whose random draws the trainer no longer follows
step for step, so equality is not asked: agreement within the interval is what "reproduces"
means here.
"""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import pytest

from usvsim.cli.main import main
from usvsim.evaluation.model_cards import load_cards, stress_summary
from usvsim.evaluation.stats import difference_interval

MODEL = "positional-gaussian-trpo-study"  # setup rl-gaussian-positional: ~10 s of training
SETS = ("study", "two-obstacles", "goal-anywhere")  # one easy set and two that discriminate
CONFIDENCE = 1.0 - 0.05 / len(SETS)  # per set: a family-wise 95 % (Bonferroni)


@pytest.mark.slow
def test_card_training_command_reproduces_its_validation_figures(tmp_path: Path) -> None:
    from usvsim.evaluation.stress import run_stress, select_sets, stress_json
    from usvsim.helm.registry import make_helmsman

    card = load_cards()[MODEL]
    argv = shlex.split(card.runs[0].command)
    assert argv[:2] == ["usvsim", "train"], argv
    argv = argv[1:]
    out = tmp_path / "run"
    argv[argv.index("--out") + 1] = str(out)
    assert main([*argv, "--quiet"]) == 0

    summary = json.loads((out / "summary.json").read_text())
    assert summary["best"]["successes"] == card.validation["best_pt"]["successes"] == 15

    recorded = card.validation["stress"]
    n = int(recorded["episodes_per_set"])
    result = run_stress(
        {MODEL: lambda: make_helmsman(str(out / "best.pt"))},
        select_sets(list(SETS)),
        n,
        False,
        split="validation",
    )
    again = stress_summary(json.loads(stress_json(result)), MODEL)["success_pct"]
    for name in SETS:
        then, now = round(recorded["success_pct"][name] * n / 100), round(again[name] * n / 100)
        lo, hi = difference_interval(then, n, now, n, CONFIDENCE)
        assert lo <= 0.0 <= hi, (name, recorded["success_pct"][name], again[name], (lo, hi))
