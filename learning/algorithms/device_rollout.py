"""On-policy batches collected on a torch device: env, policy, buffers and GAE never leave it.

The twin of :mod:`learning.algorithms.rollout` and :mod:`learning.algorithms.gae` for an env
whose ``step`` takes and returns tensors on its device
(:class:`usvsim.task.torch_env.TorchPoleAvoidanceEnv` or
:class:`usvsim.task.torch_openwater.TorchOpenWaterEnv`: autoreset ``SAME_STEP``, the final
observation of every boat in ``info["final_obs"]``). A step of
:meth:`DeviceRolloutCollector.collect` normalises the observation (:class:`DeviceNormalizer`:
the agent's normaliser with its statistics fixed within an iteration, copied to the device once),
samples the policy with a generator on the device, steps the env, applies the study's fixed
reward horizon (:func:`fixed_horizon`; an env built with ``reward_horizon="fixed"`` applies its
own, each episode's time limit against K_ref) and writes into preallocated tensors; nothing is
read back to the host (tested: every way to read a tensor raises during a rollout).

Shapes (T steps, N envs, F observation features):

=================  ============  ============================================================
field              shape         meaning
=================  ============  ============================================================
obs                (T, N, F)     raw s_t
next_obs           (T, N, F)     raw s'_t: s_{t+1}, or the final observation where the
                                 episode ended at t (so V(s'_t) needs no index lists)
actions            (T, N[, A])   sampled actions (Box: before clipping)
log_probs          (T, N)        log π_old(a_t | s_t)
rewards            (T, N)        r_t after the fixed horizon (float32)
terminated         (T, N)        absorbing end (goal, collision, left the area)
truncated          (T, N)        time limit
episode_sums       (3,)          episodes ended, their returns' sum, their lengths' sum
info[key]          (T, N)        boolean ``info[key]`` per step, for the ``info_keys`` asked
                                 (GAIL: how each episode ended)
aux[key]           (T, N, ...)   ``info[key]`` describing s_t, for the ``obs_info_keys`` asked
                                 (an asymmetric GAIL's discriminator view)
=================  ============  ============================================================

Every transition is valid (``SAME_STEP``: no reset-only steps).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import torch
from torch import Tensor

from learning.algorithms.networks import TensorObs

__all__ = [
    "DeviceBatch",
    "DeviceNormalizer",
    "DeviceRolloutCollector",
    "device_gae",
    "fixed_horizon",
    "flat_rows",
    "normalize",
]


def fixed_horizon(
    gamma: float,
    max_decisions: int,
    decision_period_s: float,
    reward: Tensor,
    terminated: Tensor,
    truncated: Tensor,
    out_of_area: Tensor,
    time_s: Tensor,
) -> tuple[Tensor, Tensor, Tensor]:
    """:func:`usvsim.task.horizon.apply_reward_horizon` with ``"fixed"``, on tensors (N,).

    Leaving the area becomes a termination; a terminating step's reward r becomes
    r · (1 + γ (1 − γ^m) / (1 − γ)), m the decisions left until the time limit. No branch on
    a tensor's value (no host read)."""
    left = out_of_area & truncated
    terminated, truncated = terminated | left, truncated & ~left
    decisions = torch.round(time_s / decision_period_s)
    m = torch.clamp(max_decisions - decisions, min=0.0)
    factor = 1.0 + gamma * (1.0 - torch.pow(gamma, m)) / (1.0 - gamma)
    return torch.where(terminated, reward * factor, reward), terminated, truncated


def normalize(x: Tensor, mean: Tensor | None, std: Tensor | None, clip: float) -> Tensor:
    """:class:`learning.algorithms.normalization.ObservationNormalizer` of a vector part on
    tensors: clip((x − μ) / sqrt(σ² + ε), ±clip) in float64, as float32; ``mean`` None: the
    normaliser is disabled (x as float32)."""
    if mean is None or std is None:
        return x.to(torch.float32)
    return torch.clamp((x.to(torch.float64) - mean) / std, -clip, clip).to(torch.float32)


class DeviceNormalizer:
    """:class:`learning.algorithms.normalization.ObservationNormalizer` on a torch device, its
    statistics as they are now, part by part: an image (uint8) scaled by 1/255, a vector part
    ``running`` (:func:`normalize` with the running mean and variance), ``scene`` (the fixed
    constants of :func:`usvsim.task.observations.standardize_scene`, empty slots all zeros, then
    clipped) or disabled (the raw values as float32). Calling it maps raw rows (..., F), or a
    dict of such parts, to float32, the NumPy normaliser's numbers bit for bit (tested)."""

    def __init__(self, normalizer: Any, device: torch.device) -> None:
        self.clip = float(normalizer.clip)
        self.kind = "scene" if normalizer.fixed else "running" if normalizer.enabled else "off"
        self.stats: dict[str, tuple[Tensor, Tensor]] = {}  # part → μ, sqrt(σ² + ε)
        self._scene: tuple[Tensor, Tensor, tuple[int, int]] | None = None
        if self.kind == "scene":
            from usvsim.task.observations import SCENE_FEATURES, SCENE_K, SCENE_STANDARDIZATION

            table = SCENE_STANDARDIZATION
            self._scene = (
                torch.tensor(table.mean, dtype=torch.float64, device=device),
                torch.tensor(table.std, dtype=torch.float64, device=device),
                (SCENE_K, SCENE_FEATURES),
            )
        elif self.kind == "running":
            for key, stats in normalizer.stats.items():
                mean = torch.as_tensor(stats.mean, dtype=torch.float64, device=device)
                var = torch.as_tensor(stats.var, dtype=torch.float64, device=device)
                self.stats[key] = (mean, torch.sqrt(var + normalizer.eps))
        self._inv255 = torch.tensor(1.0 / 255.0, dtype=torch.float32, device=device)

    def part(self, key: str, x: Tensor) -> Tensor:
        """One part (``""`` for a plain vector observation)."""
        if x.dtype == torch.uint8:  # an image: x · float32(1/255), as the NumPy normaliser
            return x.to(torch.float32) * self._inv255
        if self._scene is not None:
            mean, std, slots = self._scene
            z = ((x.to(torch.float64) - mean) / std).to(torch.float32)
            shape = (*x.shape[:-1], *slots)
            valid = x[..., 4:].reshape(shape)[..., 5:6] > 0.5
            z = torch.cat([z[..., :4], (z[..., 4:].reshape(shape) * valid).flatten(-2)], -1)
            return torch.clamp(z, -self.clip, self.clip)
        mean_std = self.stats.get(key)
        if mean_std is None:
            return x.to(torch.float32)
        return normalize(x, *mean_std, self.clip)

    def __call__(self, obs: TensorObs) -> TensorObs:
        if isinstance(obs, dict):
            return {key: self.part(key, x) for key, x in obs.items()}
        return self.part("", obs)


def _parts(obs: TensorObs) -> dict[str, Tensor]:
    return obs if isinstance(obs, dict) else {"": obs}


def flat_rows(obs: TensorObs) -> TensorObs:
    """(T, N, ...) → (T·N, ...), part by part."""
    if isinstance(obs, dict):
        return {key: x.reshape(-1, *x.shape[2:]) for key, x in obs.items()}
    return obs.reshape(-1, *obs.shape[2:])


def device_gae(
    rewards: Tensor,
    values: Tensor,
    next_values: Tensor,
    terminated: Tensor,
    episode_end: Tensor,
    gamma: float,
    lam: float,
) -> tuple[Tensor, Tensor]:
    """:func:`learning.algorithms.gae.gae` on tensors (T, N): advantages and λ-returns, float32,
    float64 inside (Schulman et al. 2016, Eq. 16; terminated and truncated kept apart)."""
    r, v, nv = (a.to(torch.float64) for a in (rewards, values, next_values))
    delta = r + gamma * (~terminated).to(torch.float64) * nv - v
    carry = gamma * lam * (~episode_end).to(torch.float64)
    adv = torch.empty_like(delta)
    running = torch.zeros_like(delta[0])
    for t in range(delta.shape[0] - 1, -1, -1):  # over time, not over boats
        running = delta[t] + carry[t] * running
        adv[t] = running
    return adv.to(torch.float32), (adv + v).to(torch.float32)


@dataclass
class DeviceBatch:
    """T steps of N envs on the device (module table)."""

    obs: TensorObs
    next_obs: TensorObs
    actions: Tensor
    log_probs: Tensor
    rewards: Tensor
    terminated: Tensor
    truncated: Tensor
    episode_sums: Tensor
    info: dict[str, Tensor] = field(default_factory=dict)
    aux: dict[str, Tensor] = field(default_factory=dict)

    @property
    def episode_end(self) -> Tensor:
        return self.terminated | self.truncated


class DeviceRolloutCollector:
    """Steps a torch vector env with a policy on the same device; episodes run across batches.

    ``env``: ``reset(seed=)`` and ``step(actions)`` on tensors (``SAME_STEP``, ``final_obs``,
    ``out_of_area`` and ``time_s`` in ``info``), ``scenario`` (``max_decisions``,
    ``decision_period_s``), ``device``, ``num_envs``. ``gamma``: the trainer's discount, for
    the fixed horizon. ``action_bounds`` (low, high) clip Box actions on the way to the env.
    ``info_keys``: boolean ``info`` entries kept per step (:attr:`DeviceBatch.info`);
    ``obs_info_keys``: ``info`` entries describing the observation returned with them, at reset
    and every step (:attr:`DeviceBatch.aux`).
    ``env_reward`` False: the env's rewards are not the trainer's (GAIL), so no fixed horizon
    is added and the env's own terminations stand, as on the CPU path.
    """

    def __init__(
        self,
        env: Any,
        gamma: float,
        seed: int,
        action_bounds: tuple[float, float] | None = None,
        info_keys: tuple[str, ...] = (),
        env_reward: bool = True,
        obs_info_keys: tuple[str, ...] = (),
    ) -> None:
        self.env, self.gamma, self.n = env, gamma, env.num_envs
        self.info_keys, self.obs_info_keys = info_keys, obs_info_keys
        self.device = torch.device(env.device)
        self.bounds = action_bounds
        self.generator = torch.Generator(device=self.device).manual_seed(seed + 2)
        obs, info = env.reset(seed=seed)
        self.aux = self._aux(info)
        # an env on the fixed horizon applies it itself (the open-water env: each episode's own
        # time limit); the study's env returns the episode's rewards, and the collector adds it
        self._own_horizon = env_reward and getattr(env, "reward_horizon", "episode") != "fixed"
        self.obs = obs
        self._ep_return = torch.zeros(self.n, dtype=torch.float64, device=self.device)
        self._ep_length = torch.zeros(self.n, dtype=torch.float64, device=self.device)

    @torch.no_grad()
    def collect(
        self,
        policy: torch.nn.Module,
        normalise: Callable[[TensorObs], TensorObs],
        n_steps: int,
    ) -> DeviceBatch:
        """Run ``n_steps`` steps of all N envs with ``policy`` on observations normalised by
        ``normalise`` (a :class:`DeviceNormalizer`: raw rows → float32); T·N transitions."""
        T, N, dev = n_steps, self.n, self.device
        sc = self.env.scenario
        obs_buf = {k: x.new_empty((T, *x.shape)) for k, x in _parts(self.obs).items()}
        next_buf = {k: torch.empty_like(x) for k, x in obs_buf.items()}
        log_probs = torch.empty((T, N), dtype=torch.float32, device=dev)
        rewards = torch.empty((T, N), dtype=torch.float32, device=dev)
        terminated = torch.empty((T, N), dtype=torch.bool, device=dev)
        truncated = torch.empty((T, N), dtype=torch.bool, device=dev)
        sums = torch.zeros(3, dtype=torch.float64, device=dev)
        info_buf = {k: torch.empty((T, N), dtype=torch.bool, device=dev) for k in self.info_keys}
        aux_buf = {k: x.new_empty((T, *x.shape)) for k, x in self.aux.items()}
        actions_buf: Tensor | None = None
        for t in range(T):
            for key, x in _parts(self.obs).items():
                obs_buf[key][t] = x
            for key, x in self.aux.items():
                aux_buf[key][t] = x
            dist = policy(normalise(self.obs))
            actions = dist.sample(self.generator)
            if actions_buf is None:
                actions_buf = torch.empty((T, *actions.shape), dtype=actions.dtype, device=dev)
            actions_buf[t], log_probs[t] = actions, dist.log_prob(actions)
            env_actions = actions if self.bounds is None else actions.clamp(*self.bounds)
            obs, reward, term, trunc, info = self.env.step(env_actions)
            if self._own_horizon:
                args = (sc.max_decisions, sc.decision_period_s, reward, term, trunc)
                reward, term, trunc = fixed_horizon(
                    self.gamma, *args, info["out_of_area"], info["time_s"]
                )
            done = term | trunc
            rewards[t], terminated[t], truncated[t] = reward, term, trunc
            for key, buf in info_buf.items():
                buf[t] = info[key]
            final = info["final_obs"]
            for key, x in _parts(obs).items():
                last = _parts(final)[key]
                mask = done.view(-1, *([1] * (x.ndim - 1)))
                next_buf[key][t] = torch.where(mask, last, x)
            self._ep_return += reward
            self._ep_length += 1.0
            d = done.to(torch.float64)
            sums += torch.stack([d.sum(), (d * self._ep_return).sum(), (d * self._ep_length).sum()])
            self._ep_return *= 1.0 - d
            self._ep_length *= 1.0 - d
            self.obs, self.aux = obs, self._aux(info)
        assert actions_buf is not None
        if isinstance(self.obs, dict):
            obs_out: TensorObs = dict(obs_buf)
            next_out: TensorObs = dict(next_buf)
        else:
            obs_out, next_out = obs_buf[""], next_buf[""]
        return DeviceBatch(obs_out, next_out, actions_buf, log_probs, rewards, terminated,
                           truncated, sums, info_buf, aux_buf)  # fmt: skip

    def _aux(self, info: dict[str, Any]) -> dict[str, Tensor]:
        """The ``obs_info_keys`` entries of ``info`` (``KeyError`` naming one absent)."""
        missing = [k for k in self.obs_info_keys if k not in info]
        if missing:
            raise KeyError(f"the env's info has no {missing[0]!r} (obs_info_keys)")
        return {k: info[k] for k in self.obs_info_keys}
