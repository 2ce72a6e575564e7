"""The stress suite's validation and test splits: disjoint by construction, each set the same
perturbation in both, the split stated in the JSON and Markdown, ``--split`` on the command line,
and the test split refused inside selection mode."""

from __future__ import annotations

import json
import zlib
from pathlib import Path

import numpy as np
import pytest

from usvsim.cli.main import main
from usvsim.common.splits import TestSplitInSelectionError, selection_mode
from usvsim.evaluation.episodes import HELDOUT_SEED, SELECTION_SEED, VALIDATION_SEED
from usvsim.evaluation.family_likeness import FAMILY_HELD_OUT_SEED
from usvsim.evaluation.stress import (
    STRESS_SETS,
    run_stress,
    select_sets,
    stress_episodes,
    stress_json,
    stress_markdown,
    write_stress,
)
from usvsim.helm.registry import make_helmsman

N = 60  # episodes per set and split compared


def _noise_seeds(episodes) -> set[int]:
    """Every per-episode random seed of a set (noise, radar; a course's noise seed)."""
    seeds: set[int] = set()
    for e in episodes:
        if hasattr(e, "start"):  # an open-water episode
            seeds.add(int(e.start.noise_seed))
            seeds |= {int(e.radar_seed)} - {0}  # 0: the study's episodes carry no radar seed
        else:  # a waypoint course
            seeds.add(int(e.noise_seed))
    return seeds


def _same(a, b) -> bool:
    if hasattr(a, "waypoints_ne"):
        return bool(np.array_equal(a.waypoints_ne, b.waypoints_ne) and a.noise_seed == b.noise_seed)
    return bool(a == b)


@pytest.mark.parametrize("stress_set", STRESS_SETS, ids=lambda s: s.name)
def test_no_validation_episode_equals_a_test_episode(stress_set) -> None:
    validation = stress_episodes(stress_set, N, "validation")
    test = stress_episodes(stress_set, N, "test")
    assert len(validation) == len(test) == N
    assert not any(_same(v, t) for v in validation for t in test)
    assert not _noise_seeds(validation) & _noise_seeds(test)
    # and the validation episodes differ among themselves (a real draw, not one repeated)
    assert len(_noise_seeds(validation)) >= N


def test_validation_seeds_are_none_of_the_other_fixed_seeds() -> None:
    from learning.experiments.validation import (
        CROWDED_VALIDATION_SEED,
        FAMILY_VALIDATION_SEED,
        RADAR_VALIDATION_SEED,
    )

    validation = {s.split_seed("validation") for s in STRESS_SETS}
    test = {s.split_seed("test") for s in STRESS_SETS}
    others = {HELDOUT_SEED, SELECTION_SEED, VALIDATION_SEED, FAMILY_HELD_OUT_SEED}
    others |= {FAMILY_VALIDATION_SEED, RADAR_VALIDATION_SEED, CROWDED_VALIDATION_SEED}
    assert len(validation) == len(test) == len(STRESS_SETS)
    assert not validation & (test | others)
    assert all(s.seed == zlib.crc32(s.name.encode()) for s in STRESS_SETS)  # test: unchanged
    with pytest.raises(ValueError, match="unknown split 'train'"):
        STRESS_SETS[0].split_seed("train")  # type: ignore[arg-type]


def test_validation_split_draws_the_same_perturbation() -> None:
    (start_short,) = select_sets(["start-short"])
    distances = [e.start.start_distance_m for e in stress_episodes(start_short, N, "validation")]
    assert 30.0 <= min(distances) and max(distances) <= 50.0
    (vessels,) = select_sets(["moving-vessels"])
    counts = [len(e.vessels) for e in stress_episodes(vessels, N, "validation")]
    assert min(counts) >= 1 and max(counts) <= 3 and len(set(counts)) >= 2
    (study,) = select_sets(["study"])
    study_eps = stress_episodes(study, N, "validation")
    assert all(len(e.obstacles) == 1 and not e.vessels for e in study_eps)  # one pole, calm
    (waypoints,) = select_sets(["waypoints"])
    assert all(len(c.poles_ne) >= 1 for c in stress_episodes(waypoints, 5, "validation"))


def test_result_states_its_split_in_json_markdown_and_file_names(tmp_path: Path) -> None:
    sets = select_sets(["study", "two-obstacles"])
    factories = {"los-avoid": lambda: make_helmsman("los-avoid")}
    result = run_stress(factories, sets, 3, progress=False, split="validation")
    payload = json.loads(stress_json(result))
    assert payload["split"] == "validation" and len(payload["rows"]) == 2
    assert "stress suite, validation split" in stress_markdown(result)
    files = write_stress(result, tmp_path, plots=False)
    assert sorted(f.name for f in files) == ["stress-validation.csv", "stress-validation.md"]
    again = run_stress(factories, sets[:1], 3, progress=False)
    assert json.loads(stress_json(again))["split"] == "test"
    assert "stress suite, test split" in stress_markdown(again)


def test_bench_split_option(tmp_path: Path, capsys) -> None:
    argv = ["bench", "--suite", "stress", "--sets", "two-obstacles", "--helmsmen", "los-avoid"]
    argv += ["--stress-episodes", "2", "--no-plots", "--json", "--out", str(tmp_path)]
    assert main([*argv, "--split", "validation"]) == 0
    assert json.loads(capsys.readouterr().out)["split"] == "validation"
    assert main(argv) == 0  # default: the test split, the reported figures
    assert json.loads(capsys.readouterr().out)["split"] == "test"
    with pytest.raises(SystemExit) as bad:  # argparse: a choice outside the Literal
        main([*argv, "--split", "train"])
    assert bad.value.code == 2
    assert "--split" in capsys.readouterr().err
    assert main(["bench", "--split", "validation", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--split needs --suite stress" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("name", ["study", "waypoints", "everything"])
def test_test_split_is_refused_in_selection_mode(name: str) -> None:
    (stress_set,) = select_sets([name])
    with selection_mode("a ship decision"):
        assert len(stress_episodes(stress_set, 4, "validation")) == 4  # allowed
        with pytest.raises(TestSplitInSelectionError, match=f"stress {name}"):
            stress_episodes(stress_set, 4, "test")
    assert len(stress_episodes(stress_set, 4, "test")) == 4  # reporting: allowed


WEATHER_SETS_NAMED = ("wind-beam", "gusts", "sea-state-3", "sea-state-4")


@pytest.mark.parametrize("name", WEATHER_SETS_NAMED)
def test_weather_sets_draw_weather_in_both_splits_and_different_weather(name: str) -> None:
    (stress_set,) = select_sets([name])
    validation = stress_episodes(stress_set, 20, "validation")
    test = stress_episodes(stress_set, 20, "test")
    for episodes in (validation, test):
        assert all(e.disturbance.weather.wind_speed_mps > 0 for e in episodes)
    assert not {e.disturbance.weather for e in validation} & {e.disturbance.weather for e in test}
    with selection_mode("a validation"), pytest.raises(TestSplitInSelectionError):
        stress_episodes(stress_set, 1, "test")


def test_only_the_weather_sets_and_everything_draw_weather() -> None:
    for stress_set in STRESS_SETS:
        if stress_set.scenario is not None:
            windy = stress_set.scenario.weather is not None
            assert windy == (stress_set.name in (*WEATHER_SETS_NAMED, "everything")), (
                stress_set.name
            )
