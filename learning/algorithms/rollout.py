"""Collect on-policy batches from a ``gymnasium.vector.VectorEnv`` of N environments.

One policy call per step serves all N environments. Both of gymnasium 1.x's autoreset modes are
handled, so that every stored transition (s_t, a_t, r_t, s'_t) is a real one:

- ``NEXT_STEP`` (``SyncVectorEnv``'s default): the step that ends an episode returns its final
  observation as the next observation; the *following* step of that env ignores its action and
  only resets (reward 0, not done). That reset step is stored with ``valid = False`` and left
  out of the loss; its observation (the final one) still gives V(s'_t) for the step before it.
- ``SAME_STEP`` (:class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`): the ending step returns
  the new episode's first observation and puts the final one in ``info["final_obs"]`` (masked by
  ``info["_final_obs"]``); it is kept in :attr:`RolloutBatch.final_obs` for the bootstrap.

Shapes (T steps, N envs, F episodes ended by a SAME_STEP autoreset):

==================  ===================  ==========================================
field               shape                meaning
==================  ===================  ==========================================
obs                 (T, N, ...)          raw s_t (array, or dict of arrays)
actions             (T, N, A) / (T, N)   sampled actions (Box: before clipping)
log_probs           (T, N)               log π_old(a_t | s_t) at collection time
rewards             (T, N)               r_t
terminated          (T, N)               the episode ended in an absorbing state
truncated           (T, N)               the episode was cut (time limit)
valid               (T, N)               False for NEXT_STEP reset steps
last_obs            (N, ...)             s_T, to bootstrap the last step
final_obs           (F, ...)             final observations (SAME_STEP)
final_index         (F, 2)               their (t, n)
values              (T, N)               V(s_t), set by :func:`attach_values`
next_values         (T, N)               V(s'_t), set by :func:`attach_values`
info[key]           (T, N)               boolean ``info[key]`` per step (``info_keys``)
aux[key]            (T, N, ...)          ``info[key]`` describing s_t (``obs_info_keys``)
==================  ===================  ==========================================

``obs_info_keys`` name ``info`` arrays (N, ...) that describe the observation returned with
them (from ``reset`` and every ``step``, after a SAME_STEP autoreset the new episode's), e.g. the
open-water env's ``info["observation_scene"]``: what an asymmetric learner (a GAIL
discriminator that sees the true scene while the policy sees the radar) reads beside s_t.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from numpy.typing import NDArray

__all__ = [
    "NonFiniteError",
    "RolloutBatch",
    "RolloutCollector",
    "attach_values",
    "concat_obs",
    "flatten_obs",
]

Obs = NDArray[Any] | dict[str, NDArray[Any]]
ActFn = Callable[[Obs], tuple[NDArray[Any], NDArray[np.float32]]]
ValueFn = Callable[[Obs], NDArray[np.float32]]


class NonFiniteError(FloatingPointError):
    """A NaN or infinity where a finite number is required (observation, reward, loss)."""


def _map(obs: Obs, fn: Callable[[NDArray[Any]], NDArray[Any]]) -> Obs:
    return {k: fn(v) for k, v in obs.items()} if isinstance(obs, dict) else fn(obs)


def flatten_obs(obs: Obs, lead: int) -> Obs:
    """Merge the first ``lead`` axes of every part into one: (T, N, ...) → (T·N, ...)."""
    return _map(obs, lambda a: a.reshape((-1, *a.shape[lead:])))


def concat_obs(parts: list[Obs]) -> Obs:
    """Concatenate batches of observations along axis 0."""
    if isinstance(parts[0], dict):
        return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return np.concatenate(parts)  # type: ignore[arg-type]


def check_finite(obs: Obs, what: str) -> None:
    """Raise :class:`NonFiniteError` if any float part of ``obs`` holds NaN or ±inf."""
    arrays = obs.values() if isinstance(obs, dict) else [obs]
    for a in arrays:
        if np.issubdtype(a.dtype, np.floating) and not np.isfinite(a).all():
            raise NonFiniteError(f"non-finite value in {what}")


@dataclass
class RolloutBatch:
    """T steps of N environments (see the module table)."""

    obs: Obs
    actions: NDArray[Any]
    log_probs: NDArray[np.float32]
    rewards: NDArray[np.float32]
    terminated: NDArray[np.bool_]
    truncated: NDArray[np.bool_]
    valid: NDArray[np.bool_]
    last_obs: Obs
    final_obs: Obs | None
    final_index: NDArray[np.intp]
    episode_returns: list[float] = field(default_factory=list)
    episode_lengths: list[int] = field(default_factory=list)
    values: NDArray[np.float32] | None = None
    next_values: NDArray[np.float32] | None = None
    info: dict[str, NDArray[np.bool_]] = field(default_factory=dict)  # (T, N) per info key
    aux: dict[str, NDArray[Any]] = field(default_factory=dict)  # (T, N, ...) per obs_info key

    @property
    def episode_end(self) -> NDArray[np.bool_]:
        return self.terminated | self.truncated


def attach_values(
    batch: RolloutBatch, value_fn: ValueFn, obs_values: NDArray[np.float32] | None = None
) -> None:
    """Set ``batch.values`` = V(s_t) and ``batch.next_values`` = V(s'_t) in one ``value_fn`` call.

    s'_t is s_{t+1} (or ``last_obs`` for t = T − 1) except where a SAME_STEP autoreset replaced
    it: there it is the stored final observation. (With NEXT_STEP the final observation *is*
    s_{t+1}.) ``value_fn`` maps raw observations (M, ...) to (M,). ``obs_values``, when the
    caller has them, are V(s_t) of ``flatten_obs(batch.obs, 2)`` (T·N,); ``value_fn`` then
    evaluates only ``last_obs`` and the final observations.
    """
    T, N = batch.rewards.shape
    parts = [batch.last_obs]
    if batch.final_obs is not None:
        parts.append(batch.final_obs)
    if obs_values is None:
        parts.insert(0, flatten_obs(batch.obs, 2))
    v = np.asarray(value_fn(concat_obs(parts)), dtype=np.float32)
    if obs_values is not None:
        v = np.concatenate([np.asarray(obs_values, dtype=np.float32), v])
    values = v[: T * N].reshape(T, N)
    seq = np.concatenate([values, v[T * N : T * N + N][None]], axis=0)
    next_values = seq[1:].copy()
    if len(batch.final_index):
        t, n = batch.final_index.T
        next_values[t, n] = v[T * N + N :]
    batch.values, batch.next_values = values, next_values


class RolloutCollector:
    """Steps a vector env with a batched policy; keeps episodes running across batches.

    ``act(obs)`` gets the raw observations of all N envs and returns the actions to store (Box:
    unclipped samples; they are clipped to the bounds only on the way to the env) and their
    log-probabilities (N,). ``seed`` seeds the env's first reset. ``info_keys`` name boolean
    per-env ``info`` arrays to keep in :attr:`RolloutBatch.info` (False where absent);
    ``obs_info_keys`` name ``info`` arrays that describe the returned observation, kept in
    :attr:`RolloutBatch.aux` beside s_t (the env must give them at reset and at every step:
    ``KeyError`` naming the key otherwise).
    """

    def __init__(
        self,
        env: VectorEnv,
        seed: int | None = None,
        info_keys: tuple[str, ...] = (),
        obs_info_keys: tuple[str, ...] = (),
    ) -> None:
        self.info_keys, self.obs_info_keys = info_keys, obs_info_keys
        mode = env.metadata.get("autoreset_mode", AutoresetMode.NEXT_STEP)
        if mode not in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
            raise ValueError(f"autoreset mode {mode} is not supported (NEXT_STEP or SAME_STEP)")
        self.env, self.same_step = env, mode == AutoresetMode.SAME_STEP
        self.n = env.num_envs
        self.obs_space, self.act_space = env.single_observation_space, env.single_action_space
        self.obs, info = env.reset(seed=seed)
        check_finite(self.obs, "the observations after reset")
        self._obs_info = self._observation_info(info, "reset")
        self._reset_pending = np.zeros(self.n, dtype=bool)  # NEXT_STEP: next step only resets
        self._ep_return = np.zeros(self.n)
        self._ep_length = np.zeros(self.n, dtype=np.int64)

    def _observation_info(self, info: dict[str, Any], where: str) -> dict[str, NDArray[Any]]:
        """Copies of the ``obs_info_keys`` arrays of ``info`` (``KeyError`` naming one absent)."""
        missing = [k for k in self.obs_info_keys if k not in info]
        if missing:
            raise KeyError(f"the env's info at {where} has no {missing[0]!r} (obs_info_keys)")
        return {k: np.array(info[k]) for k in self.obs_info_keys}

    def _buffer(self, T: int) -> Obs:
        def empty(space: spaces.Space) -> NDArray[Any]:
            return np.empty((T, self.n, *space.shape), dtype=space.dtype)  # type: ignore[misc]

        if isinstance(self.obs_space, spaces.Dict):
            return {k: empty(s) for k, s in self.obs_space.spaces.items()}
        return empty(self.obs_space)

    def _env_actions(self, actions: NDArray[Any]) -> NDArray[Any]:
        if isinstance(self.act_space, spaces.Box):
            low, high = self.act_space.low, self.act_space.high
            return np.clip(actions, low, high).astype(self.act_space.dtype)
        return actions

    def collect(self, act: ActFn, n_steps: int) -> RolloutBatch:
        """Run ``n_steps`` steps of all N envs; T·N stored transitions."""
        T, N = n_steps, self.n
        obs_buf = self._buffer(T)
        rewards = np.zeros((T, N), dtype=np.float32)
        terminated = np.zeros((T, N), dtype=bool)
        truncated = np.zeros((T, N), dtype=bool)
        valid = np.ones((T, N), dtype=bool)
        log_probs = np.zeros((T, N), dtype=np.float32)
        actions_buf: NDArray[Any] | None = None
        finals: list[Obs] = []
        final_index: list[tuple[int, int]] = []
        returns: list[float] = []
        lengths: list[int] = []
        infos = {k: np.zeros((T, N), dtype=bool) for k in self.info_keys}
        aux = {k: np.empty((T, *v.shape), dtype=v.dtype) for k, v in self._obs_info.items()}
        for t in range(T):
            for k, v in self._obs_info.items():
                aux[k][t] = v
            if isinstance(obs_buf, dict):
                for k in obs_buf:
                    obs_buf[k][t] = self.obs[k]
            else:
                obs_buf[t] = self.obs
            actions, logp = act(self.obs)
            if actions_buf is None:
                actions_buf = np.zeros((T, *actions.shape), dtype=actions.dtype)
            actions_buf[t], log_probs[t] = actions, logp
            valid[t] = ~self._reset_pending
            obs, reward, term, trunc, info = self.env.step(self._env_actions(actions))
            check_finite(obs, f"the observations at step {t}")
            reward = np.asarray(reward, dtype=np.float32)
            if not np.isfinite(reward).all():
                raise NonFiniteError(f"non-finite reward at step {t}")
            rewards[t], terminated[t], truncated[t] = reward, term, trunc
            for k in self.info_keys:
                if k in info:
                    infos[k][t] = np.asarray(info[k], dtype=bool)
            done = np.asarray(term) | np.asarray(trunc)
            self._ep_return += np.where(valid[t], reward, 0.0)
            self._ep_length += valid[t]
            for n in np.flatnonzero(done):
                returns.append(float(self._ep_return[n]))
                lengths.append(int(self._ep_length[n]))
                self._ep_return[n], self._ep_length[n] = 0.0, 0
                if self.same_step:
                    finals.append(_map(info["final_obs"][n], lambda a: np.asarray(a)[None]))
                    check_finite(finals[-1], f"the final observation at step {t}")
                    final_index.append((t, int(n)))
            if not self.same_step:
                self._reset_pending = done
            self.obs = obs
            if self.obs_info_keys:
                self._obs_info = self._observation_info(info, f"step {t}")
        assert actions_buf is not None
        return RolloutBatch(
            obs=obs_buf,
            actions=actions_buf,
            log_probs=log_probs,
            rewards=rewards,
            terminated=terminated,
            truncated=truncated,
            valid=valid,
            last_obs=_map(self.obs, np.copy),
            final_obs=concat_obs(finals) if finals else None,
            final_index=np.array(final_index, dtype=np.intp).reshape(-1, 2),
            episode_returns=returns,
            episode_lengths=lengths,
            info=infos,
            aux=aux,
        )
