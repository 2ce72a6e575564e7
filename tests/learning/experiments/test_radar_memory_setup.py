"""Radar memory in training and in checkpoints: the widened warm start is the same policy, a
memory checkpoint round-trips, and its helmsman keeps the earlier images itself."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from learning.algorithms.registry import get_algorithm
from learning.experiments.checkpoint import (
    Checkpoint,
    CheckpointError,
    load_checkpoint,
    load_helmsman,
    save_checkpoint,
    slim_copy,
    starting_policy,
)
from learning.experiments.setups import RLSetup, get_setup
from learning.experiments.train_rl import train_rl
from usvsim.common.errors import UserError
from usvsim.task.radar_memory import RadarMemory, RadarMemoryVectorEnv

MEM = "rl-gaussian-radar-colreg-ilft-safe-ow-mem"
ONE = "rl-gaussian-radar-colreg-ilft-safe-ow"


def test_the_memory_setup_differs_from_its_parent_by_the_frames_only() -> None:
    mem, one = get_setup(MEM), get_setup(ONE)
    assert mem.radar_frames == 2 and one.radar_frames == 1
    assert mem.replace(name=ONE, radar_frames=1) == one
    env = mem.make_vector_env(2)
    assert isinstance(env, RadarMemoryVectorEnv)
    assert env.single_observation_space["radar"].shape == (2, 50, 119)


@pytest.mark.parametrize("frames", [0, 1.5])
def test_radar_frames_must_be_a_positive_int(frames: Any) -> None:
    with pytest.raises(ValueError, match="radar_frames"):
        get_setup(ONE).replace(radar_frames=frames)


def test_radar_memory_needs_the_radar_observation() -> None:
    with pytest.raises(ValueError, match="radar\\+goal"):
        RLSetup("x", "positional", "gaussian", radar_frames=2)


def test_the_widened_start_is_the_same_policy_whatever_the_earlier_image(
    one_image_checkpoint: Path, radar_observations: list[dict[str, Any]]
) -> None:
    path = one_image_checkpoint
    setup = get_setup(MEM)
    env = setup.make_vector_env(5)
    agent = get_algorithm(setup.algorithm).make_agent(
        env.single_observation_space, env.single_action_space, setup.run_config(0)
    )
    agent.load_policy(starting_policy(path, setup))
    original = load_helmsman(path)
    assert original.memory is None
    first, later = radar_observations[0], radar_observations[2]
    stacked = {"radar": np.concatenate([first["radar"], later["radar"]], axis=1), **{
        "goal": first["goal"]}}  # fmt: skip
    expected = original.agent.act(first, deterministic=True)
    assert np.array_equal(agent.act(stacked, deterministic=True), expected)
    assert not np.array_equal(first["radar"], later["radar"])  # the earlier image differs


def test_a_memory_policy_cannot_start_a_one_image_run(tmp_path: Path) -> None:
    setup = get_setup(MEM)
    env = setup.make_vector_env(2)
    agent = get_algorithm(setup.algorithm).make_agent(
        env.single_observation_space, env.single_action_space, setup.run_config(0)
    )
    path = tmp_path / "mem.pt"
    save_checkpoint(Checkpoint.from_agent(agent, setup), path)
    with pytest.raises(CheckpointError, match="2 image channels cannot start a run of 1"):
        starting_policy(path, get_setup(ONE))


def test_a_memory_checkpoint_round_trips_and_its_helmsman_remembers(
    tmp_path: Path, radar_observations: list[dict[str, Any]]
) -> None:
    setup = get_setup(MEM)
    env = setup.make_vector_env(2)
    agent = get_algorithm(setup.algorithm).make_agent(
        env.single_observation_space, env.single_action_space, setup.run_config(0)
    )
    with torch.no_grad():
        agent.policy.trunk.conv.weight[:, 1].normal_(0.0, 0.5)  # the earlier image matters
    path = tmp_path / "mem.pt"
    ckpt = Checkpoint.from_agent(agent, setup)
    save_checkpoint(ckpt, path)
    save_checkpoint(slim_copy(ckpt), tmp_path / "slim.pt")
    observations = radar_observations
    for file in (path, tmp_path / "slim.pt"):
        assert load_checkpoint(file).setup_params["radar_frames"] == 2
        helmsman = load_helmsman(file)
        assert helmsman.memory is not None and helmsman.memory.frames == 2
        helmsman.reset(5)
        memory = RadarMemory(2)
        memory.reset(5)
        for obs in observations:
            expected = agent.act(memory(obs), deterministic=True)
            assert np.array_equal(helmsman.act(obs), expected)
    # without its memory (the image now twice) the policy acts otherwise: the memory is used
    twice = {**observations[2], "radar": np.repeat(observations[2]["radar"], 2, axis=1)}
    assert not np.array_equal(agent.act(twice, deterministic=True), expected)


def test_radar_memory_is_refused_on_the_device_backend(
    tmp_path: Path, one_image_checkpoint: Path
) -> None:
    with pytest.raises(UserError, match=r"radar memory .* --device cpu only"):
        train_rl(get_setup(MEM), tmp_path / "run", iterations=1, device="torch-cpu",
                 init_policy=one_image_checkpoint)  # fmt: skip


def test_the_il_memory_setup_differs_from_its_parent_by_the_frames_only() -> None:
    from learning.experiments.il_setups import get_il_setup

    mem, one = (
        get_il_setup("il-gaussian-radar-ow-colreg-mem"),
        get_il_setup("il-gaussian-radar-ow-colreg"),
    )
    assert (mem.radar_frames, one.radar_frames) == (2, 1)
    assert mem.replace(name=one.name, radar_frames=1) == one
    with pytest.raises(ValueError, match="radar_frames"):
        one.replace(observation="scene", radar_frames=2)


def test_the_expert_pairs_of_a_memory_setup_stack_each_runs_images(tmp_path: Path) -> None:
    """The same demonstrations, one image or two: channel 0 is the one-image data's image,
    channel 1 the image of the decision before in the same run (its first image at a start)."""
    from learning.experiments.il_setups import get_il_setup
    from learning.experiments.train_il import expert_pairs
    from learning.imitation.demonstrations import save_recordings
    from learning.imitation.family_demos import record_family_demonstrations

    save_recordings(record_family_demonstrations(3, seed=5), tmp_path)
    one = get_il_setup("il-gaussian-radar-ow").replace(harsh_radar_copies=0)
    plain, _, _ = expert_pairs(one, (tmp_path,), lambda _: None)
    data, _, _ = expert_pairs(one.replace(radar_frames=2), (tmp_path,), lambda _: None)
    assert isinstance(plain.obs, dict) and isinstance(data.obs, dict)
    now, before = data.obs["radar"][:, 0:1], data.obs["radar"][:, 1:2]
    assert np.array_equal(now, plain.obs["radar"])
    first = np.r_[True, plain.episode[1:] != plain.episode[:-1]]
    assert np.array_equal(before[first], now[first])
    assert np.array_equal(before[~first], plain.obs["radar"][np.flatnonzero(~first) - 1])
    assert np.array_equal(data.actions, plain.actions) and np.array_equal(
        data.obs["goal"], plain.obs["goal"]
    )
    assert first.sum() == 3 and (~first).sum() > 0
