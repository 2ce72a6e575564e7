"""Single-boat Gymnasium environment of the pole-avoidance task (``usvsim/PoleAvoidance-v0``).

The N = 1 case of :class:`usvsim.task.batch.PoleAvoidanceBatch`: no logic of its own beyond
Gymnasium's single-environment conventions; the options it shares with the vector env (reward
horizon, normalisation, rendering) are applied by :class:`usvsim.task.options.EnvLayer`.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from usvsim.task.batch import ActionKind, PoleAvoidanceBatch, observation_rows
from usvsim.task.horizon import RewardHorizon
from usvsim.task.observations import ObservationKind
from usvsim.task.options import EnvLayer, EnvOptions
from usvsim.task.render import RENDER_MODES, RenderConfig
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

    With ``normalize_observation=True`` the positional observation is standardised
    (:data:`usvsim.task.observations.POSITIONAL_STANDARDIZATION`, about unit spread; the
    space's bounds follow); radar images stay ``uint8``.

    ## Rewards
    ``r = r_pole + r_goal`` from the TRUE distances at the end of the decision period
    (:class:`usvsim.task.reward.GaussianReward`, pluggable); both terms in ``info``. With
    d_pole, d_goal the distances (m) to the pole and to the goal (Vedeler 2019, the forms of
    :mod:`usvsim.task.reward`)::

        r_pole = -2 · exp(-½ (d_pole / 5 m)²)          ∈ (-2, 0)
        r_goal = -1 + exp(-½ (d_goal / 100 m)²)        ∈ (-1, 0)

    ``reward_horizon="fixed"`` adds, on a terminating step, the discounted reward of staying
    there until the time limit (γ = ``gamma``), and reports leaving the area as ``terminated``:
    train with it, since every reward is negative and otherwise ramming the pole is the
    cheapest way to end an episode (:mod:`usvsim.task.horizon`). Default ``"episode"``.

    ## Starting State
    Drawn by :func:`usvsim.task.scenario.draw_episode` from the env's generator, or given:
    ``reset(options={"episode": EpisodeSpec(...)})``.

    ## Episode End
    From the TRUE position, checked at every 0.1 s plant step:
    ``terminated`` on reaching the goal (≤ 10 m) or a collision (closer than pole radius + half
    beam); ``truncated`` on the time limit (150 s) or leaving the area (> 250 m from the pole).
    ``info["is_success"]``: goal reached and never closer than 10 m to the pole.

    ## Rendering
    ``render_mode="rgb_array"``: ``render()`` returns a ``(400, 400, 3) uint8`` top view (boat
    at its true heading, pole with its safety circle, goal, trail, radar inset for radar
    observations; :mod:`usvsim.task.render`). ``"human"``: the same in a matplotlib window,
    shown at every reset and step. ``metadata["render_fps"]`` = 5 (one frame per 2 s
    decision: 10× real time).

    ## Arguments
    ``observation``, ``action``, ``render_mode``, ``reward_horizon`` (``"episode"`` |
    ``"fixed"``), ``gamma`` (0.99), ``normalize_observation`` (False), ``render_config``
    (:class:`usvsim.task.render.RenderConfig`), and the keyword arguments of
    :class:`usvsim.task.batch.PoleAvoidanceBatch` (``scenario``, ``reward``, ``radar``, ``nav``,
    ``plant``, ``vessel``, ``autopilot``, ``backend``).
    """

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 5}  # noqa: RUF012

    def __init__(
        self,
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
        self.sim = PoleAvoidanceBatch(1, observation=observation, action=action, **kwargs)
        self.layer = EnvLayer(self.sim, options)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": options.render.fps}
        self.observation_space = self.layer.single_observation_space
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
        obs = self.layer.started(np.zeros(1, dtype=np.intp), self.sim.reset(None, [spec]))
        self._done = False
        if self.render_mode == "human":
            self.render()
        info = {"pole_ne": self.sim.pole_ne[0].copy(), "goal_ne": self.sim.goal_ne[0].copy()}
        return observation_rows(obs, 0), info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._done:
            raise RuntimeError("the episode has ended: call reset() before step()")
        a = np.asarray(action)
        if a.shape != self.action_space.shape:
            raise ValueError(
                f"action must have shape {self.action_space.shape} for {self.action_space}, got "
                f"{a.shape}"
            )
        res = self.sim.step(a[None])
        info = {k: v[0].item() for k, v in res.info_arrays().items()}
        reward, terminated_n, truncated_n = self.layer.stepped(res)
        terminated, truncated = bool(terminated_n[0]), bool(truncated_n[0])
        self._done = terminated or truncated
        obs = observation_rows(self.layer.observation(res.observation), 0)
        if self.render_mode == "human":
            self.render()
        return obs, float(reward[0]), terminated, truncated, info

    def render(self) -> Any:
        """The current top view: ``(H, W, 3) uint8`` for ``"rgb_array"``, ``None`` for
        ``"human"`` (shown in a window); ``RuntimeError`` without a render mode."""
        frame = self.layer.frames()[0]
        if self.render_mode == "human":
            self.layer.show(frame)
            return None
        return frame

    def close(self) -> None:
        self.layer.close()
        super().close()
