"""Fixtures shared by the tests of radar policies' image channels (radar memory, goal mark)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import Checkpoint, save_checkpoint
from learning.experiments.setups import get_setup
from usvsim.task.batch import action_space
from usvsim.task.observations import observation_space
from usvsim.task.openwater_env import OpenWaterVectorEnv


@pytest.fixture
def one_image_checkpoint(tmp_path: Path) -> Path:
    """A one-image radar+goal policy (random weights, non-zero biases) saved as a checkpoint."""
    setup = get_setup("rl-gaussian-radar-colreg-ilft-safe-ow")
    agent = get_algorithm(setup.algorithm).make_agent(
        observation_space("radar+goal"), action_space("gaussian"), setup.run_config(4)
    )
    with torch.no_grad():
        for p in agent.policy.parameters():
            p.add_(0.05 * torch.randn_like(p))
    path = tmp_path / "one.pt"
    save_checkpoint(Checkpoint.from_agent(agent, setup), path)
    return path


@pytest.fixture
def radar_observations() -> list[dict[str, Any]]:
    """Three consecutive radar+goal observations of 5 open-water boats (seeded)."""
    n = 5
    env = OpenWaterVectorEnv(n, observation="radar+goal")
    obs, _ = env.reset(seed=2)
    out = [obs]
    rng = np.random.default_rng(1)
    for _ in range(2):
        obs = env.step(rng.uniform(-1, 1, (n, 1)).astype(np.float32))[0]
        out.append({k: v.copy() for k, v in obs.items()})
    return out
