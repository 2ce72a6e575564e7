"""Trust Region Policy Optimization (Schulman et al. 2015, "TRPO"), with GAE (Schulman et al. 2016).

One iteration, top to bottom (:func:`learning.algorithms.loop.train`, :meth:`TRPOAgent.update`):

1. Roll out π_θold on N envs for T steps (:mod:`learning.algorithms.rollout`).
2. Advantages Â_t by GAE(γ, λ) with terminated/truncated kept apart
   (:mod:`learning.algorithms.gae`); normalise them to zero mean, unit std over the batch.
3. Policy step (:func:`trpo_step`), the paper's Sect. 6 / Appendix C:

       maximise  L(θ) = Ê[π_θ(a|s) / π_θold(a|s) · Â]
       subject to  D̄_KL(θ_old, θ) = Ê[KL(π_θold ‖ π_θ)] ≤ δ

   g = ∇_θ L; the Fisher matrix F = ∇²_θ D̄_KL at θ_old (plus damping·I) is never formed:
   conjugate gradient solves F x = g from Fisher-vector products
   (:func:`learning.algorithms.trust_region.fisher_vector_product`, double backprop of the
   mean KL on a sub-sample of the batch). The full step is β = sqrt(2δ / xᵀFx) · x; a
   backtracking line search (:func:`learning.algorithms.trust_region.line_search`) shrinks it until
   D̄_KL ≤ δ and L improves, and restores θ_old if no fraction does.
4. Critic: regress V_φ on the λ-returns with Adam over minibatches (:func:`fit_critic`).
5. Between iterations: observation statistics and the policy's BatchNorm statistics are
   refreshed from the batch (so within one iteration π_θold is a single fixed function: the
   log-probabilities of the rollout and of the update agree).

Cost per iteration (B samples, P policy parameters): one forward+backward on B for g; one
forward + create_graph backward on the FVP sub-sample, reused by every CG iteration (each FVP is
then one backward through that graph); one no-grad forward on B per line-search trial.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch
from gymnasium import spaces
from torch import Tensor

from learning.algorithms.base import config_from_dict
from learning.algorithms.gae import gae
from learning.algorithms.networks import (
    Critic,
    NetworkConfig,
    Policy,
    TensorObs,
    make_critic,
    make_policy,
    obs_to_tensor,
    refresh_batchnorm,
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
from learning.algorithms.trust_region import (
    LineSearchResult,
    conjugate_gradient,
    fisher_vector_product,
    flat_grad,
    line_search,
    rows,
    trainable_params,
)

__all__ = [
    "LineSearchResult",
    "PolicyStepStats",
    "TRPOAgent",
    "TRPOConfig",
    "TRPOUpdateStats",
    "conjugate_gradient",
    "fisher_vector_product",
    "fit_critic",
    "line_search",
    "trpo_step",
]

STATE_FORMAT = "usvsim.learning.trpo/1"


@dataclass(frozen=True)
class TRPOConfig:
    """Every hyperparameter of a TRPO run (names after the papers)."""

    seed: int = 0
    iterations: int = 100
    num_envs: int = 8  # N
    steps_per_env: int = 512  # T; batch B = N·T samples per iteration
    gamma: float = 0.99  # γ, discount
    gae_lambda: float = 0.97  # λ of GAE (Schulman et al. 2016 use 0.96-0.99)
    max_kl: float = 0.01  # δ, trust-region radius in mean KL (nats)
    cg_iters: int = 10  # conjugate-gradient iterations
    cg_damping: float = 0.1  # F + damping·I
    fvp_fraction: float = 0.2  # share of the batch used for Fisher-vector products
    line_search_steps: int = 10  # backtracking trials
    line_search_decay: float = 0.5  # step fraction factor between trials
    normalize_advantages: bool = True
    normalize_observations: bool = True
    obs_clip: float = 10.0  # normalised observations clipped to ±obs_clip
    critic_lr: float = 1e-3  # Adam
    critic_epochs: int = 5
    critic_minibatch: int = 512  # rows; the CNN's FC1 input is 512·3192 float32 ≈ 6.5 MB
    network: NetworkConfig = field(default_factory=NetworkConfig)

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.steps_per_env


@dataclass(frozen=True)
class PolicyStepStats:
    entropy: float  # mean policy entropy at θ_old, nats
    surrogate_old: float  # L(θ_old)
    expected_improvement: float  # gᵀβ, first-order prediction of the full step
    line_search: LineSearchResult


def trpo_step(
    policy: Policy,
    obs: TensorObs,
    actions: Tensor,
    advantages: Tensor,
    cfg: TRPOConfig,
    generator: torch.Generator,
) -> PolicyStepStats:
    """One natural-gradient step of ``policy`` with line search (module docstring, step 3).

    ``obs`` (B, ...), ``actions`` (B, ...), ``advantages`` (B,) as tensors, already normalised.
    Raises :class:`NonFiniteError` (parameters untouched) if the surrogate or its gradient is not
    finite.
    """
    policy.eval()
    params = trainable_params(policy)
    # L(θ) and g = ∇L at θ_old from one forward pass; π_θold is that pass, detached.
    dist = policy(obs)
    log_prob = dist.log_prob(actions)
    old_dist, old_log_prob = dist.detach(), log_prob.detach()
    surrogate = (torch.exp(log_prob - old_log_prob) * advantages).mean()
    g = flat_grad(surrogate, params)
    if not (torch.isfinite(surrogate) and torch.isfinite(g).all()):
        raise NonFiniteError("non-finite surrogate loss or gradient: policy left unchanged")
    entropy = float(old_dist.entropy().mean())

    # x ≈ F⁻¹ g by conjugate gradient on Fisher-vector products over a sub-sample.
    B = advantages.shape[0]
    n_sub = min(B, max(2, math.ceil(cfg.fvp_fraction * B)))
    sub = torch.randperm(B, generator=generator)[:n_sub] if n_sub < B else torch.arange(B)
    Fvp = fisher_vector_product(policy, rows(obs, sub), cfg.cg_damping)
    x = conjugate_gradient(Fvp, g, cfg.cg_iters)
    xFx = float(x @ Fvp(x))
    if not math.isfinite(xFx):
        raise NonFiniteError("non-finite Fisher-vector product: policy left unchanged")
    if xFx <= 0:  # g = 0: nothing to gain, no step
        return PolicyStepStats(
            entropy, float(surrogate), 0.0, LineSearchResult(False, 0.0, 0, 0.0, 0.0)
        )
    full_step = math.sqrt(2 * cfg.max_kl / xFx) * x  # β: ½ βᵀFβ = δ

    @torch.no_grad()
    def evaluate() -> tuple[float, float]:
        new = policy(obs)
        ratio = torch.exp(new.log_prob(actions) - old_log_prob)
        return float((ratio * advantages).mean()), float(old_dist.kl(new).mean())

    result = line_search(
        params,
        full_step,
        evaluate,
        float(surrogate.detach()),
        cfg.max_kl,
        cfg.line_search_steps,
        cfg.line_search_decay,
    )
    return PolicyStepStats(entropy, float(surrogate.detach()), float(g @ full_step), result)


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


# ---------------------------------------------------------------------------------------------
# The agent: networks, normaliser, random state; one update per iteration
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TRPOUpdateStats:
    """What one :meth:`TRPOAgent.update` did: the policy step and the critic's fit."""

    LOG_FIELDS: ClassVar[tuple[str, ...]] = (
        "kl",
        "entropy",
        "surrogate_improvement",
        "line_search_accepted",
        "value_loss",
    )

    policy_step: PolicyStepStats
    value_loss: float  # mean squared error of the critic's last epoch

    @property
    def kl(self) -> float:
        """Mean KL(π_old ‖ π_new) on the batch after the step, nats."""
        return self.policy_step.line_search.kl

    @property
    def entropy(self) -> float:
        """Mean entropy of π_old, nats."""
        return self.policy_step.entropy

    @property
    def surrogate_improvement(self) -> float:
        """L(θ_new) − L(θ_old)."""
        return self.policy_step.line_search.improvement

    @property
    def expected_improvement(self) -> float:
        return self.policy_step.expected_improvement

    @property
    def line_search_accepted(self) -> bool:
        return self.policy_step.line_search.accepted

    @property
    def line_search_trials(self) -> int:
        return self.policy_step.line_search.trials


class TRPOAgent:
    """Policy, critic, critic optimiser, observation normaliser and random state of one run."""

    def __init__(
        self, observation_space: spaces.Space, action_space: spaces.Space, config: TRPOConfig
    ) -> None:
        self.config = config
        self.observation_space, self.action_space = observation_space, action_space
        with torch.random.fork_rng():  # initialise from the seed without touching global state
            torch.manual_seed(config.seed)
            self.policy = make_policy(observation_space, action_space, config.network)
            self.critic = make_critic(observation_space, config.network).eval()
        self.critic_optimizer = torch.optim.Adam(self.critic.parameters(), lr=config.critic_lr)
        self.normalizer = ObservationNormalizer(
            observation_space, clip=config.obs_clip, enabled=config.normalize_observations
        )
        self.generator = torch.Generator().manual_seed(config.seed + 1)
        self.iteration = 0
        self.env_steps = 0
        self.info_keys: tuple[str, ...] = ()  # the update reads no env info

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

    @torch.inference_mode()
    def values(self, obs: Obs, chunk: int = 4096) -> np.ndarray:
        """V(s) (M,) for raw observations (M, ...)."""
        t = self.policy_input(obs)
        M = next(iter(t.values())).shape[0] if isinstance(t, dict) else t.shape[0]
        out = [self.critic(rows(t, torch.arange(i, min(M, i + chunk)))) for i in range(0, M, chunk)]
        return torch.cat(out).numpy()

    # -- learning --------------------------------------------------------------------------

    def update(self, batch: RolloutBatch) -> TRPOUpdateStats:
        """Steps 2-5 of the module docstring on one batch; returns the policy step's stats and
        the critic's loss (:class:`TRPOUpdateStats`). Inputs are checked first: non-finite data
        raises :class:`NonFiniteError` before any parameter changes."""
        cfg = self.config
        attach_values(batch, self.values)
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
        raw_obs = flatten_obs(batch.obs, 2)
        raw_obs = (
            {k: v[valid] for k, v in raw_obs.items()}
            if isinstance(raw_obs, dict)
            else raw_obs[valid]
        )
        obs = self.policy_input(raw_obs)
        actions = torch.as_tensor(batch.actions.reshape(-1, *batch.actions.shape[2:])[valid])
        adv = torch.as_tensor(advantages.reshape(-1)[valid])
        ret = torch.as_tensor(returns.reshape(-1)[valid])
        parts = obs.values() if isinstance(obs, dict) else [obs]
        if not all(bool(torch.isfinite(p).all()) for p in parts):
            raise NonFiniteError("non-finite observation in the batch: no update made")
        if not (torch.isfinite(adv).all() and torch.isfinite(ret).all()):
            raise NonFiniteError("non-finite advantages or returns: no update made")
        if cfg.normalize_advantages and adv.numel() > 1:
            adv = (adv - adv.mean()) / (adv.std() + 1e-8)
        step = trpo_step(self.policy, obs, actions, adv, cfg, self.generator)
        value_loss = fit_critic(
            self.critic,
            self.critic_optimizer,
            obs,
            ret,
            cfg.critic_epochs,
            cfg.critic_minibatch,
            self.generator,
        )
        # Between iterations: refresh the statistics the next rollout's policy will use.
        self.normalizer.update(raw_obs)
        refresh_batchnorm(self.policy, obs)
        self.iteration += 1
        self.env_steps += int(valid.sum())
        return TRPOUpdateStats(step, value_loss)

    # -- checkpoints -----------------------------------------------------------------------

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume or to act: plain types, tensors and numpy arrays."""
        return {
            "format": STATE_FORMAT,
            "config": dataclasses.asdict(self.config),
            "observation_space": space_to_spec(self.observation_space),
            "action_space": space_to_spec(self.action_space),
            "policy": self.policy.state_dict(),
            "critic": self.critic.state_dict(),
            "critic_optimizer": self.critic_optimizer.state_dict(),
            "normalizer": self.normalizer.state_dict(),
            "generator": self.generator.get_state(),
            "iteration": self.iteration,
            "env_steps": self.env_steps,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict`; raises ``ValueError`` if its spaces differ from ours."""
        if state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a TRPO state (format {state.get('format')!r})")
        for key, space in (
            ("observation_space", self.observation_space),
            ("action_space", self.action_space),
        ):
            if state[key] != space_to_spec(space):
                raise ValueError(f"checkpoint {key} {state[key]} does not match {space}")
        self.policy.load_state_dict(state["policy"])
        self.critic.load_state_dict(state["critic"])
        self.critic_optimizer.load_state_dict(state["critic_optimizer"])
        self.normalizer.load_state_dict(state["normalizer"])
        self.generator.set_state(state["generator"])
        self.iteration, self.env_steps = int(state["iteration"]), int(state["env_steps"])

    @classmethod
    def from_state_dict(cls, state: dict[str, Any], config: TRPOConfig | None = None) -> TRPOAgent:
        """An agent rebuilt from a :meth:`state_dict` (its own config unless one is given)."""
        if config is None:
            config = config_from_dict(TRPOConfig, state["config"])
        agent = cls(
            space_from_spec(state["observation_space"]),
            space_from_spec(state["action_space"]),
            config,
        )
        agent.load_state_dict(state)
        return agent
