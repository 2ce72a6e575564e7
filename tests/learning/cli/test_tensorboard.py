"""``usvsim train --tensorboard DIR`` and ``usvsim sweep --tensorboard DIR``: every ``log.csv``
row as TensorBoard scalars, read back with TensorBoard's own reader."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator  # dev extra
from test_train_cli import _csv

# the tiny GAIL setup of the IL command's tests (a fixture), validated on 5 episodes
from test_train_il_cli import reference, tiny  # noqa: F401

from learning.cli.train import TrainArgs, run
from learning.experiments.run_log import scalar_tag
from learning.experiments.setups import get_setup
from learning.experiments.sweep import train_trial
from learning.experiments.train_il import IL_CSV_FIELDS
from learning.experiments.train_rl import csv_fields
from usvsim.cli import main

SETUP = "rl-categorical-positional"
STEPS_PER_ITERATION = 4 * 64  # n_envs x decisions per boat


def _args(out: Path, board: Path, **kw: object) -> TrainArgs:
    base: dict[str, object] = dict(
        setup=SETUP,
        iterations=2,
        validate_every=1,
        n_envs=4,
        out=str(out),
        quiet=True,
        threads=1,
        tensorboard=str(board),
    )
    base.update(kw)
    return TrainArgs(**base)  # type: ignore[arg-type]


def _scalars(folder: Path) -> EventAccumulator:
    acc = EventAccumulator(str(folder), size_guidance={"scalars": 0})  # 0: keep every event
    acc.Reload()
    return acc


def test_train_writes_every_csv_column_as_scalars(tmp_path: Path) -> None:
    out, board = tmp_path / "run", tmp_path / "tb"
    assert run(_args(out, board)) == 0
    events = list((board / "run").glob("events.out.tfevents.*"))
    assert len(events) == 1  # DIR/<output folder's name>, one event file
    acc = _scalars(board / "run")
    columns = [c for c in csv_fields(get_setup(SETUP)) if c != "env_steps"]  # env_steps: the step
    assert sorted(acc.Tags()["scalars"]) == sorted(scalar_tag(c) for c in columns)
    assert {"train/mean_return", "validation/val_successes", "time/rollout_s"} <= set(
        acc.Tags()["scalars"]
    )
    rows = _csv(out / "log.csv")
    steps = [int(r["env_steps"]) for r in rows]
    assert steps == [STEPS_PER_ITERATION, 2 * STEPS_PER_ITERATION]
    for column in columns:  # every column at every iteration (validation every iteration here)
        scalars = acc.Scalars(scalar_tag(column))
        assert [s.step for s in scalars] == steps
        expected = [float(r[column]) for r in rows]
        assert [s.value for s in scalars] == pytest.approx(expected, rel=1e-6, abs=1e-6)


@pytest.mark.usefixtures("tiny")
def test_il_train_writes_its_columns_as_scalars(tmp_path: Path) -> None:
    out, board = tmp_path / "run", tmp_path / "tb"
    assert run(_args(out, board, setup="il-gaussian-positional", validate_every=2)) == 0
    acc = _scalars(board / "run")
    columns = [c for c in IL_CSV_FIELDS if c != "env_steps"]
    assert sorted(acc.Tags()["scalars"]) == sorted(scalar_tag(c) for c in columns)
    steps = [int(r["env_steps"]) for r in _csv(out / "log.csv")]
    assert len(steps) == 2
    assert [s.step for s in acc.Scalars("train/env_return")] == steps
    assert [s.step for s in acc.Scalars("train/disc_loss")] == steps
    assert [s.step for s in acc.Scalars("validation/val_path_distance_m")] == steps[1:]


def test_resume_continues_the_scalars_without_repeating_steps(tmp_path: Path) -> None:
    """The first session logs iterations 1-3 but keeps its checkpoint of 2; the resumed one
    redoes 3 and adds 4: one event per step, those of the resumed session."""
    out, board = tmp_path / "run", tmp_path / "tb"
    assert run(_args(out, board, iterations=3, validate_every=2)) == 0
    assert run(_args(out, board, iterations=4, validate_every=2, resume=True)) == 0
    acc = _scalars(board / "run")
    returns = acc.Scalars("train/mean_return")
    assert [s.step for s in returns] == [k * STEPS_PER_ITERATION for k in (1, 2, 3, 4)]
    rows = _csv(out / "log.csv")
    assert [s.value for s in returns] == pytest.approx([float(r["mean_return"]) for r in rows])
    validations = acc.Scalars("validation/val_successes")  # on validation iterations only
    assert [s.step for s in validations] == [2 * STEPS_PER_ITERATION, 4 * STEPS_PER_ITERATION]


def test_sweep_trial_writes_its_scalars_into_its_own_folder(tmp_path: Path) -> None:
    options = {"iterations": 1, "validate_every": 1, "stop_after": 3, "n_envs": 4}
    config = {
        "setup": SETUP,
        "seed": 0,
        "threads": 1,
        "overrides": {},
        "options": {**options, "time_budget_s": 0.0},
        "tensorboard": str(tmp_path / "tb" / "trial-a"),
    }
    train_trial(config, tmp_path / "runs" / "trial-a")
    acc = _scalars(tmp_path / "tb" / "trial-a")
    assert [s.step for s in acc.Scalars("train/mean_return")] == [STEPS_PER_ITERATION]
    assert [s.step for s in acc.Scalars("validation/val_successes")] == [STEPS_PER_ITERATION]


def test_missing_tensorboard_is_one_line_before_any_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "torch.utils.tensorboard", None)  # import fails
    argv = ["train", SETUP, "--out", str(tmp_path / "run"), "--tensorboard", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "usvsim train: --tensorboard needs the tensorboard package: "
        'pip install "usvsim[tensorboard]"'
    )
    assert not (tmp_path / "run").exists()
