"""benchmarks/goal_mark_use.py: how much a goal-mark policy's heading command reads its mark."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
import torch

from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import Checkpoint, save_checkpoint, starting_policy
from learning.experiments.setups import get_setup

_BENCH = Path(__file__).resolve().parents[3] / "benchmarks"
_SPEC = importlib.util.spec_from_file_location("goal_mark_use", _BENCH / "goal_mark_use.py")
assert _SPEC is not None and _SPEC.loader is not None
use = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(use)

MARKED = "rl-gaussian-radar-colreg-ilft-safe-ow-aim2-mark"


def _marked(one_image: Path, tmp_path: Path, mark_std: float) -> Path:
    """The one-image policy widened for the mark; its mark weights drawn N(0, mark_std)."""
    setup = get_setup(MARKED)
    env = setup.make_vector_env(2)
    agent = get_algorithm(setup.algorithm).make_agent(
        env.single_observation_space, env.single_action_space, setup.run_config(0)
    )
    agent.load_policy(starting_policy(one_image, setup))
    if mark_std:
        with torch.no_grad():
            agent.policy.trunk.conv.weight[:, 1].normal_(0.0, mark_std)
    path = tmp_path / f"marked-{mark_std}.pt"
    save_checkpoint(Checkpoint.from_agent(agent, setup), path)
    return path


def test_a_widened_untrained_policy_does_not_read_the_mark(
    one_image_checkpoint: Path, tmp_path: Path
) -> None:
    observations = use.decision_observations(8, 3, 1, seed=0)
    row = use.mark_use(_marked(one_image_checkpoint, tmp_path, 0.0), observations)
    assert row["decisions"] == 24
    assert row["mean_deg"] == 0.0 and row["max_deg"] == 0.0
    assert row["conv_weight_norm_per_channel"][1] == 0.0
    assert row["conv_weight_norm_per_channel"][0] > 1.0


def test_weights_on_the_mark_move_the_heading_command(
    one_image_checkpoint: Path, tmp_path: Path
) -> None:
    observations = use.decision_observations(8, 3, 1, seed=0)
    row = use.mark_use(_marked(one_image_checkpoint, tmp_path, 0.5), observations)
    assert row["mean_deg"] > 0.1 and row["p90_deg"] <= row["max_deg"] <= 60.0


def test_a_policy_without_a_mark_is_refused_with_exit_2(
    one_image_checkpoint: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        use.main(["--policies", str(one_image_checkpoint), "--boats", "2", "--decisions", "1"])
    assert exc.value.code == 2
    assert "not a goal-mark policy" in capsys.readouterr().err
