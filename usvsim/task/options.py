"""What the single and the vector environment add to the batch simulator, written once.

:class:`EnvOptions` holds the environment options that are not the task's physics: the reward
horizon (:mod:`usvsim.task.horizon`), observation normalisation and the render mode.
:class:`EnvLayer` applies them to a :class:`usvsim.task.batch.PoleAvoidanceBatch`: both
:class:`usvsim.task.env.PoleAvoidanceEnv` (N = 1) and
:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv` call it at reset and step, so the two
cannot drift apart.

``normalize_observation=True`` standardises the positional observation with the fixed
constants the networks use (:data:`usvsim.task.observations.POSITIONAL_STANDARDIZATION`: about
zero mean, unit spread over an episode, instead of raw metres with bounds of 10 km), so an
outside trainer needs no normaliser of its own. The radar image stays ``uint8`` (image
networks, Stable-Baselines3's included, scale it themselves) and the goal vector of
``radar+goal`` is standardised already.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import cast

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from usvsim.task.batch import BatchStep, Observation, PoleAvoidanceBatch
from usvsim.task.horizon import RewardHorizon, apply_reward_horizon, parse_reward_horizon
from usvsim.task.observations import POSITIONAL_STANDARDIZATION
from usvsim.task.render import RENDER_MODES, Frame, HumanWindow, RenderConfig, TopView

__all__ = ["EnvLayer", "EnvOptions", "normalized_observation", "normalized_positional_space"]


def normalized_positional_space(space: spaces.Space) -> spaces.Box:
    """The positional observation space as ``normalize_observation=True`` reports it."""
    assert isinstance(space, spaces.Box)
    return spaces.Box(
        POSITIONAL_STANDARDIZATION.apply(space.low),
        POSITIONAL_STANDARDIZATION.apply(space.high),
        dtype=np.float32,
    )


def normalized_observation(kind: str, obs: Observation) -> Observation:
    """A batched observation of ``kind`` as ``normalize_observation=True`` returns it: the
    positional one standardised (float32), radar images and ``radar+goal`` unchanged."""
    if kind == "positional":
        assert not isinstance(obs, dict)
        return POSITIONAL_STANDARDIZATION.apply(cast(NDArray[np.floating], obs))
    return obs


@dataclass(frozen=True)
class EnvOptions:
    """Environment options beyond the task (module docstring)."""

    reward_horizon: RewardHorizon = "episode"  # "fixed": the study's fixed-length return
    gamma: float = 0.99  # discount of the fixed horizon; the trainer's γ
    normalize_observation: bool = False  # standardised positional observation
    render_mode: str | None = None  # None, "rgb_array" or "human"
    render: RenderConfig = field(default_factory=RenderConfig)

    def __post_init__(self) -> None:
        parse_reward_horizon(self.reward_horizon, self.gamma)
        if self.render_mode is not None and self.render_mode not in RENDER_MODES:
            raise ValueError(
                f"render_mode must be None or one of {RENDER_MODES}, got {self.render_mode!r}"
            )
        if not isinstance(self.normalize_observation, bool):
            raise ValueError(
                f"normalize_observation must be True or False, got {self.normalize_observation!r}"
            )


class EnvLayer:
    """Reward horizon, normalisation and rendering of ``sim`` under ``options``."""

    def __init__(self, sim: PoleAvoidanceBatch, options: EnvOptions) -> None:
        self.sim, self.options = sim, options
        self._normalize = options.normalize_observation and sim.observation_kind == "positional"
        space = sim.single_observation_space
        if self._normalize:
            space = normalized_positional_space(space)
        self.single_observation_space: spaces.Space = space
        self._view: TopView | None = None
        self._radar: NDArray[np.uint8] | None = None
        self._window: HumanWindow | None = None
        if options.render_mode is not None:
            vessel = sim.plant.vessel
            self._view = TopView(
                sim.n_boats, sim.scenario, vessel.length_m, vessel.beam_m, options.render
            )
            self._time_s = np.zeros(sim.n_boats)
            if sim.observation_kind != "positional":  # the last radar image, for the inset
                self._radar = np.zeros((sim.n_boats, *sim.radar.shape), dtype=np.uint8)
        if options.render_mode == "human":
            self._window = HumanWindow(options.render.fps)

    def observation(self, obs: Observation) -> Observation:
        """The batched observation of every boat as the env returns it (normalised if asked)."""
        return self.started(np.arange(self.sim.n_boats), obs, new_episodes=False)

    def started(
        self, boats: NDArray[np.intp], obs: Observation, new_episodes: bool = True
    ) -> Observation:
        """Boats ``boats`` started new episodes (``new_episodes``) or stepped; ``obs`` holds
        their rows. Returns the rows as the env returns them (normalised if asked)."""
        if self._view is not None and new_episodes:
            sim = self.sim
            self._view.reset(
                boats, sim.state.eta[boats, :2], sim.pole_ne[boats], sim.goal_ne[boats]
            )
            self._time_s[boats] = 0.0
        if self._radar is not None:
            self._radar[boats] = obs["radar"] if isinstance(obs, dict) else obs
        if self._normalize:
            return normalized_observation(self.sim.observation_kind, obs)
        return obs

    def stepped(
        self, res: BatchStep
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
        """Record the step for rendering; reward and flags under the reward horizon."""
        if self._view is not None:
            self._view.record(res.trajectory[:, :, 0:2], res.end_step)
            self._time_s = res.time_s.copy()
        o = self.options
        return apply_reward_horizon(
            o.reward_horizon,
            o.gamma,
            self.sim.scenario,
            res.reward,
            res.terminated,
            res.truncated,
            res.out_of_area,
            res.time_s,
        )

    def frames(self) -> list[Frame]:
        """One top-view frame per boat (``render_mode`` must be set)."""
        if self._view is None:
            raise RuntimeError("render() needs render_mode='rgb_array' or 'human' at construction")
        eta = self.sim.state.eta
        return [
            self._view.frame(
                i,
                eta[i],
                self.sim.pole_ne[i],
                self.sim.goal_ne[i],
                float(self._time_s[i]),
                None if self._radar is None else self._radar[i],
            )
            for i in range(self.sim.n_boats)
        ]

    def show(self, frame: Frame) -> None:
        """Show ``frame`` in the human-mode window."""
        assert self._window is not None
        self._window.show(frame)

    def close(self) -> None:
        if self._window is not None:
            self._window.close()
