"""Radar memory: the policy sees the last K radar images, not one (issue 41).

A ``radar+goal`` observation is one image, so a policy on it is memoryless: it cannot tell a
vessel's course from one frame, and an obstacle that has left the ±120° field of view is gone
from its input. With radar memory the image part holds the images of the last K decisions as K
channels, the newest first:

==================  ===================  =====================================================
part                shape                meaning
==================  ===================  =====================================================
``radar``           (N, K, 50, 119)      channel 0 the image now, channel j the image of j
                                         decisions (2 j s) earlier; each in the boat's own
                                         frame at its time (no motion compensation)
``goal``            (N, 2)               unchanged
==================  ===================  =====================================================

At an episode's first decision there is no earlier image: every channel holds the first image
(the scene as if it had not moved), so a new episode never sees the last one's pictures.

One definition serves training and evaluation: :class:`RadarMemory` keeps each boat's earlier
images; :class:`RadarMemoryVectorEnv` applies it to a vector env (autoreset ``SAME_STEP``: the
boats whose episode ended start their memory from the new episode's first image, and their final
observations are stacked with their own episode's images), and a trained policy's helmsman applies
it to the observations of any evaluation (``learning.experiments.checkpoint.PolicyHelmsman``),
reset with the helmsman before each batch of episodes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv, VectorWrapper
from numpy.typing import NDArray

__all__ = [
    "RadarMemory",
    "RadarMemoryVectorEnv",
    "memory_frames",
    "stack_episode_frames",
    "stacked_space",
]

IMAGE_KEY = "radar"  # the image part of a radar+goal observation


def stacked_space(space: spaces.Space, frames: int) -> spaces.Dict:
    """The single-boat ``radar+goal`` space ``space`` with ``frames`` (>= 1) images of one
    channel each stacked as channels: ``radar`` (1, H, W) → (frames, H, W)."""
    if frames < 1:
        raise ValueError(f"radar memory needs frames >= 1, got {frames!r}")
    if not (isinstance(space, spaces.Dict) and IMAGE_KEY in space.spaces):
        raise ValueError(f"radar memory needs a radar+goal (Dict with 'radar') space, got {space}")
    image = space.spaces[IMAGE_KEY]
    assert isinstance(image, spaces.Box)
    if image.shape[0] != 1:
        raise ValueError(f"radar memory stacks one-channel images, got shape {image.shape}")
    shape = (frames, *image.shape[1:])
    widened = spaces.Box(0, 255, shape, dtype=np.uint8)
    return spaces.Dict({**space.spaces, IMAGE_KEY: widened})


def memory_frames(space: spaces.Space) -> int:
    """The number of radar images (channels) a policy of observation ``space`` reads: 1 for a
    plain ``radar+goal`` policy or any other observation, K for one with radar memory."""
    if isinstance(space, spaces.Dict) and IMAGE_KEY in space.spaces:
        shape = space.spaces[IMAGE_KEY].shape
        return int(shape[0]) if shape else 1
    return 1


def stack_episode_frames(
    images: NDArray[np.uint8], episode: NDArray[np.integer], frames: int
) -> NDArray[np.uint8]:
    """Recorded runs' images with memory: ``images`` (M, 1, H, W) of consecutive decisions,
    ``episode`` (M,) the run of each (a run's rows together, in time order) → (M, frames, H, W),
    what :class:`RadarMemory` gives along each run (an expert's demonstrations as the policy
    will see its own episodes)."""
    episode = np.asarray(episode)
    m = images.shape[0]
    if images.ndim != 4 or images.shape[1] != 1 or episode.shape != (m,):
        raise ValueError(
            f"stack_episode_frames takes images (M, 1, H, W) and episode (M,), got "
            f"{images.shape} and {episode.shape}"
        )
    row = np.arange(m)
    first = np.ones(m, dtype=bool)
    first[1:] = episode[1:] != episode[:-1]
    if np.unique(episode[first]).size != int(first.sum()):
        raise ValueError("stack_episode_frames needs each run's rows together")
    start = np.maximum.accumulate(np.where(first, row, 0))
    out = np.empty((m, frames, *images.shape[2:]), dtype=images.dtype)  # one allocation
    for j in range(frames):  # channels, not rows: K array operations
        out[:, j] = images[np.maximum(row - j, start), 0]
    return out


class RadarMemory:
    """Every boat's last ``frames - 1`` radar images, stacked behind the image now.

    ``reset(n)`` forgets everything; ``__call__(obs, fresh)`` returns the stacked observation of
    a batched ``radar+goal`` observation and remembers its images. ``fresh`` (N,) bool marks the
    boats whose observation is an episode's first (None: only those never seen since ``reset``).
    """

    def __init__(self, frames: int) -> None:
        if frames < 2:
            raise ValueError(f"RadarMemory needs frames >= 2 (1 is no memory), got {frames!r}")
        self.frames = frames
        self._past: NDArray[np.uint8] | None = None  # (N, frames - 1, H, W), newest first

    def reset(self, n_boats: int) -> None:
        """Forget every boat's images (a new batch of ``n_boats`` episodes follows)."""
        self._n = n_boats
        self._past = None

    def stack(self, image: NDArray[np.uint8], past: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """[image (B, 1, H, W), past (B, K - 1, H, W)] → (B, K, H, W), without remembering."""
        return np.concatenate([image, past], axis=1)

    def first_past(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """The earlier images (B, K - 1, H, W) of an episode's first decision: copies of its
        ``image`` (B, 1, H, W)."""
        return np.repeat(image, self.frames - 1, axis=1)

    def past_of(self, image: NDArray[np.uint8], fresh: NDArray[np.bool_] | None) -> NDArray[Any]:
        """The earlier images (N, K - 1, H, W) behind ``image`` (N, 1, H, W): the remembered
        ones, or copies of ``image`` for boats starting an episode."""
        if self._past is None or self._past.shape[0] != image.shape[0]:
            return self.first_past(image)
        if fresh is None or not fresh.any():
            return self._past
        past = self._past.copy()
        past[fresh] = self.first_past(image[fresh])
        return past

    def __call__(
        self, observation: dict[str, Any], fresh: NDArray[np.bool_] | None = None
    ) -> dict[str, Any]:
        image = np.asarray(observation[IMAGE_KEY])
        if image.ndim != 4 or image.shape[1] != 1:
            raise ValueError(
                f"RadarMemory takes radar images of shape (N, 1, H, W), got {image.shape}"
            )
        past = self.past_of(image, fresh)
        stacked = self.stack(image, past)
        self._past = np.ascontiguousarray(stacked[:, :-1])  # the newest K - 1 for next time
        return {**observation, IMAGE_KEY: stacked}

    def remembered(self, boats: NDArray[np.intp]) -> NDArray[np.uint8] | None:
        """The remembered images (B, K - 1, H, W) of ``boats``, or None before the first call."""
        return None if self._past is None else self._past[boats]


class RadarMemoryVectorEnv(VectorWrapper):
    """A ``radar+goal`` vector env (autoreset ``SAME_STEP``) whose observations carry the last
    ``frames`` radar images (module docstring): ``single_observation_space`` is
    :func:`stacked_space`; ``info["final_obs"]`` rows are stacked with their own episode's
    images."""

    def __init__(self, env: VectorEnv, frames: int) -> None:
        super().__init__(env)
        if env.metadata.get("autoreset_mode") != AutoresetMode.SAME_STEP:
            raise ValueError(
                f"RadarMemoryVectorEnv needs autoreset_mode SAME_STEP, got "
                f"{env.metadata.get('autoreset_mode')!r}"
            )
        self.memory = RadarMemory(frames)
        single = stacked_space(env.single_observation_space, frames)
        image_shape: tuple[int, ...] = tuple(single.spaces[IMAGE_KEY].shape or ())
        shape = (self.num_envs, *image_shape)
        batched = env.observation_space
        assert isinstance(batched, spaces.Dict)
        self.single_observation_space = single
        self.observation_space = spaces.Dict(
            {
                **batched.spaces,
                IMAGE_KEY: spaces.Box(0, 255, shape, dtype=np.uint8),
            }
        )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self.memory.reset(self.num_envs)
        return self.memory(obs), info

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        done = np.asarray(terminated) | np.asarray(truncated)
        if done.any() and "final_obs" in info:
            ended = np.flatnonzero(done)
            past = self.memory.remembered(ended)
            final = info["final_obs"].copy()
            for j, i in enumerate(ended.tolist()):
                row = final[i]
                image = np.asarray(row[IMAGE_KEY])[None]  # (1, 1, H, W)
                before = past[j : j + 1] if past is not None else self.memory.first_past(image)
                final[i] = {**row, IMAGE_KEY: self.memory.stack(image, before)[0]}
            info = {**info, "final_obs": final}
        return self.memory(obs, fresh=done), reward, terminated, truncated, info
