"""``usvsim train il-*``: a GAIL run writes the files of an RL run; resume, early stop, refusals."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import pytest

import learning.experiments.train_il as train_il
from learning.algorithms.loop import TIME_FIELDS
from learning.cli.train import TrainArgs, run
from learning.experiments.checkpoint import load_checkpoint
from learning.experiments.il_setups import IL_SETUPS
from learning.experiments.train_il import IL_CSV_FIELDS
from usvsim.evaluation.episodes import evaluate, selection_episodes, validation_episodes
from usvsim.evaluation.likeness import ExpertReference, expert_reference
from usvsim.helm.registry import make_helmsman

SETUP = "il-gaussian-positional"
STEPS = 4 * 16  # n_envs x steps_per_env of the tiny setup


SPECS = tuple(validation_episodes()[:5])  # validation on 5 of the 15 episodes: a third of the time
EXTRA = tuple(selection_episodes()[15:18])  # and 3 of the 45 extra selection episodes


@pytest.fixture(scope="module")
def reference() -> ExpertReference:
    """The expert side of the likeness metric on ``SPECS``, built once for the module."""
    return expert_reference(SPECS)


@pytest.fixture
def tiny(monkeypatch: pytest.MonkeyPatch, reference: ExpertReference) -> None:
    """The setup with the small budget of tests/test_gail.py, validated on ``SPECS``."""
    setup = IL_SETUPS[SETUP]
    small = setup.replace(
        gail=dataclasses.replace(setup.gail, bc_epochs=1),
        algorithm_config=dataclasses.replace(setup.algorithm_config, steps_per_env=16),
    )
    monkeypatch.setitem(IL_SETUPS, SETUP, small)
    monkeypatch.setattr(train_il, "validation_episodes", lambda: SPECS)
    monkeypatch.setattr(train_il, "selection_episodes", lambda: SPECS + EXTRA)
    monkeypatch.setattr(train_il, "expert_reference", lambda specs: reference)


def _args(out: Path, **kw: Any) -> TrainArgs:
    base: dict[str, Any] = dict(
        setup=SETUP, iterations=2, validate_every=2, n_envs=4, out=str(out), quiet=True, threads=1
    )
    base.update(kw)
    return TrainArgs(**base)


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def _summary(out: Path) -> dict[str, Any]:
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text())
    return summary


@pytest.mark.usefixtures("tiny")
def test_two_iterations_write_log_curve_summary_and_checkpoints(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    assert {p.name for p in tmp_path.iterdir()} >= {
        "latest.pt", "latest.gail.pt", "best.pt", "log.csv", "curve.png", "summary.json",
    }  # fmt: skip
    rows = _csv(tmp_path / "log.csv")
    assert tuple(rows[0]) == IL_CSV_FIELDS
    assert [(int(r["iteration"]), int(r["env_steps"])) for r in rows] == [
        (1, STEPS),
        (2, 2 * STEPS),
    ]
    assert all(rows[0][f] == "" for f in IL_CSV_FIELDS if f.startswith("val_"))
    assert 0 <= int(rows[1]["val_successes"]) <= len(SPECS)
    assert float(rows[1]["val_path_distance_m"]) > 0
    assert all(0 <= float(r[f]) <= 1 for r in rows for f in ("expert_accuracy", "policy_accuracy"))
    assert 0 < float(rows[0]["wall_time_s"]) <= float(rows[1]["wall_time_s"])
    # where each iteration's wall-clock went: every part > 0, together within the iteration
    assert IL_CSV_FIELDS[-5:] == TIME_FIELDS and "discriminator_s" in TIME_FIELDS
    walls = [0.0] + [float(r["wall_time_s"]) for r in rows]
    for r, start, end in zip(rows, walls, walls[1:], strict=False):
        parts = [float(r[f]) for f in TIME_FIELDS]
        assert min(parts) > 0 and sum(parts) <= end - start + 1e-3  # wall rounded to 1 ms
    summary = _summary(tmp_path)
    assert (summary["setup"], summary["iterations"], summary["env_steps"]) == (SETUP, 2, 2 * STEPS)
    assert summary["stop_reason"] == "iterations"
    assert summary["command"] == (
        f"usvsim train {SETUP} --iterations 2 --validate-every 2 --out {tmp_path} --n-envs 4 "
        "--threads 1 --quiet"
    )
    best = summary["best"]
    assert best["iteration"] == 2 and best["successes"] == int(rows[1]["val_successes"])
    assert best["n_episodes"] == len(SPECS)
    assert (summary["first_14_of_15"] is None) == (best["successes"] < len(SPECS) - 1)
    assert math.isclose(summary["study_success"], 0.866)
    assert (tmp_path / "curve.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.usefixtures("tiny")
def test_resume_continues_the_log_and_drops_rows_after_the_checkpoint(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    with (tmp_path / "log.csv").open("a") as handle:  # a row logged after latest.pt was saved
        handle.write("3," + ",".join(["999"] * (len(IL_CSV_FIELDS) - 1)) + "\n")
    assert run(_args(tmp_path, iterations=3, resume=True)) == 0
    rows = _csv(tmp_path / "log.csv")
    assert [int(r["iteration"]) for r in rows] == [1, 2, 3]
    assert int(rows[2]["env_steps"]) == 3 * STEPS and rows[2]["val_successes"] != ""
    assert float(rows[1]["wall_time_s"]) <= float(rows[2]["wall_time_s"]) < 999
    assert [h["iteration"] for h in load_checkpoint(tmp_path / "latest.pt").history] == [2, 3]
    summary = _summary(tmp_path)
    assert (summary["iterations"], summary["env_steps"]) == (3, 3 * STEPS)


@pytest.mark.usefixtures("tiny")
def test_early_stop_after_consecutive_full_validations(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    full = {
        "successes": 15, "n_episodes": 15, "mean_return": -10.0, "min_pole_distance_m": 20.0,
        "path_distance_m": 3.0,
    }  # fmt: skip
    monkeypatch.setattr(train_il, "validate_il", lambda *a: dict(full))
    assert run(_args(tmp_path, iterations=10, validate_every=1, stop_after=2)) == 0
    summary = _summary(tmp_path)
    assert summary["iterations"] == 2
    assert summary["stop_reason"] == "2 consecutive 15/15 validations"
    assert summary["first_14_of_15"]["iteration"] == summary["first_15_of_15"]["iteration"] == 1
    assert summary["first_15_of_15"]["env_steps"] == STEPS


def test_existing_run_is_not_overwritten_without_resume(tmp_path: Path) -> None:
    (tmp_path / "latest.pt").write_bytes(b"")
    with pytest.raises(SystemExit, match="exists: use --resume"):
        run(_args(tmp_path))


def test_resume_without_a_checkpoint_names_the_file(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match=r"cannot resume: .*latest\.pt"):
        run(_args(tmp_path, resume=True))


@pytest.mark.usefixtures("tiny")
def test_best_is_chosen_on_the_selection_set_before_the_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two 15/15 validations: the one with more selection successes wins over a closer path."""
    base = {"successes": 15, "n_episodes": 15, "mean_return": -10.0, "min_pole_distance_m": 20.0}
    vals = iter(
        [
            {**base, "path_distance_m": 2.0, "selection_successes": 55},
            {**base, "path_distance_m": 6.0, "selection_successes": 59},
            {**base, "path_distance_m": 1.0, "selection_successes": 59},
            {**base, "path_distance_m": 0.5, "selection_successes": 58},
        ]
    )
    seen: list[int] = []

    def fake(agent: Any, setup: Any, specs: Any, reference: Any, extra: Any) -> dict[str, Any]:
        seen.append(len(extra))
        return dict(next(vals))

    monkeypatch.setattr(train_il, "validate_il", fake)
    assert run(_args(tmp_path, iterations=4, validate_every=1, stop_after=0)) == 0
    assert seen == [len(EXTRA)] * 4
    best = load_checkpoint(tmp_path / "best.pt").validation
    assert (best["iteration"], best["path_distance_m"]) == (3, 1.0)
    rows = _csv(tmp_path / "log.csv")
    assert [r["val_selection_successes"] for r in rows] == ["55", "59", "59", "58"]


def test_validate_il_counts_selection_successes_over_both_sets(
    monkeypatch: pytest.MonkeyPatch, reference: ExpertReference
) -> None:
    """The 15-episode figures come from ``specs`` only, the selection count from both sets."""
    recs = evaluate(  # a classical helmsman's episodes stand in for a policy's
        make_helmsman("los-avoid"), [*SPECS, *EXTRA], observation="positional"
    )
    monkeypatch.setattr(train_il, "policy_records", lambda agent, setup, specs: recs)
    monkeypatch.setattr(train_il, "likeness", lambda r, ref: _Path(len(r)))
    setup = IL_SETUPS[SETUP]
    val = train_il.validate_il(None, setup, SPECS, reference, EXTRA)  # type: ignore[arg-type]
    assert val["n_episodes"] == len(SPECS) and val["path_distance_m"] == len(SPECS)
    assert val["successes"] == sum(r.success for r in recs[: len(SPECS)])
    assert val["selection_successes"] == sum(r.success for r in recs)
    plain = train_il.validate_il(None, setup, SPECS, reference)  # type: ignore[arg-type]
    assert "selection_successes" not in plain


@dataclasses.dataclass
class _Path:
    path_distance_m: float
