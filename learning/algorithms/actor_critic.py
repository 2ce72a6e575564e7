"""What every on-policy actor-critic agent shares: networks, acting, the training batch, saving.

:class:`ActorCritic` is the one base class of :class:`learning.algorithms.trpo.TRPOAgent` and
:class:`learning.algorithms.ppo.PPOAgent` (the split of Stable-Baselines3's
``ActorCriticPolicy`` / ``OnPolicyAlgorithm``, Raffin et al. 2021): it builds the policy, the
critic, the observation normaliser and the seeded generator; it acts; it turns a
:class:`RolloutBatch` into the checked tensors of one update (:meth:`ActorCritic.training_batch`:
GAE advantages and λ-returns, Schulman et al. 2016) and refreshes the statistics between
iterations (:meth:`ActorCritic.finish_update`); it saves and restores everything. A subclass
adds its optimisers (:meth:`ActorCritic.optimizers`) and writes ``update`` from the policy step
of its paper plus :func:`fit_critic`.

One iteration of a subclass's ``update``::

    tb    = self.training_batch(batch)              # checked; nothing has changed yet
    step  = <the algorithm's policy step>(self.policy, tb.obs, tb.actions, tb.advantages, ...)
    loss  = fit_critic(self.critic, <its Adam>, tb.obs, tb.returns, ...)
    self.finish_update(tb)                          # normaliser, BatchNorm, counters
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

import numpy as np
import torch
from gymnasium import spaces
from torch import Tensor

from learning.algorithms.base import Stopwatch, config_from_dict
from learning.algorithms.gae import gae
from learning.algorithms.networks import (
    Critic,
    TensorObs,
    make_critic,
    make_policy,
    obs_to_tensor,
    refresh_batchnorm,
    rows,
    space_from_spec,
    space_to_spec,
)
from learning.algorithms.normalization import ObservationNormalizer
from learning.algorithms.rollout import (
    NonFiniteError,
    Obs,
    RolloutBatch,
    attach_values,
    flatten_obs,
)

__all__ = ["ActorCritic", "TrainingBatch", "fit_critic"]

A = TypeVar("A", bound="ActorCritic")


@dataclass(frozen=True)
class TrainingBatch:
    """The valid transitions of one rollout as the update needs them (B valid rows).

    ``raw_obs`` as the environment gave them (they update the normaliser after the step);
    ``obs`` normalised tensors; ``advantages`` GAE(γ, λ) (B,), normalised when the config says
    so; ``returns`` the λ-returns (B,), the critic's targets.
    """

    raw_obs: Obs
    obs: TensorObs
    actions: Tensor
    advantages: Tensor
    returns: Tensor


def fit_critic(
    critic: Critic,
    optimizer: torch.optim.Optimizer,
    obs: TensorObs,
    returns: Tensor,
    epochs: int,
    minibatch: int,
    generator: torch.Generator,
) -> float:
    """Regress V_φ(s) on ``returns`` (B,) by Adam on shuffled minibatches; mean loss of the last
    epoch (mean squared error). Minibatches of one row are skipped (BatchNorm needs two)."""
    critic.train()
    B = returns.shape[0]
    losses: list[float] = []
    for _ in range(epochs):
        losses = []
        perm = torch.randperm(B, generator=generator)
        for start in range(0, B, minibatch):
            idx = perm[start : start + minibatch]
            if idx.numel() < 2:
                continue
            loss = (critic(rows(obs, idx)) - returns[idx]).pow(2).mean()
            if not torch.isfinite(loss):
                raise NonFiniteError("non-finite critic loss: optimizer step skipped")
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            optimizer.step()
            losses.append(float(loss.detach()))
    critic.eval()
    return float(np.mean(losses)) if losses else float("nan")


def _finite(raw_obs: Obs, obs: TensorObs) -> bool:
    """True if every normalised part of ``obs`` is finite. Parts of integer raw observations
    (images / 255) always are; a float part is, exactly when its float64 sum is (a NaN or ±inf
    anywhere makes the sum non-finite; float32 values cannot overflow it), a sum being ~10x
    cheaper than ``isfinite(x).all()``."""
    if isinstance(obs, dict):
        assert isinstance(raw_obs, dict)
        pairs = [(raw_obs[k], obs[k]) for k in obs]
    else:
        assert not isinstance(raw_obs, dict)
        pairs = [(raw_obs, obs)]
    return all(
        bool(torch.isfinite(t.sum(dtype=torch.float64)))
        for raw, t in pairs
        if not np.issubdtype(raw.dtype, np.integer)
    )


class ActorCritic:
    """Policy, critic, observation normaliser, random state and counters of one run.

    Subclasses set ``STATE_FORMAT`` (the ``state_dict``'s format tag), ``NAME`` (for messages)
    and ``config_type``, and build their optimisers after ``super().__init__``.
    """

    STATE_FORMAT: ClassVar[str]
    NAME: ClassVar[str]
    config_type: ClassVar[type[Any]]
    critic_optimizer: torch.optim.Optimizer  # built by the subclass

    def __init__(
        self, observation_space: spaces.Space, action_space: spaces.Space, config: Any
    ) -> None:
        self.config = config
        self.observation_space, self.action_space = observation_space, action_space
        with torch.random.fork_rng():  # initialise from the seed without touching global state
            torch.manual_seed(config.seed)
            self.policy = make_policy(observation_space, action_space, config.network)
            self.critic = make_critic(observation_space, config.network).eval()
        self.normalizer = ObservationNormalizer(
            observation_space,
            clip=config.obs_clip,
            enabled=config.normalize_observations,
            scaling=config.observation_scaling,
        )
        self.generator = torch.Generator().manual_seed(config.seed + 1)
        self.iteration = 0
        self.env_steps = 0
        self.info_keys: tuple[str, ...] = ()  # the update reads no env info

    def optimizers(self) -> dict[str, torch.optim.Optimizer]:
        """The subclass's optimisers by ``state_dict`` key (saved and restored with the agent)."""
        raise NotImplementedError

    # -- acting ----------------------------------------------------------------------------

    def policy_input(self, obs: Obs) -> TensorObs:
        """Raw observations → the normalised tensors the policy and critic take."""
        return obs_to_tensor(self.normalizer(obs))

    @torch.inference_mode()
    def sample(self, obs: Obs) -> tuple[np.ndarray, np.ndarray]:
        """Actions (unclipped) and their log-probabilities for a batch of raw observations."""
        dist = self.policy(self.policy_input(obs))
        actions = dist.sample(self.generator)
        return actions.numpy(), dist.log_prob(actions).numpy()

    @torch.inference_mode()
    def act(self, obs: Obs, deterministic: bool = True) -> np.ndarray:
        """Environment-ready actions (Box: clipped to the bounds) for raw observations (N, ...)."""
        dist = self.policy(self.policy_input(obs))
        actions = (dist.mode() if deterministic else dist.sample(self.generator)).numpy()
        if isinstance(self.action_space, spaces.Box):
            actions = np.clip(actions, self.action_space.low, self.action_space.high)
        return actions

    def values(self, obs: Obs, chunk: int = 4096) -> np.ndarray:
        """V(s) (M,) for raw observations (M, ...)."""
        return self.critic_values(self.policy_input(obs), chunk)

    @torch.inference_mode()
    def critic_values(self, t: TensorObs, chunk: int = 4096) -> np.ndarray:
        """V(s) (M,) for normalised tensor observations (M, ...), ``chunk`` rows at a time."""
        M = next(iter(t.values())).shape[0] if isinstance(t, dict) else t.shape[0]
        out = [self.critic(rows(t, slice(i, i + chunk))) for i in range(0, M, chunk)]
        return torch.cat(out).numpy()

    # -- learning --------------------------------------------------------------------------

    def training_batch(self, batch: RolloutBatch) -> TrainingBatch:
        """GAE advantages and λ-returns of ``batch`` as checked tensors of its valid rows.

        Raises :class:`NonFiniteError` on a non-finite observation, advantage or return, before
        any parameter or statistic changes.
        """
        cfg = self.config
        # the observations are normalised once, for V(s_t) and for the update
        raw_obs = flatten_obs(batch.obs, 2)
        obs = self.policy_input(raw_obs)
        attach_values(batch, self.values, self.critic_values(obs))
        assert batch.values is not None and batch.next_values is not None
        advantages, returns = gae(
            batch.rewards,
            batch.values,
            batch.next_values,
            batch.terminated,
            batch.episode_end,
            cfg.gamma,
            cfg.gae_lambda,
        )
        valid = batch.valid.reshape(-1)
        if not valid.all():
            raw_obs = (
                {k: v[valid] for k, v in raw_obs.items()}
                if isinstance(raw_obs, dict)
                else raw_obs[valid]
            )
            obs = rows(obs, torch.as_tensor(valid))
        actions = torch.as_tensor(batch.actions.reshape(-1, *batch.actions.shape[2:])[valid])
        adv = torch.as_tensor(advantages.reshape(-1)[valid])
        ret = torch.as_tensor(returns.reshape(-1)[valid])
        if not _finite(raw_obs, obs):
            raise NonFiniteError("non-finite observation in the batch: no update made")
        if not (torch.isfinite(adv).all() and torch.isfinite(ret).all()):
            raise NonFiniteError("non-finite advantages or returns: no update made")
        if cfg.normalize_advantages and adv.numel() > 1:
            adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        return TrainingBatch(raw_obs, obs, actions, adv, ret)

    def fit_critic_and_finish(self, tb: TrainingBatch, clock: Stopwatch) -> float:
        """The update's last steps, after the policy step: the critic's regression on the
        λ-returns (``critic_s``), then :meth:`finish_update` (``batch_s``); the critic's loss."""
        cfg = self.config
        value_loss = fit_critic(
            self.critic,
            self.critic_optimizer,
            tb.obs,
            tb.returns,
            cfg.critic_epochs,
            cfg.critic_minibatch,
            self.generator,
        )
        clock.lap("critic_s")
        self.finish_update(tb)
        clock.lap("batch_s")
        return value_loss

    def finish_update(self, tb: TrainingBatch) -> None:
        """Between iterations: refresh the statistics the next rollout's policy will use (the
        normaliser from the raw observations, the policy's BatchNorm from the normalised ones),
        so that within one iteration π_θold is one fixed function; count the update. With
        ``config.fixed_input_stats`` both stay as they started: refreshed from the rollouts of
        a new task they change what a loaded policy does outside the trust region (measured:
        the GAIL radar policy on the family went from 14/15 to 0/15 in 15 RL iterations)."""
        if not getattr(self.config, "fixed_input_stats", False):
            self.normalizer.update(tb.raw_obs)
            refresh_batchnorm(self.policy, tb.obs)
        self.iteration += 1
        self.env_steps += int(tb.returns.shape[0])

    # -- checkpoints -----------------------------------------------------------------------

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume or to act: plain types, tensors and numpy arrays."""
        return {
            "format": self.STATE_FORMAT,
            "config": dataclasses.asdict(self.config),
            "observation_space": space_to_spec(self.observation_space),
            "action_space": space_to_spec(self.action_space),
            "policy": self.policy.state_dict(),
            "critic": self.critic.state_dict(),
            **{key: opt.state_dict() for key, opt in self.optimizers().items()},
            "normalizer": self.normalizer.state_dict(),
            "generator": self.generator.get_state(),
            "iteration": self.iteration,
            "env_steps": self.env_steps,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict`; raises ``ValueError`` on another format or if its
        spaces differ from ours."""
        self._check_spaces(state)
        self.policy.load_state_dict(state["policy"])
        self.critic.load_state_dict(state["critic"])
        for key, opt in self.optimizers().items():
            opt.load_state_dict(state[key])
        self.normalizer.load_state_dict(state["normalizer"])
        self.generator.set_state(state["generator"])
        self.iteration, self.env_steps = int(state["iteration"]), int(state["env_steps"])

    def load_policy(self, state: dict[str, Any]) -> None:
        """Start from another run's policy: its weights and observation normaliser from
        ``state`` (a :meth:`state_dict`, slim or full, of the same format, spaces and networks,
        e.g. a GAIL run's); the critic, optimisers, random generator and counters stay this
        agent's own. Raises ``ValueError`` as :meth:`load_state_dict`, ``RuntimeError`` where
        the weights do not fit."""
        self._check_spaces(state)
        self.policy.load_state_dict(state["policy"])
        self.normalizer.load_state_dict(state["normalizer"])

    def _check_spaces(self, state: dict[str, Any]) -> None:
        if state.get("format") != self.STATE_FORMAT:
            raise ValueError(f"not a {self.NAME} state (format {state.get('format')!r})")
        for key, space in (
            ("observation_space", self.observation_space),
            ("action_space", self.action_space),
        ):
            if state[key] != space_to_spec(space):
                raise ValueError(f"checkpoint {key} {state[key]} does not match {space}")

    @classmethod
    def from_state_dict(cls: type[A], state: dict[str, Any], config: Any | None = None) -> A:
        """An agent rebuilt from a :meth:`state_dict` (its own config unless one is given)."""
        if config is None:
            config = config_from_dict(cls.config_type, state["config"])
        agent = cls(
            space_from_spec(state["observation_space"]),
            space_from_spec(state["action_space"]),
            config,
        )
        agent.load_state_dict(state)
        return agent
