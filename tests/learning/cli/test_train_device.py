"""``usvsim train --device``: torch-cpu trains a positional setup with the device loop and
writes a cpu run's files; other setups and a missing GPU are one line, exit 2."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
import torch

from learning.cli.train import TrainArgs, command_of, run
from learning.experiments.checkpoint import load_checkpoint


def _args(out: Path, **kw: object) -> TrainArgs:
    base: dict[str, object] = dict(
        setup="rl-categorical-positional",
        iterations=2,
        validate_every=1,
        n_envs=8,
        out=str(out),
        quiet=True,
        threads=1,
        device="torch-cpu",
    )
    base.update(kw)
    return TrainArgs(**base)  # type: ignore[arg-type]


def test_torch_cpu_run_writes_the_files_of_a_cpu_run(tmp_path: Path) -> None:
    assert run(_args(tmp_path)) == 0
    with (tmp_path / "log.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["iteration"]) for r in rows] == [1, 2]
    assert [int(r["env_steps"]) for r in rows] == [8 * 64, 2 * 8 * 64]
    assert all(r["val_successes"] != "" for r in rows)  # CPU validation on the 15 episodes
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["iterations"] == 2 and "--device torch-cpu" in summary["command"]
    ckpt = load_checkpoint(tmp_path / "best.pt")
    weights = ckpt.agent["policy"]
    assert all(t.device == torch.device("cpu") for t in weights.values())
    # resumable: one more iteration from latest.pt
    assert run(_args(tmp_path, iterations=3, resume=True)) == 0
    assert load_checkpoint(tmp_path / "latest.pt").agent["iteration"] == 3


def test_torch_cpu_trains_an_open_water_scene_setup(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """rl-gaussian-scene-ow on the torch open-water env (its training family drawn at reset,
    a small table here): the files of a cpu run, the family validated on the CPU env."""
    import learning.experiments.train_rl as train_rl

    monkeypatch.setattr(train_rl, "OPEN_WATER_TABLE_EPISODES", 64)
    args = _args(tmp_path, setup="rl-gaussian-scene-ow", iterations=1, n_envs=4)
    assert run(args) == 0
    with (tmp_path / "log.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["env_steps"]) for r in rows] == [4 * 64]
    assert rows[0]["val_family_successes"] != ""
    assert load_checkpoint(tmp_path / "best.pt").setup == "rl-gaussian-scene-ow"


def test_torch_cpu_trains_an_open_water_radar_setup(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """rl-gaussian-radar-ow (radar image and goal, harsh radar share) on the torch open-water
    env: one iteration, the goal's running statistics merged, a cpu run's files."""
    import learning.experiments.train_rl as train_rl

    monkeypatch.setattr(train_rl, "OPEN_WATER_TABLE_EPISODES", 32)
    args = _args(tmp_path, setup="rl-gaussian-radar-ow", iterations=1, n_envs=4)
    assert run(args) == 0
    ckpt = load_checkpoint(tmp_path / "best.pt")
    assert ckpt.setup == "rl-gaussian-radar-ow" and ckpt.agent["env_steps"] == 4 * 64
    assert ckpt.agent["normalizer"]["goal"]["count"] >= 4 * 64  # the batch merged


def test_torch_cpu_trains_a_colreg_setup_with_the_colreg_reward(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """rl-gaussian-radar-colreg (issue 41) on the torch open-water env: its env adds the
    setup's COLREG terms to the reward; one iteration runs and writes a cpu run's files."""
    import learning.experiments.train_rl as train_rl
    from learning.experiments.setups import get_setup

    monkeypatch.setattr(train_rl, "OPEN_WATER_TABLE_EPISODES", 32)
    env = train_rl.device_env_maker(get_setup("rl-gaussian-radar-colreg"), "torch-cpu")(4)
    env.reset(seed=0)
    _, reward, _, _, info = env.step(torch.zeros((4, 1), dtype=torch.float64))
    plain = info["reward_pole"] + info["reward_goal"] + info["reward_colreg"]
    torch.testing.assert_close(reward, plain)  # no boat ended: the horizon left it alone
    args = _args(tmp_path, setup="rl-gaussian-radar-colreg", iterations=1, n_envs=4)
    assert run(args) == 0
    assert load_checkpoint(tmp_path / "best.pt").setup == "rl-gaussian-radar-colreg"


def test_torch_cpu_trains_the_reactive_colreg_setup(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """rl-gaussian-radar-colreg-reactive: the targets steered by vo on the host each decision
    (usvsim.evaluation.torch_reactive); one iteration runs and writes a cpu run's files."""
    import learning.experiments.train_rl as train_rl
    from learning.experiments.setups import get_setup
    from usvsim.evaluation.torch_reactive import DeviceReactiveTargets

    monkeypatch.setattr(train_rl, "OPEN_WATER_TABLE_EPISODES", 32)
    env = train_rl.device_env_maker(get_setup("rl-gaussian-radar-colreg-reactive"), "torch-cpu")(4)
    assert isinstance(env.on_decision, DeviceReactiveTargets)
    args = _args(tmp_path, setup="rl-gaussian-radar-colreg-reactive", iterations=1, n_envs=4)
    assert run(args) == 0
    assert load_checkpoint(tmp_path / "best.pt").setup == "rl-gaussian-radar-colreg-reactive"


def test_torch_cpu_trains_gail(tmp_path: Path) -> None:
    """il-categorical-positional by GAIL on the torch study env: two iterations, the
    discriminator's state saved beside latest.pt, a cpu run's validation columns."""
    args = _args(tmp_path, setup="il-categorical-positional", iterations=2, n_envs=8)
    assert run(args) == 0
    with (tmp_path / "log.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["env_steps"]) for r in rows] == [8 * 64, 2 * 8 * 64]
    assert all(r["val_successes"] != "" and r["disc_loss"] != "" for r in rows)
    assert (tmp_path / "latest.gail.pt").is_file()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert "--device torch-cpu" in summary["command"]


@pytest.mark.parametrize(
    ("setup", "device", "message"),
    [
        ("rl-gaussian-radar", "torch-cpu", "is for the TRPO positional"),
        ("rl-categorical-positional-ppo", "torch-cpu", "is for the TRPO positional"),
        ("il-gaussian-radar", "torch-cpu", "trains GAIL for the IL positional"),
        ("rl-gaussian-positional", "gpu", "--device must be one of cpu, torch-cpu, cuda"),
    ],
)
def test_a_device_it_cannot_use_is_one_line(
    tmp_path: Path, setup: str, device: str, message: str
) -> None:
    with pytest.raises(SystemExit, match=message):
        run(_args(tmp_path, setup=setup, device=device))
    assert not (tmp_path / "log.csv").exists()


@pytest.mark.skipif(torch.cuda.is_available(), reason="a GPU is here")
def test_cuda_without_a_gpu_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="torch sees no CUDA GPU"):
        run(_args(tmp_path, device="cuda"))


def test_the_default_device_is_cpu_and_not_in_the_command(tmp_path: Path) -> None:
    args = _args(tmp_path, device="cpu")
    assert "--device" not in command_of(args)
