"""Single-boat Gymnasium environment of the pole-avoidance task (``usvsim/PoleAvoidance-v0``).

The N = 1 case of :class:`usvsim.task.batch.PoleAvoidanceBatch`: no logic of its own beyond
Gymnasium's single-environment conventions.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from usvsim.task.batch import ActionKind, PoleAvoidanceBatch, observation_rows
from usvsim.task.observations import ObservationKind
from usvsim.task.scenario import EpisodeSpec, draw_episode

__all__ = ["PoleAvoidanceEnv"]


class PoleAvoidanceEnv(gym.Env):
    """Steer a small USV past a pole to a goal 220 m from the start (Vedeler 2019).

    ## Description
    One of two fixed poles is the episode's obstacle. The boat starts 50-100 m from it, heading
    at it, at a constant 3 m/s; the goal lies 220 m from the start on the start→pole line, beyond
    the pole. Every 2 s the helmsman changes the heading reference; an autopilot steers the boat
    (20 plant steps of 0.1 s) while noisy GNSS, compass and gyro feed a navigation filter.
    See :mod:`usvsim.task.scenario`.

    ## Action Space
    ``action="gaussian"``: ``Box(-1, 1, (1,), float32)``, heading change ``30° · a`` relative to
    the *estimated* heading (linear; outside [-1, 1] or NaN raises ``ValueError``).
    ``action="categorical"``: ``Discrete(41)``, heading change ``-30° + 1.5° · k``.

    ## Observation Space
    From the navigation estimate, never the true state (:mod:`usvsim.task.observations`):
    ``"positional"`` ``Box((4,))`` = [r_pole m, φ_pole rad, r_goal m, φ_goal rad];
    ``"radar"`` ``Box(0, 255, (1, 50, 119), uint8)``; ``"radar+goal"`` ``Dict(radar, goal)``.

    ## Rewards
    ``r = r_pole + r_goal`` from the TRUE distances at the end of the decision period
    (:class:`usvsim.task.reward.GaussianReward`, pluggable); both terms in ``info``.

    ## Starting State
    Drawn by :func:`usvsim.task.scenario.draw_episode` from the env's generator, or given:
    ``reset(options={"episode": EpisodeSpec(...)})``.

    ## Episode End
    From the TRUE position, checked at every 0.1 s plant step:
    ``terminated`` on reaching the goal (≤ 10 m) or a collision (closer than pole radius + half
    beam); ``truncated`` on the time limit (150 s) or leaving the area (> 250 m from the pole).
    ``info["is_success"]``: goal reached and never closer than 10 m to the pole.

    ## Arguments
    ``observation``, ``action``, and the keyword arguments of
    :class:`usvsim.task.batch.PoleAvoidanceBatch` (``scenario``, ``reward``, ``radar``, ``nav``,
    ``plant``, ``vessel``, ``autopilot``, ``backend``).
    """

    def __init__(
        self,
        observation: ObservationKind = "positional",
        action: ActionKind = "gaussian",
        render_mode: str | None = None,
        **kwargs: Any,
    ) -> None:
        if render_mode is not None:
            raise ValueError(
                "PoleAvoidanceEnv has no render modes; use usvsim.evaluation.episode_plots"
            )
        self.sim = PoleAvoidanceBatch(1, observation=observation, action=action, **kwargs)
        self.observation_space = self.sim.single_observation_space
        self.action_space = self.sim.single_action_space
        self._done = True

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        options = dict(options or {})
        spec = options.pop("episode", None)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; known: ['episode']")
        if spec is None:
            spec = draw_episode(self.np_random, self.sim.scenario)
        elif not isinstance(spec, EpisodeSpec):
            raise ValueError(f"options['episode'] must be an EpisodeSpec, got {spec!r}")
        obs = observation_rows(self.sim.reset(None, [spec]), 0)
        self._done = False
        return obs, {"pole_ne": self.sim.pole_ne[0].copy(), "goal_ne": self.sim.goal_ne[0].copy()}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        res = self.sim.step(np.asarray(action)[None])
        info = {k: v[0].item() for k, v in res.info_arrays().items()}
        terminated, truncated = bool(res.terminated[0]), bool(res.truncated[0])
        self._done = terminated or truncated
        return (
            observation_rows(res.observation, 0),
            float(res.reward[0]),
            terminated,
            truncated,
            info,
        )
