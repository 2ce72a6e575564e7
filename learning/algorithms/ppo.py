"""Proximal Policy Optimization with the clipped surrogate (Schulman et al. 2017, "PPO").

One iteration, top to bottom (:func:`learning.algorithms.loop.train`, :meth:`PPOAgent.update`),
in the order of CleanRL's ``ppo_continuous_action.py`` (Huang et al. 2022):

1. Roll out π_θold on N envs for T steps (:mod:`learning.algorithms.rollout`).
2. Advantages Â_t by GAE(γ, λ) with terminated/truncated kept apart
   (:mod:`learning.algorithms.gae`); normalise them to zero mean, unit std over the batch.
3. Policy epochs (:func:`ppo_step`): K epochs of Adam over shuffled minibatches of

       L^CLIP(θ) = Ê[min(r_t(θ) Â_t, clip(r_t(θ), 1 − ε, 1 + ε) Â_t)],
       r_t(θ) = π_θ(a_t|s_t) / π_θold(a_t|s_t)                            (PPO, Eq. 7)

   maximised together with the entropy bonus c₂ S[π_θ](s_t) (PPO, Eq. 9), the gradient's norm
   clipped to ``max_grad_norm``. After each epoch the mean KL(π_θold ‖ π_θ) on the whole batch
   is measured (exactly, from the distributions' parameters); above ``target_kl`` the remaining
   epochs are skipped (the early stop of OpenAI Spinning Up and Stable-Baselines3).
4. Critic: regress V_φ on the λ-returns with Adam over minibatches, the squared-error value
   loss L^VF of Eq. 9 (:func:`learning.algorithms.actor_critic.fit_critic`). Policy and critic have
   separate weights here, so Eq. 9's sum L^CLIP − c₁ L^VF + c₂ S splits into two independent
   problems: the critic gets its own epochs, minibatch and learning rate (c₁ drops out under
   Adam).
5. Between iterations: observation statistics and the policy's BatchNorm statistics are
   refreshed from the batch, as in TRPO (:class:`learning.algorithms.trpo.TRPOAgent`), so that
   π_θold is one fixed function within an iteration: the rollout's log-probabilities and the
   update's old ones agree.

log π_θold(a_t|s_t) is recomputed at the start of step 3 (no gradients) over the minibatches of
the first epoch, row for row as the first epoch will see them: at the first minibatch r_t(θ)
is exactly 1, bit for bit, whatever the floating-point blocking of the matrix products.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch
from gymnasium import spaces
from torch import Tensor, nn

from learning.algorithms.actor_critic import ActorCritic
from learning.algorithms.base import Stopwatch, UpdateTimes
from learning.algorithms.networks import (
    NetworkConfig,
    Policy,
    TensorObs,
    fused_passes,
    rows,
)
from learning.algorithms.rollout import (
    NonFiniteError,
    RolloutBatch,
)
from learning.algorithms.trust_region import trainable_params

__all__ = [
    "PPOAgent",
    "PPOConfig",
    "PPOUpdateStats",
    "PolicyUpdateStats",
    "clipped_surrogate",
    "ppo_step",
]

STATE_FORMAT = "usvsim.learning.ppo/1"


@dataclass(frozen=True)
class PPOConfig:
    """Every hyperparameter of a PPO run (names after the paper).

    The defaults are the paper's MuJoCo settings (Schulman et al. 2017, Table 3: ε = 0.2,
    Adam 3·10⁻⁴, K = 10 epochs, B = 2048, γ = 0.99, λ = 0.95) as kept by CleanRL's
    ``ppo_continuous_action.py`` (gradient-norm clip 0.5, Adam ε = 10⁻⁵, no entropy bonus, the
    critic trained with the policy's epochs and step size), except the minibatch: 128 rows
    instead of 64. Measured on ``rl-gaussian-positional`` (B = 32 × 64, seeds 0-4, iterations to
    the first 15/15 validation): minibatch 64 → 5-7 (median 6), 128 → 6-8 (median 6) at half
    the update time, 256 → 7-12 (median 9).
    """

    seed: int = 0
    iterations: int = 100
    num_envs: int = 8  # N
    steps_per_env: int = 256  # T; batch B = N·T samples per iteration (CleanRL: 1 × 2048)
    gamma: float = 0.99  # γ, discount (PPO, Table 3)
    gae_lambda: float = 0.95  # λ of GAE (PPO, Table 3)
    clip_range: float = 0.2  # ε of L^CLIP (PPO, Table 3; Sect. 6.1 found 0.2 best)
    policy_lr: float = 3e-4  # Adam step size (PPO, Table 3)
    adam_eps: float = 1e-5  # Adam ε (CleanRL; PyTorch's 1e-8 is the other common choice)
    update_epochs: int = 10  # K, policy epochs per iteration (PPO, Table 3)
    minibatch_size: int = 128  # rows per policy Adam step (Table 3: 64; class docstring)
    entropy_coef: float = 0.0  # c₂ of Eq. 9 (0 for continuous control in PPO and CleanRL)
    max_grad_norm: float | None = 0.5  # global gradient-norm clip (CleanRL); None: none
    target_kl: float | None = None  # stop the epochs once mean KL(π_old ‖ π) exceeds it, nats
    normalize_advantages: bool = True
    normalize_observations: bool = True
    # vector observations: "running" mean/std, or "scene" (fixed constants, empty slots 0;
    # usvsim.task.observations.standardize_scene) for the k-nearest scene form
    observation_scaling: str = "running"
    obs_clip: float = 10.0  # normalised observations clipped to ±obs_clip
    # keep the observation normaliser's and BatchNorm's statistics as they start (a fine-tuned
    # imitation policy's; ActorCritic.finish_update) instead of refreshing them from rollouts
    fixed_input_stats: bool = False
    critic_lr: float = 3e-4  # Adam (PPO, Table 3: one step size for both losses)
    critic_epochs: int = 10  # as the policy's K
    critic_minibatch: int = 128  # rows, as the policy's minibatch
    network: NetworkConfig = field(default_factory=NetworkConfig)

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.steps_per_env


# ---------------------------------------------------------------------------------------------
# The policy epochs
# ---------------------------------------------------------------------------------------------


def clipped_surrogate(ratio: Tensor, advantages: Tensor, clip_range: float) -> Tensor:
    """Per-sample min(r Â, clip(r, 1 − ε, 1 + ε) Â) (PPO, Eq. 7); shapes (B,) → (B,).

    The gradient with respect to r is zero where the clip is the minimum: r > 1 + ε with Â > 0
    and r < 1 − ε with Â < 0.

    >>> r = torch.tensor([0.5, 1.5, 0.5, 1.5]); a = torch.tensor([1.0, 1.0, -1.0, -1.0])
    >>> clipped_surrogate(r, a, 0.2).tolist()
    [0.5, 1.2000000476837158, -0.800000011920929, -1.5]
    """
    clipped = torch.clamp(ratio, 1.0 - clip_range, 1.0 + clip_range)
    return torch.min(ratio * advantages, clipped * advantages)


def _minibatches(perm: Tensor, size: int) -> Iterator[Tensor]:
    for start in range(0, perm.shape[0], size):
        yield perm[start : start + size]


@dataclass(frozen=True)
class PolicyUpdateStats:
    """What the policy epochs of one iteration did."""

    entropy: float  # mean policy entropy at θ_old, nats
    kl: float  # mean KL(π_old ‖ π_new) on the whole batch after the last epoch, nats
    clip_fraction: float  # share of minibatch rows with |r − 1| > ε, over all steps
    surrogate: float  # mean L^CLIP over the minibatch steps of the last epoch
    epochs: int  # epochs done (< update_epochs when target_kl stopped them)
    steps: int  # Adam steps made
    early_stopped: bool


def ppo_step(
    policy: Policy,
    optimizer: torch.optim.Optimizer,
    obs: TensorObs,
    actions: Tensor,
    advantages: Tensor,
    cfg: PPOConfig,
    generator: torch.Generator,
) -> PolicyUpdateStats:
    """The K policy epochs of one iteration (module docstring, step 3).

    ``obs`` (B, ...), ``actions`` (B, ...), ``advantages`` (B,) as tensors, already normalised.
    The policy stays in eval mode (BatchNorm uses its running statistics, as in the rollout).
    Raises :class:`NonFiniteError` instead of a step whose loss is not finite (the parameters
    are then those after the last finite step).
    """
    policy.eval()
    B = advantages.shape[0]
    params = trainable_params(policy)
    first = torch.randperm(B, generator=generator)
    old_log_prob = torch.empty(B)
    with torch.no_grad():
        old_dist = policy(obs).detach()
        for idx in _minibatches(first, cfg.minibatch_size):
            old_log_prob[idx] = policy(rows(obs, idx)).log_prob(actions[idx])
    entropy = float(old_dist.entropy().mean())

    steps, clipped_rows, epochs, kl = 0, 0, 0, float("nan")
    surrogates: list[float] = []
    for epoch in range(cfg.update_epochs):
        perm = first if epoch == 0 else torch.randperm(B, generator=generator)
        surrogates = []
        for idx in _minibatches(perm, cfg.minibatch_size):
            dist = policy(rows(obs, idx))
            ratio = torch.exp(dist.log_prob(actions[idx]) - old_log_prob[idx])
            surrogate = clipped_surrogate(ratio, advantages[idx], cfg.clip_range).mean()
            loss = -surrogate
            if cfg.entropy_coef:
                loss = loss - cfg.entropy_coef * dist.entropy().mean()
            if not torch.isfinite(loss):
                raise NonFiniteError("non-finite PPO loss: optimizer step skipped")
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            if cfg.max_grad_norm is not None:
                nn.utils.clip_grad_norm_(params, cfg.max_grad_norm)
            optimizer.step()
            steps += 1
            clipped_rows += int(((ratio.detach() - 1.0).abs() > cfg.clip_range).sum())
            surrogates.append(float(surrogate.detach()))
        epochs += 1
        if cfg.target_kl is not None or epoch == cfg.update_epochs - 1:
            with torch.no_grad():
                kl = float(old_dist.kl(policy(obs)).mean())
            if cfg.target_kl is not None and kl > cfg.target_kl:
                break
    return PolicyUpdateStats(
        entropy=entropy,
        kl=kl,
        clip_fraction=clipped_rows / max(1, epochs * B),
        surrogate=float(np.mean(surrogates)) if surrogates else float("nan"),
        epochs=epochs,
        steps=steps,
        early_stopped=epochs < cfg.update_epochs,
    )


# ---------------------------------------------------------------------------------------------
# The agent: networks, optimisers, normaliser, random state; one update per iteration
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PPOUpdateStats:
    """What one :meth:`PPOAgent.update` did: the policy epochs and the critic's fit."""

    LOG_FIELDS: ClassVar[tuple[str, ...]] = (
        "kl",
        "entropy",
        "clip_fraction",
        "epochs",
        "value_loss",
    )

    policy_step: PolicyUpdateStats
    value_loss: float  # mean squared error of the critic's last epoch
    times: UpdateTimes = field(default_factory=UpdateTimes, compare=False)  # wall-clock split

    @property
    def kl(self) -> float:
        """Mean KL(π_old ‖ π_new) on the batch after the update, nats."""
        return self.policy_step.kl

    @property
    def entropy(self) -> float:
        """Mean entropy of π_old, nats."""
        return self.policy_step.entropy

    @property
    def clip_fraction(self) -> float:
        return self.policy_step.clip_fraction

    @property
    def epochs(self) -> int:
        return self.policy_step.epochs

    @property
    def early_stopped(self) -> bool:
        return self.policy_step.early_stopped


class PPOAgent(ActorCritic):
    """Policy, critic, their optimisers, observation normaliser and random state of one run.

    The same public interface as :class:`learning.algorithms.trpo.TRPOAgent`.
    """

    STATE_FORMAT: ClassVar[str] = STATE_FORMAT
    NAME: ClassVar[str] = "PPO"
    config_type: ClassVar[type[Any]] = PPOConfig
    config: PPOConfig

    def __init__(
        self, observation_space: spaces.Space, action_space: spaces.Space, config: PPOConfig
    ) -> None:
        super().__init__(observation_space, action_space, config)
        self.policy_optimizer = torch.optim.Adam(
            self.policy.parameters(), lr=config.policy_lr, eps=config.adam_eps
        )
        self.critic_optimizer = torch.optim.Adam(
            self.critic.parameters(), lr=config.critic_lr, eps=config.adam_eps
        )

    def optimizers(self) -> dict[str, torch.optim.Optimizer]:
        return {
            "policy_optimizer": self.policy_optimizer,
            "critic_optimizer": self.critic_optimizer,
        }

    def update(self, batch: RolloutBatch) -> PPOUpdateStats:
        """Steps 2-5 of the module docstring on one batch (:class:`PPOUpdateStats`). Inputs are
        checked first: non-finite data raises :class:`NonFiniteError` before any parameter
        changes."""
        with fused_passes(self.policy, self.critic):
            cfg = self.config
            clock = Stopwatch()
            tb = self.training_batch(batch)
            clock.lap("batch_s")
            step = ppo_step(
                self.policy,
                self.policy_optimizer,
                tb.obs,
                tb.actions,
                tb.advantages,
                cfg,
                self.generator,
            )
            clock.lap("policy_step_s")
            value_loss = self.fit_critic_and_finish(tb, clock)
            return PPOUpdateStats(step, value_loss, clock.times())
