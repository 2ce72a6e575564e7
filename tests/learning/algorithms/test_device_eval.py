"""Validation on a torch device equals the CPU validation (issue 40)."""

from __future__ import annotations

import numpy as np
import torch

from learning.algorithms.device_eval import first_episode_outcomes, outcome_counts
from learning.algorithms.device_rollout import DeviceNormalizer
from learning.experiments.checkpoint import load_agent, load_checkpoint
from learning.experiments.setups import get_setup
from learning.experiments.validation import family_records, family_validation_episodes
from usvsim.helm.registry import model_path
from usvsim.task.torch_openwater import TorchOpenWaterEnv
from usvsim.task.torch_openwater_episodes import pack_episodes


def test_the_shipped_scene_model_scores_on_the_device_as_on_the_cpu() -> None:
    """scene-gaussian-gail-trpo-openwater on the first 40 family validation episodes: torch-cpu
    float64 with the episodes' noise replayed gives every episode's outcome of the CPU
    evaluation (success, goal, collision; closest approach to 1e-6 m)."""
    n = 40
    path = model_path("scene-gaussian-gail-trpo-openwater")
    agent = load_agent(load_checkpoint(path), path)
    setup = get_setup("rl-gaussian-scene-ow-ft")
    episodes = family_validation_episodes()[:n]
    cpu = family_records(agent, setup, episodes)
    env = TorchOpenWaterEnv(n, table=pack_episodes(episodes), per_boat=1, noise="replay",
                            observation="scene")  # fmt: skip
    obs, _ = env.reset(seed=0)
    got = first_episode_outcomes(
        agent.policy, DeviceNormalizer(agent.normalizer, torch.device("cpu")), env, obs,
        (-1.0, 1.0), 400,
    )  # fmt: skip
    np.testing.assert_array_equal(got["is_success"], [r.success for r in cpu])
    np.testing.assert_array_equal(got["collision"], [r.collision for r in cpu])
    np.testing.assert_array_equal(got["reached_goal"], [r.reached_goal for r in cpu])
    np.testing.assert_allclose(got["min_distance_m"], [r.min_pole_distance_m for r in cpu],
                               atol=1e-6)  # fmt: skip
    counts = outcome_counts(got)
    assert counts["n_episodes"] == n and 0 < counts["successes"] <= n
