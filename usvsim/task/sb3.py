"""Stable-Baselines3 adapter: the native batch of N boats as an SB3 ``VecEnv``.

``pip install "usvsim[sb3]"``; this is the only module that imports ``stable_baselines3``.
SB3 does not take a Gymnasium ``VectorEnv`` ("not a Gymnasium environment"); wrapping N single
envs in its ``DummyVecEnv`` works (``make_vec_env("usvsim/PoleAvoidance-v0", n_envs=N)``) but
steps the plant once per boat. :class:`SB3VecEnv` presents
:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv` (one compiled plant call for all boats)
with SB3's conventions: ``dones = terminated | truncated``; for a finished boat
``infos[i]["terminal_observation"]`` (its last observation; ``obs`` already holds the next
episode's first), ``infos[i]["TimeLimit.truncated"]`` (truncated and not terminated, so SB3
bootstraps from it) and ``infos[i]["episode"]`` (return, length, time, as SB3's ``Monitor``
writes it, for its ``rollout/ep_rew_mean`` log). ``infos[i]["is_success"]`` is the task's.

Example (SB3 PPO with its default hyper-parameters, ``benchmarks/train_sb3.py``)::

    from stable_baselines3 import PPO
    from usvsim.task.sb3 import make_sb3_vec_env

    env = make_sb3_vec_env(8, seed=0)   # fixed reward horizon, normalised observation
    PPO("MlpPolicy", env, seed=0).learn(200_000)

:func:`make_sb3_vec_env` defaults to what training needs: ``reward_horizon="fixed"``
(:mod:`usvsim.task.horizon`; with the per-episode reward SB3 PPO learns to ram the pole) with
SB3's default γ = 0.99, and ``normalize_observation=True``
(:mod:`usvsim.task.options`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import VecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnvIndices

from usvsim.task.batch import ActionKind
from usvsim.task.horizon import RewardHorizon
from usvsim.task.observations import ObservationKind
from usvsim.task.options import normalized_observation
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

__all__ = ["SB3Helmsman", "SB3VecEnv", "make_sb3_vec_env"]


class SB3VecEnv(VecEnv):
    """A :class:`PoleAvoidanceVectorEnv` as a Stable-Baselines3 ``VecEnv`` (module docstring).

    ``seed(s)`` before ``reset()`` seeds boat i with ``s + i`` (SB3's convention, which is also
    the vector env's); ``reset_infos[i]`` holds boat i's pole and goal positions.
    """

    def __init__(self, env: PoleAvoidanceVectorEnv) -> None:
        if not isinstance(env, PoleAvoidanceVectorEnv):
            raise ValueError(f"SB3VecEnv wraps a PoleAvoidanceVectorEnv, got {type(env).__name__}")
        self.env = env
        super().__init__(env.num_envs, env.single_observation_space, env.single_action_space)
        self._actions: Any = None
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._t0 = time.perf_counter()

    def reset(self) -> Any:
        seeds = self._seeds
        if all(s is None for s in seeds):
            seed: list[int] | None = None
        elif any(s is None for s in seeds):
            raise ValueError(f"seed every boat or none, got seeds {seeds}")
        else:
            seed = [int(s) for s in seeds if s is not None]
        options: dict[str, Any] | None = None
        if any(self._options):
            if not all("episode" in o for o in self._options):
                raise ValueError("reset options: give every boat an 'episode' (EpisodeSpec)")
            options = {"episodes": [o["episode"] for o in self._options]}
        obs, info = self.env.reset(seed=seed, options=options)
        self.reset_infos = [
            {"pole_ne": info["pole_ne"][i], "goal_ne": info["goal_ne"][i]}
            for i in range(self.num_envs)
        ]
        self._reset_seeds()
        self._reset_options()
        self._returns[:] = 0.0
        self._lengths[:] = 0
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, terminated, truncated, info = self.env.step(self._actions)
        done = terminated | truncated
        self._returns += reward
        self._lengths += 1
        keys = [k for k in info if not k.startswith("_") and k not in ("final_obs", "final_info")]
        infos: list[dict[str, Any]] = [
            {k: info[k][i].item() for k in keys} for i in range(self.num_envs)
        ]
        for i in np.flatnonzero(done):
            infos[i]["terminal_observation"] = info["final_obs"][i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            infos[i]["episode"] = {
                "r": float(self._returns[i]),
                "l": int(self._lengths[i]),
                "t": round(time.perf_counter() - self._t0, 6),
            }
        self._returns[done] = 0.0
        self._lengths[done] = 0
        return obs, np.asarray(reward, dtype=np.float32), done, infos

    def close(self) -> None:
        self.env.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        if self.env.render_mode != "rgb_array":
            raise RuntimeError("get_images needs render_mode='rgb_array' at construction")
        frames = self.env.render()
        assert frames is not None
        return list(frames)

    def _indices(self, indices: VecEnvIndices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, (int, np.integer)):
            return [int(indices)]
        return [int(i) for i in indices]

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The vector env's attribute, once per requested boat (they share one object)."""
        value = getattr(self.env, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        if indices is not None and len(self._indices(indices)) != self.num_envs:
            raise ValueError("the boats share one environment: set attributes for all of them")
        setattr(self.env, attr_name, value)

    def env_method(
        self,
        method_name: str,
        *method_args: Any,
        indices: VecEnvIndices = None,
        **method_kwargs: Any,
    ) -> list[Any]:
        """Calls the vector env's method once; its result is repeated per requested boat."""
        result = getattr(self.env, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._indices(indices)]

    def env_is_wrapped(
        self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None
    ) -> list[bool]:
        return [False for _ in self._indices(indices)]


def make_sb3_vec_env(
    num_envs: int = 8,
    observation: ObservationKind = "positional",
    action: ActionKind = "gaussian",
    *,
    reward_horizon: RewardHorizon = "fixed",
    gamma: float = 0.99,
    normalize_observation: bool = True,
    render_mode: str | None = None,
    seed: int | None = None,
    **kwargs: Any,
) -> SB3VecEnv:
    """``num_envs`` boats as an SB3 ``VecEnv``, set up for training (module docstring).

    ``gamma`` must be the trainer's discount (SB3's default 0.99); ``seed`` seeds the first
    reset (boat i: ``seed + i``); further keyword arguments go to
    :class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`.
    """
    env = SB3VecEnv(
        PoleAvoidanceVectorEnv(
            num_envs,
            observation=observation,
            action=action,
            render_mode=render_mode,
            reward_horizon=reward_horizon,
            gamma=gamma,
            normalize_observation=normalize_observation,
            **kwargs,
        )
    )
    if seed is not None:  # SB3's seed(None) would draw a seed from NumPy's global generator
        env.seed(seed)
    return env


class SB3Helmsman:
    """A trained SB3 model as a helmsman (:class:`usvsim.helm.protocol.Helmsman`): its
    deterministic action for the environment's raw batched observation, normalised first as
    during training (``normalize_observation``), e.g. for
    :func:`usvsim.evaluation.episodes.evaluate`.
    """

    def __init__(
        self,
        model: Any,
        observation: ObservationKind = "positional",
        normalize_observation: bool = True,
    ) -> None:
        self.model, self.observation, self.normalize = model, observation, normalize_observation

    def reset(self, n_boats: int) -> None:
        self._n = n_boats

    def act(self, observation: Any) -> np.ndarray:
        if self.normalize:
            observation = normalized_observation(self.observation, observation)
        action, _ = self.model.predict(observation, deterministic=True)
        return np.asarray(action)
