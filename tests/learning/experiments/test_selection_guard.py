"""Selection never reads a test episode (issue 37): the training run's validations, ``best.pt``
and early stop, the open-water validation sets, the IL run's selection set, and the sweep's
search objective and shipped-seed rule.

Each path runs inside :func:`usvsim.common.splits.selection_mode`; the test splits' drawers
refuse there. The tests run the real paths (they pass, so they draw no test episode) and the same
paths with one episode source swapped for a test split (they must fail: the guard is live on
that path).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import pytest
import torch

import learning.experiments.train_il as train_il_module
import learning.experiments.validation as validation_module
from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import load_checkpoint
from learning.experiments.setups import get_setup
from learning.experiments.sweep import OBJECTIVE
from learning.experiments.sweep_report import TrialRecord, best_by_validation, choose_shipped
from learning.experiments.train_rl import train_rl
from learning.experiments.validation import (
    crowded_validation_episodes,
    family_validation_episodes,
    radar_validation_episodes,
)
from usvsim.common.splits import TestSplitInSelectionError, current_selection, selection_mode
from usvsim.evaluation.episodes import heldout_episodes
from usvsim.evaluation.family_likeness import family_held_out_episodes
from usvsim.evaluation.stress import STRESS_SETS, stress_episodes
from usvsim.task.batch import action_space
from usvsim.task.observations import observation_space


def _tiny_rl_setup():  # type: ignore[no-untyped-def]
    base = get_setup("rl-gaussian-positional")
    config = dataclasses.replace(base.algorithm_config, num_envs=4, steps_per_env=16)
    return dataclasses.replace(base, validate_every=1, algorithm_config=config)


@pytest.fixture
def one_thread():  # type: ignore[no-untyped-def]
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def test_a_training_run_selects_on_validation_episodes_only(tmp_path: Path, one_thread) -> None:
    result = train_rl(_tiny_rl_setup(), tmp_path, iterations=1)
    assert [h["iteration"] for h in result.history] == [1]  # validated, best.pt kept
    assert load_checkpoint(tmp_path / "best.pt").validation is not None
    assert current_selection() == ""  # the mode ends with the run


def test_a_training_run_that_validates_on_held_out_episodes_fails(
    tmp_path: Path, monkeypatch, one_thread
) -> None:
    monkeypatch.setattr(validation_module, "validation_episodes", lambda: heldout_episodes(n=15))
    with pytest.raises(TestSplitInSelectionError, match="drew the test split 'study held-out'"):
        train_rl(_tiny_rl_setup(), tmp_path, iterations=1)
    assert not (tmp_path / "best.pt").exists()  # nothing chosen on the test split


def test_open_water_validation_on_a_held_out_family_fails(monkeypatch) -> None:
    setup = get_setup("rl-gaussian-scene-ow")
    agent = get_algorithm(setup.algorithm).make_agent(
        observation_space(setup.observation), action_space(setup.action), setup.run_config(0)
    )
    monkeypatch.setattr(
        validation_module, "family_validation_episodes", lambda: family_held_out_episodes(3)
    )
    monkeypatch.setattr(validation_module, "validation_episodes", lambda: heldout_episodes(n=0))
    with pytest.raises(TestSplitInSelectionError, match="'study held-out'"):
        validation_module.validate(agent, setup)
    monkeypatch.setattr(validation_module, "validation_episodes", lambda: ())
    with pytest.raises(TestSplitInSelectionError, match="'family held-out'"):
        validation_module.open_water_summary(agent, setup)


def test_il_selection_set_from_held_out_episodes_fails(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(train_il_module, "selection_episodes", lambda: heldout_episodes(n=60))
    monkeypatch.setattr(train_il_module, "expert_pairs", lambda *a: (None, 0, 0))
    from learning.experiments.il_setups import get_il_setup

    with pytest.raises(TestSplitInSelectionError, match="'study held-out'"):
        train_il_module.train_il(get_il_setup("il-gaussian-positional"), tmp_path, iterations=1)


def _key(episode) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    return int(episode.start.noise_seed), int(episode.radar_seed)


def test_family_validation_sets_share_no_episode_with_a_test_split() -> None:
    chosen_on = {
        _key(e)
        for e in (
            *family_validation_episodes(),
            *radar_validation_episodes(),
            *crowded_validation_episodes(),
        )
    }
    reported = {_key(e) for e in family_held_out_episodes(100)}
    for s in STRESS_SETS:
        if s.kind == "open-water":
            reported |= {_key(e) for e in stress_episodes(s, 100)}
    assert len(chosen_on) == 200 and not chosen_on & reported


def _trial(seed: int, best: int, auc: float, heldout: float) -> TrialRecord:
    metrics = {"val_best_successes": best, OBJECTIVE: auc, "iterations": 10}
    return TrialRecord("s", seed, {}, Path(f"t{seed}"), "finished", "", metrics, heldout, [])


def test_sweep_choices_do_not_move_with_the_held_out_figures() -> None:
    # validation ties on purpose: a held-out tie-break would show as a different choice
    validation = [(15, 0.8), (15, 0.8), (14, 0.9), (15, 0.5), (13, 0.95)]
    shipped, best = set(), set()
    for heldout in itertools.permutations([0.2, 0.4, 0.6, 0.8, 1.0]):
        trials = [
            _trial(i, b, a, h)
            for i, ((b, a), h) in enumerate(zip(validation, heldout, strict=True))
        ]
        choice = choose_shipped(trials, "median-validation")
        assert choice is not None
        shipped.add(choice.seed)
        answer = best_by_validation(trials)
        assert answer is not None
        best.add(answer["dir"])
    nan_trials = [_trial(i, b, a, math.nan) for i, (b, a) in enumerate(validation)]
    nan_choice = choose_shipped(nan_trials, "median-validation")
    assert nan_choice is not None and shipped == {nan_choice.seed}
    assert best == {"t4"}  # the highest validation AUC


def test_selection_mode_nests_and_ends() -> None:
    with selection_mode("outer"):
        with selection_mode("inner"):
            assert current_selection() == "inner"
        assert current_selection() == "outer"
        with pytest.raises(TestSplitInSelectionError, match="outer drew"):
            heldout_episodes(n=1)
    assert current_selection() == "" and len(heldout_episodes(n=1)) == 1
