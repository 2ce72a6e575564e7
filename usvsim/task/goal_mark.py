"""A goal mark in the radar image: the goal's circle drawn as one more image channel (issue 41).

A ``radar+goal`` policy sees the goal only as two numbers beside the image (its standardised
range and bearing, joined to the convolution's features in FC 1), so "the goal is nearer than
that islet" asks the network to compare image rows with a number. Measured on the traffic
policies (``benchmarks/goal_response.py --islet``, ``docs/notes/2026-12-traffic.md``): beside an
islet they turn away at the limit whatever the goal's bearing. With the goal mark the image part
carries one more channel, the last, in the radar's own polar grid:

==================  ===================  =====================================================
part                shape                meaning
==================  ===================  =====================================================
``radar``           (N, C + 1, 50, 119)  channels 0..C-1 the radar image(s) as before; channel
                                         C the goal mark: 255 in every cell whose centre lies
                                         within the goal circle (10 m, the study's
                                         ``Scenario.goal_radius_m``), and in the goal's own
                                         cell; 0 elsewhere
``goal``            (N, 2)               unchanged
==================  ===================  =====================================================

A goal beyond the image (farther than its 200 m, or outside its ±120°) is drawn where it leaves
it: its range clipped to the last row's centre and its bearing to the outermost column's, so the
mark always shows the direction to steer. The mark is a function of the observation's own goal
part (its standardisation inverted), so it needs no state: one definition,
:func:`with_goal_mark`, serves the training env (:class:`GoalMarkVectorEnv`) and a trained
policy's helmsman on any evaluation (``learning.experiments.checkpoint.PolicyHelmsman``). A
one-channel policy is widened to read it with the new channel's weights at zero
(``learning.experiments.memory_start.widened_policy_state``): the same function until trained.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import VectorEnv, VectorWrapper
from numpy.typing import NDArray

from usvsim.task.observations import GOAL_STANDARDIZATION
from usvsim.task.radar import RadarConfig

__all__ = [
    "GOAL_MARK_RADIUS_M",
    "GoalMarkVectorEnv",
    "goal_mark_images",
    "goal_polar",
    "marked_space",
    "with_goal_mark",
]

IMAGE_KEY, GOAL_KEY = "radar", "goal"
GOAL_MARK_RADIUS_M = 10.0  # m; the study's goal circle (usvsim.task.scenario.Scenario)
MARK = 255  # the mark's intensity, a radar return's full scale
MARK_BLOCK = 2048  # boats marked per NumPy pass in with_goal_mark (bounds its memory)


def goal_polar(goal: NDArray[np.floating]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Range (m) and bearing (rad, to starboard positive) of the goal from the ``radar+goal``
    observation's standardised goal part ``goal`` (N, 2): ``GOAL_STANDARDIZATION`` inverted."""
    g = np.asarray(goal, dtype=np.float64)
    mean, std = np.asarray(GOAL_STANDARDIZATION.mean), np.asarray(GOAL_STANDARDIZATION.std)
    raw = g * std + mean
    return raw[..., 0], raw[..., 1]


@functools.cache
def _cell_centres(cfg: RadarConfig) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Every cell's centre (H, W) in the boat's frame: forward x (m), starboard y (m)."""
    r = 0.5 * (cfg.range_edges_m[:-1] + cfg.range_edges_m[1:])
    b = 0.5 * (cfg.bearing_edges_rad[:-1] + cfg.bearing_edges_rad[1:])
    return np.outer(r, np.cos(b)), np.outer(r, np.sin(b))


def goal_mark_images(
    goal: NDArray[np.floating],
    cfg: RadarConfig | None = None,
    radius_m: float = GOAL_MARK_RADIUS_M,
) -> NDArray[np.uint8]:
    """The goal-mark channel (N, 1, H, W) uint8 of N boats' standardised goals ``goal`` (N, 2)
    (module docstring): ``MARK`` in the cells whose centre is within ``radius_m`` (m) of the
    goal, its range and bearing first clipped into the image, and in the goal's own cell."""
    cfg = cfg or RadarConfig()
    r, b = goal_polar(goal)
    row_m = cfg.max_range_m / cfg.n_rows
    col_rad = 2.0 * cfg.half_fov_rad / cfg.n_cols
    r = np.clip(r, 0.0, cfg.max_range_m - 0.5 * row_m)
    # bearings wrapped to [-π, π) first, as the image's columns (usvsim.common.angles.ssa)
    b = np.mod(b + np.pi, 2.0 * np.pi) - np.pi
    b = np.clip(b, -cfg.half_fov_rad + 0.5 * col_rad, cfg.half_fov_rad - 0.5 * col_rad)
    gx, gy = r * np.cos(b), r * np.sin(b)
    cx, cy = _cell_centres(cfg)
    near = (cx - gx[:, None, None]) ** 2 + (cy - gy[:, None, None]) ** 2 <= radius_m**2
    row = np.minimum((r / row_m).astype(np.intp), cfg.n_rows - 1)
    col = np.minimum(((b + cfg.half_fov_rad) / col_rad).astype(np.intp), cfg.n_cols - 1)
    near[np.arange(r.shape[0]), row, col] = True
    return (near * np.uint8(MARK))[:, None]


def with_goal_mark(observation: dict[str, Any]) -> dict[str, Any]:
    """A batched ``radar+goal`` observation with the goal mark appended as the image's last
    channel: ``radar`` (N, C, H, W) → (N, C + 1, H, W)."""
    image = np.asarray(observation[IMAGE_KEY])
    if image.ndim != 4:
        raise ValueError(f"with_goal_mark takes radar images (N, C, H, W), got {image.shape}")
    cfg = RadarConfig(n_rows=image.shape[2], n_cols=image.shape[3])
    goal = np.asarray(observation[GOAL_KEY]).reshape(-1, 2)
    n, c = image.shape[:2]
    out = np.empty((n, c + 1, *image.shape[2:]), dtype=np.uint8)
    out[:, :c] = image
    # in blocks of boats: the mark's geometry takes 8-byte temporaries per pixel, which for a
    # demonstration set's 160,000 images would need tens of GB at once
    for lo in range(0, n, MARK_BLOCK):
        out[lo : lo + MARK_BLOCK, c:] = goal_mark_images(goal[lo : lo + MARK_BLOCK], cfg)
    return {**observation, IMAGE_KEY: out}


def marked_space(space: spaces.Space) -> spaces.Dict:
    """The single-boat ``radar+goal`` space ``space`` with the goal-mark channel added:
    ``radar`` (C, H, W) → (C + 1, H, W)."""
    if not (isinstance(space, spaces.Dict) and IMAGE_KEY in space.spaces):
        raise ValueError(f"the goal mark needs a radar+goal (Dict with 'radar') space, got {space}")
    image = space.spaces[IMAGE_KEY]
    assert isinstance(image, spaces.Box)
    c, h, w = image.shape
    return spaces.Dict(
        {**space.spaces, IMAGE_KEY: spaces.Box(0, 255, (c + 1, h, w), dtype=np.uint8)}
    )


class GoalMarkVectorEnv(VectorWrapper):
    """A ``radar+goal`` vector env whose observations (and ``info["final_obs"]`` rows) carry the
    goal mark (module docstring): ``single_observation_space`` is :func:`marked_space`."""

    def __init__(self, env: VectorEnv) -> None:
        super().__init__(env)
        single = marked_space(env.single_observation_space)
        batched = env.observation_space
        assert isinstance(batched, spaces.Dict)
        shape = (self.num_envs, *(single.spaces[IMAGE_KEY].shape or ()))
        self.single_observation_space = single
        self.observation_space = spaces.Dict(
            {**batched.spaces, IMAGE_KEY: spaces.Box(0, 255, shape, dtype=np.uint8)}
        )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        return with_goal_mark(obs), info

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        ended = np.flatnonzero(np.asarray(terminated) | np.asarray(truncated))
        if ended.size and "final_obs" in info:  # the ended boats' rows, marked in one batch
            final = info["final_obs"].copy()
            rows = [final[i] for i in ended.tolist()]
            marked = with_goal_mark({k: np.stack([r[k] for r in rows]) for k in rows[0]})
            for j, i in enumerate(ended.tolist()):
                final[i] = {k: v[j] for k, v in marked.items()}
            info = {**info, "final_obs": final}
        return with_goal_mark(obs), reward, terminated, truncated, info
