"""The pole-avoidance task as a native ``gymnasium.vector.VectorEnv`` (autoreset ``SAME_STEP``).

:class:`PoleAvoidanceVectorEnv` wraps :class:`usvsim.task.batch.PoleAvoidanceBatch`: when a boat's
episode ends, ``step`` returns the reward and flags of the finished episode, puts its last
observation in ``info["final_obs"]`` (object array, ``None`` for running boats) and its info in
``info["final_info"]`` (masked by ``info["_final_info"]``), and returns the *new* episode's first
observation in ``obs``. The top-level info arrays describe the step just taken for every boat,
finished or not.

It is the registered ``vector_entry_point`` of ``usvsim/PoleAvoidance-v0``:
``gymnasium.make_vec("usvsim/PoleAvoidance-v0", num_envs=N)`` returns it. The options it shares
with the single env (reward horizon, normalisation, rendering) are applied by
:class:`usvsim.task.options.EnvLayer`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from usvsim.task.batch import (
    ActionKind,
    Observation,
    PoleAvoidanceBatch,
    observation_rows,
    write_observation_rows,
)
from usvsim.task.horizon import RewardHorizon
from usvsim.task.observations import ObservationKind
from usvsim.task.options import EnvLayer, EnvOptions
from usvsim.task.render import RENDER_MODES, RenderConfig, tile_frames
from usvsim.task.scenario import draw_episode

__all__ = ["PoleAvoidanceVectorEnv", "boat_generators", "episodes_option"]

FloatArray = NDArray[np.float64]


def boat_generators(num_envs: int, seed: int | Sequence[int]) -> list[np.random.Generator]:
    """Each boat's episode generator: boat i seeded ``seed + i`` (an int) or ``seed[i]``."""
    seeds = [seed + i for i in range(num_envs)] if isinstance(seed, int) else list(seed)
    if len(seeds) != num_envs:
        raise ValueError(f"need {num_envs} seeds, got {len(seeds)}")
    return [seeding.np_random(int(s))[0] for s in seeds]


def episodes_option(options: dict[str, Any] | None) -> Any:
    """The ``episodes`` reset option (None when absent); any other option is refused."""
    options = dict(options or {})
    episodes = options.pop("episodes", None)
    if options:
        raise ValueError(f"unknown reset options {sorted(options)}; known: ['episodes']")
    return episodes


class PoleAvoidanceVectorEnv(VectorEnv):
    """Native batched pole-avoidance environment: ``num_envs`` boats, one plant call per step.

    Autoreset mode ``SAME_STEP`` (see the module docstring). Boat i draws its episodes from its
    own generator, seeded ``seed + i`` by ``reset(seed=seed)`` (or ``seed[i]`` for a list), which
    is what a single :class:`usvsim.task.env.PoleAvoidanceEnv` reset with ``seed + i`` draws: the
    batch equals N single environments. ``reset(options={"episodes": [spec, ...]})`` starts the
    given :class:`usvsim.task.scenario.EpisodeSpec` (one per boat); later autoresets draw again.

    ``reward_horizon``, ``gamma``, ``normalize_observation``, ``render_mode`` and
    ``render_config`` mean what they mean for :class:`usvsim.task.env.PoleAvoidanceEnv`;
    ``render()`` returns a tuple of ``num_envs`` frames (``"rgb_array"``) or shows them tiled
    (``"human"``). After an autoreset a boat's frame shows its new episode. Further keyword
    arguments are those of :class:`PoleAvoidanceBatch`.
    """

    def __init__(
        self,
        num_envs: int,
        observation: ObservationKind = "positional",
        action: ActionKind = "gaussian",
        render_mode: str | None = None,
        reward_horizon: RewardHorizon = "episode",
        gamma: float = 0.99,
        normalize_observation: bool = False,
        render_config: RenderConfig | None = None,
        **kwargs: Any,
    ) -> None:
        options = EnvOptions(
            reward_horizon,
            gamma,
            normalize_observation,
            render_mode,
            render_config or RenderConfig(),
        )
        self.metadata = {
            "autoreset_mode": AutoresetMode.SAME_STEP,
            "render_modes": list(RENDER_MODES),
            "render_fps": options.render.fps,
        }
        self.render_mode = render_mode
        self.sim = PoleAvoidanceBatch(num_envs, observation=observation, action=action, **kwargs)
        self.layer = EnvLayer(self.sim, options)
        self.num_envs = self.sim.n_boats
        self.single_observation_space = self.layer.single_observation_space
        self.single_action_space = self.sim.single_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._boat_rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._obs: Observation | None = None

    def reset(
        self, *, seed: int | Sequence[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Reset every boat; ``seed`` int → boat i uses ``seed + i``; ``options``: ``episodes``."""
        super().reset(seed=seed if isinstance(seed, int) or seed is None else None)
        if seed is not None:
            self._boat_rngs = boat_generators(self.num_envs, seed)
        specs = episodes_option(options)
        if specs is None:
            specs = [draw_episode(g, self.sim.scenario) for g in self._boat_rngs]
        self._obs = self.layer.started(np.arange(self.num_envs), self.sim.reset(None, list(specs)))
        if self.render_mode == "human":
            self.render()
        return self._obs, {"pole_ne": self.sim.pole_ne.copy(), "goal_ne": self.sim.goal_ne.copy()}

    def step(
        self, actions: Any
    ) -> tuple[Observation, FloatArray, NDArray[np.bool_], NDArray[np.bool_], dict[str, Any]]:
        res = self.sim.step(actions)
        reward, terminated, truncated = self.layer.stepped(res)
        info: dict[str, Any] = {}
        everyone = np.ones(self.num_envs, dtype=bool)
        arrays = res.info_arrays()
        for key, value in arrays.items():
            info[key], info[f"_{key}"] = value, everyone
        obs = self.layer.observation(res.observation)
        done = terminated | truncated
        if done.any():
            idx = np.flatnonzero(done)
            final_obs = np.full(self.num_envs, None, dtype=object)
            for i in idx:
                final_obs[i] = observation_rows(obs, i)
            final_info: dict[str, Any] = {}
            for key, value in arrays.items():
                final_info[key], final_info[f"_{key}"] = value.copy(), done
            info.update(
                final_obs=final_obs, _final_obs=done, final_info=final_info, _final_info=done
            )
            specs = [draw_episode(self._boat_rngs[i], self.sim.scenario) for i in idx]
            write_observation_rows(obs, idx, self.layer.started(idx, self.sim.reset(idx, specs)))
        self._obs = obs
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

    def render(self) -> tuple[Any, ...] | None:
        """A tuple of ``num_envs`` frames ``(H, W, 3) uint8`` (``"rgb_array"``), or ``None``
        after showing them tiled in a window (``"human"``)."""
        frames = self.layer.frames()
        if self.render_mode == "human":
            self.layer.show(tile_frames(frames))
            return None
        return tuple(frames)

    def close_extras(self, **kwargs: Any) -> None:
        self.layer.close()
