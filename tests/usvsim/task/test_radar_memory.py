"""Radar memory: the last K images as channels, in training (vector env) and evaluation alike."""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium import spaces

from usvsim.task.observations import observation_space
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.radar_memory import (
    RadarMemory,
    RadarMemoryVectorEnv,
    memory_frames,
    stack_episode_frames,
    stacked_space,
)


def _obs(images: list[int]) -> dict[str, np.ndarray]:
    """A batched radar+goal observation whose boat i's image is filled with images[i]."""
    radar = np.stack([np.full((1, 3, 4), v, dtype=np.uint8) for v in images])
    return {"radar": radar, "goal": np.zeros((len(images), 2), dtype=np.float32)}


def test_the_stacked_space_has_one_channel_per_frame_and_the_same_goal() -> None:
    space = observation_space("radar+goal")
    stacked = stacked_space(space, 3)
    assert stacked["radar"].shape == (3, *space["radar"].shape[1:])
    assert stacked["goal"] == space["goal"]
    assert memory_frames(stacked) == 3
    assert memory_frames(space) == 1
    assert memory_frames(observation_space("positional")) == 1


@pytest.mark.parametrize("bad", [0, -1])
def test_a_stack_of_no_frames_is_refused(bad: int) -> None:
    with pytest.raises(ValueError, match="frames >= 1"):
        stacked_space(observation_space("radar+goal"), bad)


def test_a_positional_space_has_no_radar_to_stack() -> None:
    with pytest.raises(ValueError, match="radar\\+goal"):
        stacked_space(spaces.Box(-1, 1, (4,)), 2)


def test_memory_stacks_the_newest_first_and_starts_from_the_first_image() -> None:
    memory = RadarMemory(3)
    memory.reset(2)
    first = memory(_obs([1, 2]))["radar"]
    assert first[:, :, 0, 0].tolist() == [[1, 1, 1], [2, 2, 2]]  # no earlier image: the first
    second = memory(_obs([3, 4]))["radar"]
    assert second[:, :, 0, 0].tolist() == [[3, 1, 1], [4, 2, 2]]
    third = memory(_obs([5, 6]))["radar"]
    assert third[:, :, 0, 0].tolist() == [[5, 3, 1], [6, 4, 2]]


def test_a_boat_starting_an_episode_forgets_its_last_episode() -> None:
    memory = RadarMemory(2)
    memory.reset(2)
    memory(_obs([1, 2]))
    out = memory(_obs([3, 4]), fresh=np.array([False, True]))["radar"]
    assert out[:, :, 0, 0].tolist() == [[3, 1], [4, 4]]


def test_reset_forgets_every_boat() -> None:
    memory = RadarMemory(2)
    memory.reset(1)
    memory(_obs([7]))
    memory.reset(1)
    assert memory(_obs([9]))["radar"][0, :, 0, 0].tolist() == [9, 9]


def test_memory_refuses_stacked_input_and_a_single_frame() -> None:
    with pytest.raises(ValueError, match="frames >= 2"):
        RadarMemory(1)
    memory = RadarMemory(2)
    memory.reset(1)
    with pytest.raises(ValueError, match=r"\(N, 1, H, W\)"):
        memory({"radar": np.zeros((1, 2, 3, 4), dtype=np.uint8)})


def test_the_vector_env_stacks_each_boats_own_episode_and_its_final_observation() -> None:
    """Against the unwrapped env stepped with the same actions: channel 0 is the env's image,
    channel 1 the boat's image of the decision before (its first image at an episode's start),
    and a final observation's channel 1 is the image before it in the same episode."""
    n, steps = 6, 60
    plain = OpenWaterVectorEnv(n, observation="radar+goal")
    wrapped = RadarMemoryVectorEnv(OpenWaterVectorEnv(n, observation="radar+goal"), 2)
    assert wrapped.single_observation_space["radar"].shape == (2, 50, 119)
    assert wrapped.observation_space["radar"].shape == (n, 2, 50, 119)
    raw, _ = plain.reset(seed=5)
    obs, _ = wrapped.reset(seed=5)
    assert np.array_equal(obs["radar"][:, 0:1], raw["radar"])
    assert np.array_equal(obs["radar"][:, 1:2], raw["radar"])
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(steps):
        before = raw["radar"].copy()
        actions = rng.uniform(-1, 1, (n, 1)).astype(np.float32)
        raw, _, te, tr, raw_info = plain.step(actions)
        obs, _, te2, tr2, info = wrapped.step(actions)
        assert np.array_equal(te, te2) and np.array_equal(tr, tr2)
        done = te | tr
        assert np.array_equal(obs["radar"][:, 0:1], raw["radar"])
        expected_past = np.where(done[:, None, None, None], raw["radar"], before)
        assert np.array_equal(obs["radar"][:, 1:2], expected_past)
        assert np.array_equal(obs["goal"], raw["goal"])
        for i in np.flatnonzero(done):
            final = info["final_obs"][i]["radar"]
            assert np.array_equal(final[0:1], raw_info["final_obs"][i]["radar"])
            assert np.array_equal(final[1:2], before[i])
            ended += 1
    assert ended > 0  # the test saw episodes end


def test_the_vector_env_needs_same_step_autoreset() -> None:
    env = OpenWaterVectorEnv(2, observation="radar+goal")
    env.metadata = {**env.metadata, "autoreset_mode": None}
    with pytest.raises(ValueError, match="SAME_STEP"):
        RadarMemoryVectorEnv(env, 2)


def test_recorded_runs_are_stacked_as_the_memory_stacks_an_episode() -> None:
    """Three runs of 4, 1 and 3 decisions: each row's channels are those RadarMemory gives at
    that decision of its run."""
    values = [1, 2, 3, 4, 10, 20, 21, 22]
    episode = np.array([0, 0, 0, 0, 1, 2, 2, 2])
    images = np.stack([np.full((1, 2, 2), v, dtype=np.uint8) for v in values])
    stacked = stack_episode_frames(images, episode, 3)
    expected = []
    for run in (0, 1, 2):
        memory = RadarMemory(3)
        memory.reset(1)
        for i in np.flatnonzero(episode == run):
            expected.append(memory({"radar": images[i : i + 1]})["radar"][0])
    assert np.array_equal(stacked, np.stack(expected))
    assert stacked[:, :, 0, 0].tolist()[:5] == [
        [1, 1, 1], [2, 1, 1], [3, 2, 1], [4, 3, 2], [10, 10, 10]
    ]  # fmt: skip


def test_runs_must_be_contiguous_to_be_stacked() -> None:
    images = np.zeros((3, 1, 2, 2), dtype=np.uint8)
    with pytest.raises(ValueError, match="together"):
        stack_episode_frames(images, np.array([0, 1, 0]), 2)
    with pytest.raises(ValueError, match=r"\(M, 1, H, W\)"):
        stack_episode_frames(images[:, 0], np.array([0, 1, 0]), 2)
