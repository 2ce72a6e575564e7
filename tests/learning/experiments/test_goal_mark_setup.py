"""The goal mark in training and in checkpoints (usvsim.task.goal_mark): the widened warm start
is the same policy, a marked checkpoint round-trips, and its helmsman draws the mark itself."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import (
    Checkpoint,
    load_checkpoint,
    load_helmsman,
    save_checkpoint,
    slim_copy,
    starting_policy,
)
from learning.experiments.setups import RLSetup, get_setup
from learning.experiments.train_rl import train_rl
from usvsim.common.errors import UserError
from usvsim.task.goal_mark import GoalMarkVectorEnv, with_goal_mark

MARKED = "rl-gaussian-radar-colreg-ilft-safe-ow-aim2-mark"
PARENT = "rl-gaussian-radar-colreg-ilft-safe-ow-aim2"


def _marked_agent() -> Any:
    setup = get_setup(MARKED)
    env = setup.make_vector_env(2)
    return setup, get_algorithm(setup.algorithm).make_agent(
        env.single_observation_space, env.single_action_space, setup.run_config(0)
    )


def test_the_marked_setup_differs_from_its_parent_by_the_mark_only() -> None:
    marked, parent = get_setup(MARKED), get_setup(PARENT)
    assert marked.goal_mark and not parent.goal_mark
    assert marked.replace(name=PARENT, goal_mark=False) == parent
    env = marked.make_vector_env(2)
    assert isinstance(env, GoalMarkVectorEnv)
    assert env.single_observation_space["radar"].shape == (2, 50, 119)


def test_the_goal_mark_needs_the_radar_observation() -> None:
    with pytest.raises(ValueError, match="goal_mark needs observation='radar\\+goal'"):
        RLSetup("x", "scene", "gaussian", goal_mark=True)


def test_the_widened_start_is_the_same_policy_whatever_the_mark(
    one_image_checkpoint: Path, radar_observations: list[dict[str, Any]]
) -> None:
    path = one_image_checkpoint
    setup, agent = _marked_agent()
    agent.load_policy(starting_policy(path, setup))
    original = load_helmsman(path)
    assert not original.goal_mark and original.memory is None
    for obs in radar_observations:
        marked = with_goal_mark(obs)
        assert marked["radar"][:, 1].any()  # a mark to ignore
        expected = original.agent.act(obs, deterministic=True)
        assert np.array_equal(agent.act(marked, deterministic=True), expected)


def test_a_marked_checkpoint_round_trips_and_its_helmsman_draws_the_mark(
    tmp_path: Path, radar_observations: list[dict[str, Any]]
) -> None:
    setup, agent = _marked_agent()
    with torch.no_grad():
        agent.policy.trunk.conv.weight[:, 1].normal_(0.0, 0.5)  # the mark matters
    ckpt = Checkpoint.from_agent(agent, setup)
    save_checkpoint(ckpt, tmp_path / "full.pt")
    save_checkpoint(slim_copy(ckpt), tmp_path / "slim.pt")
    observations = radar_observations
    for file in (tmp_path / "full.pt", tmp_path / "slim.pt"):
        assert load_checkpoint(file).setup_params["goal_mark"] is True
        helmsman = load_helmsman(file)
        assert helmsman.goal_mark and helmsman.memory is None
        helmsman.reset(5)
        for obs in observations:
            expected = agent.act(with_goal_mark(obs), deterministic=True)
            assert np.array_equal(helmsman.act(obs), expected)
    # with the mark blanked the policy acts otherwise: the mark is used
    blank = with_goal_mark(observations[2])
    blank["radar"][:, 1] = 0
    assert not np.array_equal(agent.act(blank, deterministic=True), expected)


def test_a_marked_policy_continues_a_marked_run(tmp_path: Path) -> None:
    setup, agent = _marked_agent()
    path = tmp_path / "marked.pt"
    save_checkpoint(Checkpoint.from_agent(agent, setup), path)
    state = starting_policy(path, setup)
    assert state["policy"]["trunk.conv.weight"].shape[1] == 2  # not widened twice


def test_the_goal_mark_is_refused_on_the_device_backend(
    tmp_path: Path, one_image_checkpoint: Path
) -> None:
    with pytest.raises(UserError, match=r"goal mark .* --device cpu only"):
        train_rl(get_setup(MARKED), tmp_path / "run", iterations=1, device="torch-cpu",
                 init_policy=one_image_checkpoint)  # fmt: skip


def test_the_il_marked_setup_differs_from_its_parent_by_the_mark_only() -> None:
    from learning.experiments.il_setups import ILSetup, get_il_setup

    marked, parent = (
        get_il_setup("il-gaussian-radar-ow-colreg-mark"),
        get_il_setup("il-gaussian-radar-ow-colreg"),
    )
    assert marked.goal_mark and not parent.goal_mark
    assert marked.replace(name=parent.name, goal_mark=False) == parent
    with pytest.raises(ValueError, match="goal_mark needs observation='radar\\+goal'"):
        ILSetup("x", "scene", "gaussian", goal_mark=True)


def test_the_expert_pairs_of_a_marked_setup_carry_the_mark_last(tmp_path: Path) -> None:
    """The same demonstrations with and without the mark: the image channels before the last
    are the unmarked data's (radar memory's included), the last is the goal part's mark."""
    from learning.experiments.il_setups import get_il_setup
    from learning.experiments.train_il import expert_pairs
    from learning.imitation.demonstrations import save_recordings
    from learning.imitation.family_demos import record_family_demonstrations
    from usvsim.task.goal_mark import goal_mark_images
    from usvsim.task.radar import RadarConfig

    save_recordings(record_family_demonstrations(3, seed=5), tmp_path)
    one = get_il_setup("il-gaussian-radar-ow").replace(harsh_radar_copies=0, radar_frames=2)
    plain, _, _ = expert_pairs(one, (tmp_path,), lambda _: None)
    data, _, _ = expert_pairs(one.replace(goal_mark=True), (tmp_path,), lambda _: None)
    assert isinstance(plain.obs, dict) and isinstance(data.obs, dict)
    assert data.obs["radar"].shape == (len(plain), 3, 50, 119)
    assert np.array_equal(data.obs["radar"][:, :2], plain.obs["radar"])
    mark = data.obs["radar"][:, 2:]
    assert np.array_equal(mark, goal_mark_images(plain.obs["goal"], RadarConfig()))
    assert (mark.reshape(len(plain), -1).max(axis=1) == 255).all()  # every pair shows its goal
    assert np.array_equal(data.actions, plain.actions)


def test_the_il_goal_mark_is_refused_on_the_device_backend(tmp_path: Path) -> None:
    from learning.experiments.il_setups import get_il_setup
    from learning.experiments.train_il import train_il

    with pytest.raises(UserError, match=r"goal mark .* --device cpu only"):
        train_il(get_il_setup("il-gaussian-radar-ow-colreg-mark"), tmp_path / "run",
                 iterations=1, device="torch-cpu")  # fmt: skip
    assert not (tmp_path / "run").exists()  # refused before anything was written
