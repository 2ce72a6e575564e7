"""Trust Region Policy Optimization (Schulman et al. 2015, "TRPO"), with GAE (Schulman et al. 2016).

One iteration, top to bottom (:func:`learning.algorithms.loop.train`, :meth:`TRPOAgent.update`):

1. Roll out π_θold on N envs for T steps (:mod:`learning.algorithms.rollout`).
2. Advantages Â_t by GAE(γ, λ) with terminated/truncated kept apart
   (:mod:`learning.algorithms.gae`); normalise them to zero mean, unit std over the batch.
3. Policy step (:func:`trpo_step`), the paper's Sect. 6 / Appendix C:

       maximise  L(θ) = Ê[π_θ(a|s) / π_θold(a|s) · Â]
       subject to  D̄_KL(θ_old, θ) = Ê[KL(π_θold ‖ π_θ)] ≤ δ

   g = ∇_θ L; the Fisher matrix F = ∇²_θ D̄_KL at θ_old (plus damping·I) is never formed:
   conjugate gradient solves F x = g from Fisher-vector products on a sub-sample of the batch
   (:func:`learning.algorithms.trust_region.fisher_vector_product`: Jᵀ M J v for the CNN,
   double backprop of the mean KL for the MLP). The full step is β = sqrt(2δ / xᵀFx) · x; a
   backtracking line search (:func:`learning.algorithms.trust_region.line_search`) shrinks it until
   D̄_KL ≤ δ and L improves, and restores θ_old if no fraction does.
4. Critic: regress V_φ on the λ-returns with Adam over minibatches (:func:`fit_critic`).
5. Between iterations: observation statistics and the policy's BatchNorm statistics are
   refreshed from the batch (so within one iteration π_θold is a single fixed function: the
   log-probabilities of the rollout and of the update agree).

Cost per iteration (B samples, P policy parameters): one forward+backward on B for g; one
forward (MLP: + create_graph backward) on the FVP sub-sample, reused by every CG iteration (each
FVP is then a forward-mode pass and one backward, or one backward through the double graph);
one no-grad forward on B per line-search trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import torch
from gymnasium import spaces
from torch import Tensor

from learning.algorithms.actor_critic import ActorCritic
from learning.algorithms.base import Stopwatch, UpdateTimes
from learning.algorithms.networks import NetworkConfig, Policy, TensorObs, fused_passes, rows
from learning.algorithms.rollout import NonFiniteError, RolloutBatch
from learning.algorithms.trust_region import (
    LineSearchResult,
    conjugate_gradient,
    fisher_vector_product,
    flat_grad,
    line_search,
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
    # vector observations: "running" mean/std, or "scene" (fixed constants, empty slots 0;
    # usvsim.task.observations.standardize_scene) for the k-nearest scene form
    observation_scaling: str = "running"
    obs_clip: float = 10.0  # normalised observations clipped to ±obs_clip
    # keep the observation normaliser's and BatchNorm's statistics as they start (a fine-tuned
    # imitation policy's; ActorCritic.finish_update) instead of refreshing them from rollouts
    fixed_input_stats: bool = False
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
    times: UpdateTimes = field(default_factory=UpdateTimes, compare=False)  # wall-clock split

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


class TRPOAgent(ActorCritic):
    """Policy, critic, critic optimiser, observation normaliser and random state of one run."""

    STATE_FORMAT: ClassVar[str] = STATE_FORMAT
    NAME: ClassVar[str] = "TRPO"
    config_type: ClassVar[type[Any]] = TRPOConfig
    config: TRPOConfig

    def __init__(
        self, observation_space: spaces.Space, action_space: spaces.Space, config: TRPOConfig
    ) -> None:
        super().__init__(observation_space, action_space, config)
        self.critic_optimizer = torch.optim.Adam(self.critic.parameters(), lr=config.critic_lr)

    def optimizers(self) -> dict[str, torch.optim.Optimizer]:
        return {"critic_optimizer": self.critic_optimizer}

    def update(self, batch: RolloutBatch) -> TRPOUpdateStats:
        """Steps 2-5 of the module docstring on one batch (:class:`TRPOUpdateStats`). Inputs are
        checked first: non-finite data raises :class:`NonFiniteError` before any parameter
        changes."""
        with fused_passes(self.policy, self.critic):
            cfg = self.config
            clock = Stopwatch()
            tb = self.training_batch(batch)
            clock.lap("batch_s")
            step = trpo_step(self.policy, tb.obs, tb.actions, tb.advantages, cfg, self.generator)
            clock.lap("policy_step_s")
            value_loss = self.fit_critic_and_finish(tb, clock)
            return TRPOUpdateStats(step, value_loss, clock.times())
