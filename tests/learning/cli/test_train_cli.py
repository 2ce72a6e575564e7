"""``usvsim train`` / ``usvsim evaluate``: files written, resume, early stop, bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import torch

import learning.algorithms.actor_critic
import learning.algorithms.trpo
from learning.cli.evaluate import EvaluateArgs
from learning.cli.evaluate import run as run_evaluate
from learning.cli.train import TrainArgs, run
from learning.experiments.checkpoint import load_checkpoint
from learning.experiments.setups import get_setup
from learning.experiments.train_rl import TIME_FIELDS, csv_fields

SETUP = "rl-categorical-positional"


def _args(out: Path, **kw: object) -> TrainArgs:
    base: dict[str, object] = dict(
        setup=SETUP, iterations=2, validate_every=1, n_envs=4, out=str(out), quiet=True, threads=1
    )
    base.update(kw)
    return TrainArgs(**base)  # type: ignore[arg-type]


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_two_iterations_write_checkpoints_log_curve_and_summary(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    assert {p.name for p in tmp_path.iterdir()} >= {
        "latest.pt", "best.pt", "log.csv", "curve.png", "summary.json",
    }  # fmt: skip
    rows = _csv(tmp_path / "log.csv")
    assert tuple(rows[0]) == csv_fields(get_setup(SETUP))
    assert [int(r["iteration"]) for r in rows] == [1, 2]
    assert all(r["val_successes"] != "" for r in rows)
    ckpt = load_checkpoint(tmp_path / "latest.pt", expected_setup=SETUP)
    assert ckpt.agent["iteration"] == 2 and ckpt.agent["env_steps"] == 2 * 4 * 64
    assert [h["iteration"] for h in ckpt.history] == [1, 2]
    assert ckpt.train_args["seed"] == 0 and not ckpt.slim
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["iterations"] == 2 and summary["stop_reason"] == "iterations"
    best = max(rows, key=lambda r: (int(r["val_successes"]), float(r["val_mean_return"])))
    assert type(summary["best"]["successes"]) is int  # the count, not the "passed all 15" flag
    assert summary["best"]["successes"] == int(best["val_successes"])
    assert summary["best"]["mean_return"] == pytest.approx(float(best["val_mean_return"]))
    assert (tmp_path / "curve.png").read_bytes()[:4] == b"\x89PNG"


def test_time_split_is_positive_and_within_each_iteration(tmp_path: Path) -> None:
    assert run(_args(tmp_path, iterations=3)) == 0
    rows = _csv(tmp_path / "log.csv")
    assert TIME_FIELDS == ("rollout_s", "batch_s", "policy_step_s", "critic_s")
    walls = [0.0] + [float(r["wall_time_s"]) for r in rows]
    for r, start, end in zip(rows, walls, walls[1:], strict=False):
        parts = [float(r[f]) for f in TIME_FIELDS]
        assert min(parts) > 0
        # wall_time_s is rounded to 1 ms, the parts to 0.1 ms
        assert sum(parts) <= end - start + 1e-3
    # the first row's wall-clock is its rollout and update alone: the split covers it
    assert sum(float(rows[0][f]) for f in TIME_FIELDS) >= 0.9 * walls[1]


def test_resume_continues_the_run(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    assert run(_args(tmp_path, iterations=3, resume=True)) == 0
    rows = _csv(tmp_path / "log.csv")
    assert [int(r["iteration"]) for r in rows] == [1, 2, 3]
    ckpt = load_checkpoint(tmp_path / "latest.pt")
    assert ckpt.agent["iteration"] == 3 and ckpt.agent["env_steps"] == 3 * 4 * 64
    assert [h["iteration"] for h in ckpt.history] == [1, 2, 3]


def test_time_budget_counts_the_whole_run_across_a_resume(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    spent = float(_csv(tmp_path / "log.csv")[-1]["wall_time_s"])
    # the budget is already spent by the first part: the resumed part stops after one iteration
    assert run(_args(tmp_path, iterations=6, resume=True, time_budget_s=spent)) == 0
    rows = _csv(tmp_path / "log.csv")
    assert [int(r["iteration"]) for r in rows] == [1, 2, 3]
    assert float(rows[-1]["wall_time_s"]) > spent
    assert json.loads((tmp_path / "summary.json").read_text())["stop_reason"] == "time budget"


def test_existing_run_is_not_overwritten_without_resume(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    with pytest.raises(SystemExit, match="exists: use --resume"):
        run(_args(tmp_path))


def test_resume_with_another_setup_names_the_mismatch(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    with pytest.raises(SystemExit, match=r"cannot resume.*expected 'rl-categorical-radar'"):
        run(_args(tmp_path, setup="rl-categorical-radar", resume=True))


def test_resume_from_a_corrupt_checkpoint(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    (tmp_path / "latest.pt").write_bytes(b"\x00" * 100)
    with pytest.raises(SystemExit, match="corrupt or truncated"):
        run(_args(tmp_path, iterations=3, resume=True))


def test_unknown_setup(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match=r"unknown setup 'rl-banana'.*rl-gaussian-positional"):
        run(_args(tmp_path, setup="rl-banana"))
    assert not tmp_path.joinpath("latest.pt").exists()


def test_nan_in_the_loss_stops_with_an_error_and_keeps_the_checkpoint(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run(_args(tmp_path)) == 0
    before = {name: (tmp_path / name).read_bytes() for name in ("latest.pt", "best.pt")}
    real_gae = learning.algorithms.actor_critic.gae

    def nan_gae(*a: object, **kw: object) -> tuple[np.ndarray, np.ndarray]:
        adv, ret = real_gae(*a, **kw)  # type: ignore[arg-type]
        return adv * np.nan, ret

    monkeypatch.setattr(learning.algorithms.actor_critic, "gae", nan_gae)
    assert run(_args(tmp_path, iterations=4, resume=True)) == 1
    assert "non-finite" in capsys.readouterr().err
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data
    assert load_checkpoint(tmp_path / "latest.pt").agent["iteration"] == 2


def test_early_stop_after_consecutive_full_validations(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import learning.experiments.train_rl as train_rl

    full = {"successes": 15, "n_episodes": 15, "mean_return": -10.0, "min_pole_distance_m": 20.0}
    monkeypatch.setattr(train_rl, "validate", lambda agent, setup: dict(full))
    assert run(_args(tmp_path, iterations=10, stop_after=2)) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["iterations"] == 2
    assert summary["stop_reason"] == "2 consecutive 15/15 validations"
    assert summary["first_15_of_15"]["iteration"] == 1


def test_setups_train_on_the_fixed_reward_horizon_with_their_gamma() -> None:
    # the horizon itself: tests/usvsim/task/test_reward_horizon.py
    setup = get_setup(SETUP)
    options = setup.make_vector_env(2).layer.options
    assert (options.reward_horizon, options.gamma) == ("fixed", setup.algorithm_config.gamma)


def test_evaluate_prints_the_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert run(_args(tmp_path, iterations=1)) == 0
    out_json = tmp_path / "eval.json"
    args = EvaluateArgs(str(tmp_path / "latest.pt"), heldout=4, json_out=str(out_json))
    assert run_evaluate(args) == 0
    text = capsys.readouterr().out
    assert "validation" in text and "held-out" in text
    rows = json.loads(out_json.read_text())["rows"]
    assert [(r["set"], r["episodes"]) for r in rows] == [("validation", 15), ("held-out", 4)]


def test_evaluate_bad_checkpoint(tmp_path: Path) -> None:
    (tmp_path / "x.pt").write_text("garbage")
    with pytest.raises(SystemExit, match="not a readable checkpoint"):
        run_evaluate(EvaluateArgs(str(tmp_path / "x.pt")))


def test_nan_weights_after_an_update_are_never_saved(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run(_args(tmp_path)) == 0
    before = {name: (tmp_path / name).read_bytes() for name in ("latest.pt", "best.pt")}
    real_step = learning.algorithms.trpo.trpo_step

    def poisoned_step(policy, *a, **kw):
        stats = real_step(policy, *a, **kw)
        with torch.no_grad():
            policy.head.bias.fill_(float("nan"))
        return stats

    monkeypatch.setattr(learning.algorithms.trpo, "trpo_step", poisoned_step)
    assert run(_args(tmp_path, iterations=4, resume=True)) == 1
    assert "non-finite weights" in capsys.readouterr().err
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data


def test_a_run_can_start_from_another_runs_policy(tmp_path: Path) -> None:
    # an IL model (GAIL's TRPO policy) starts an RL run: the first validation is that policy's
    source = Path("usvsim/models/positional-categorical-gail-study.pt")
    assert run(_args(tmp_path, iterations=1, init_policy=str(source))) == 0
    ckpt = load_checkpoint(tmp_path / "latest.pt")
    assert ckpt.train_args["init_policy"] == str(source)
    il = load_checkpoint(source)
    assert il.validation is not None and il.validation["successes"] == 15
    rows = _csv(tmp_path / "log.csv")
    # one small TRPO step (max KL 0.01) from a 15/15 policy keeps it at 14-15/15; new
    # networks score 0/15 after one iteration
    assert int(rows[0]["val_successes"]) >= 14


def test_a_start_policy_of_other_kinds_or_with_resume_is_refused(tmp_path: Path) -> None:
    radar = "usvsim/models/radar-categorical-gail-study.pt"
    with pytest.raises(SystemExit, match=r"cannot start from that policy.*radar\+goal/categorical"):
        run(_args(tmp_path / "a", init_policy=radar))
    assert not (tmp_path / "a" / "latest.pt").exists()
    with pytest.raises(SystemExit, match="not both"):
        run(_args(tmp_path / "b", init_policy=radar, resume=True))
    with pytest.raises(SystemExit, match="for the rl-\\* setups"):
        run(_args(tmp_path / "c", setup="il-gaussian-positional", init_policy=radar))


def test_crowded_share_is_for_new_open_water_runs(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="for the rl-\\*-ow setups"):
        run(_args(tmp_path / "a", crowded_share=0.5))
    with pytest.raises(SystemExit, match="--resume keeps the run's own"):
        run(_args(tmp_path / "b", setup="rl-gaussian-scene-ow", crowded_share=0.5, resume=True))
    with pytest.raises(SystemExit, match="must be > 0 and < 1"):
        run(_args(tmp_path / "c", setup="rl-gaussian-scene-ow", crowded_share=1.0))
    assert not any(tmp_path.rglob("*.pt"))


def test_harsh_radar_share_is_for_new_radar_rl_runs_on_the_family(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="for the rl-\\*-radar-ow setups"):
        run(_args(tmp_path / "a", setup="rl-gaussian-scene-ow", harsh_radar_share=0.5))
    with pytest.raises(SystemExit, match="--harsh-radar-copies"):
        run(_args(tmp_path / "b", setup="il-gaussian-radar-ow", harsh_radar_share=0.5))
    with pytest.raises(SystemExit, match="--resume keeps the run's own"):
        run(_args(tmp_path / "c", setup="rl-gaussian-radar-ow", harsh_radar_share=0.5, resume=True))
    with pytest.raises(SystemExit, match="must be > 0 and < 1"):
        run(_args(tmp_path / "d", setup="rl-gaussian-radar-ow", harsh_radar_share=1.0))
    assert not any(tmp_path.rglob("*.pt"))


def test_a_setup_that_starts_from_a_trained_file_refuses_to_start_without_one(
    tmp_path: Path,
) -> None:
    with pytest.raises(SystemExit, match="give --init-policy FILE"):
        run(_args(tmp_path / "a", setup="rl-gaussian-radar-colreg-ilft"))
    assert not any(tmp_path.rglob("*.pt"))
