"""Action distributions of the policy heads, written out so that TRPO's KL terms are explicit.

================  ===========================  ==========================  ===================
distribution      parameters                   actions                     used for
================  ===========================  ==========================  ===================
``DiagGaussian``  mean (B, A), log_std (A,)    (B, A) float, env units     ``Box`` actions
``Categorical``   logits (B, K)                (B,) int64 in 0..K-1        ``Discrete(K)``
================  ===========================  ==========================  ===================

Both give ``log_prob``, ``entropy``, ``kl(other)`` = KL(self ‖ other) per row, ``sample`` from an
explicit ``torch.Generator`` (reproducible runs), ``mode`` (the deterministic action),
``detach``/``rows`` (the "old" policy of a TRPO step, or a sub-sample of it), and for TRPO's
Fisher-vector products ``params`` (the parameter tensors of the table) and ``fisher(t)``: the
Hessian of the mean KL in those parameters, at the distribution itself, times ``t``
(Gaussian: t_μ / σ² per row and 2 t_logσ; categorical: p ⊙ t − p (pᵀt) per row; each per-row
term divided by B).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import torch
from torch import Tensor

__all__ = ["ActionDistribution", "Categorical", "DiagGaussian"]

_LOG_2PI = math.log(2.0 * math.pi)


class ActionDistribution(ABC):
    """A batch of B action distributions."""

    @abstractmethod
    def log_prob(self, actions: Tensor) -> Tensor:
        """log π(a|s), shape (B,)."""

    @abstractmethod
    def entropy(self) -> Tensor:
        """H[π(·|s)], shape (B,)."""

    @abstractmethod
    def kl(self, other: ActionDistribution) -> Tensor:
        """KL(self ‖ other), shape (B,)."""

    @abstractmethod
    def sample(self, generator: torch.Generator | None = None) -> Tensor:
        """One action per row."""

    @abstractmethod
    def mode(self) -> Tensor:
        """The most likely action per row."""

    @abstractmethod
    def detach(self) -> ActionDistribution:
        """The same distribution with its parameters cut from the graph."""

    @abstractmethod
    def rows(self, idx: Tensor) -> ActionDistribution:
        """The distributions of rows ``idx``."""

    @abstractmethod
    def params(self) -> tuple[Tensor, ...]:
        """The parameter tensors of the module table, in its order."""

    @abstractmethod
    def fisher(self, tangents: tuple[Tensor, ...]) -> tuple[Tensor, ...]:
        """∇²_q D̄_KL(self ‖ q)|_{q = self} · t for tangents t shaped as :meth:`params`
        (D̄: the mean over the B rows); the Fisher information of the distribution's parameters."""


class DiagGaussian(ActionDistribution):
    """N(mean, diag(exp(log_std)²)); ``log_std`` is state-independent, shape (A,)."""

    def __init__(self, mean: Tensor, log_std: Tensor) -> None:
        self.mean, self.log_std = mean, log_std

    def log_prob(self, actions: Tensor) -> Tensor:
        z = (actions - self.mean) * torch.exp(-self.log_std)
        return (-0.5 * z.pow(2) - self.log_std - 0.5 * _LOG_2PI).sum(-1)

    def entropy(self) -> Tensor:
        h = (self.log_std + 0.5 * (1.0 + _LOG_2PI)).sum(-1)
        return h.expand(self.mean.shape[0])

    def kl(self, other: ActionDistribution) -> Tensor:
        # KL(p‖q) = Σ log σ_q/σ_p + (σ_p² + (μ_p − μ_q)²) / (2 σ_q²) − ½
        assert isinstance(other, DiagGaussian)
        var_p, var_q = torch.exp(2 * self.log_std), torch.exp(2 * other.log_std)
        kl = other.log_std - self.log_std + (var_p + (self.mean - other.mean).pow(2)) / (2 * var_q)
        return (kl - 0.5).sum(-1)

    def sample(self, generator: torch.Generator | None = None) -> Tensor:
        noise = torch.randn(
            self.mean.shape, generator=generator, dtype=self.mean.dtype, device=self.mean.device
        )
        return self.mean + noise * torch.exp(self.log_std)

    def mode(self) -> Tensor:
        return self.mean

    def detach(self) -> DiagGaussian:
        # clone: log_std may *be* a parameter, which the line search then changes in place
        return DiagGaussian(self.mean.detach(), self.log_std.detach().clone())

    def rows(self, idx: Tensor) -> DiagGaussian:
        return DiagGaussian(self.mean[idx], self.log_std)

    def params(self) -> tuple[Tensor, ...]:
        return self.mean, self.log_std

    def fisher(self, tangents: tuple[Tensor, ...]) -> tuple[Tensor, ...]:
        # ∂²KL/∂μ_q² = 1/σ², ∂²KL/∂(log σ_q)² = 2, no cross term, at q = p
        t_mean, t_log_std = tangents
        inv_var = torch.exp(-2 * self.log_std.detach())
        return t_mean * inv_var / self.mean.shape[0], 2 * t_log_std


class Categorical(ActionDistribution):
    """Softmax over ``logits`` (B, K)."""

    def __init__(self, logits: Tensor) -> None:
        self.logits = logits
        self.log_p = torch.log_softmax(logits, dim=-1)

    def log_prob(self, actions: Tensor) -> Tensor:
        return self.log_p.gather(-1, actions.long().unsqueeze(-1)).squeeze(-1)

    def entropy(self) -> Tensor:
        return -(self.log_p.exp() * self.log_p).sum(-1)

    def kl(self, other: ActionDistribution) -> Tensor:
        assert isinstance(other, Categorical)
        return (self.log_p.exp() * (self.log_p - other.log_p)).sum(-1)

    def sample(self, generator: torch.Generator | None = None) -> Tensor:
        return torch.multinomial(self.log_p.exp(), 1, generator=generator).squeeze(-1)

    def mode(self) -> Tensor:
        return self.logits.argmax(-1)

    def detach(self) -> Categorical:
        return Categorical(self.logits.detach())

    def rows(self, idx: Tensor) -> Categorical:
        return Categorical(self.logits[idx])

    def params(self) -> tuple[Tensor, ...]:
        return (self.logits,)

    def fisher(self, tangents: tuple[Tensor, ...]) -> tuple[Tensor, ...]:
        # the Hessian of log-sum-exp: diag(p) − p pᵀ
        (t,) = tangents
        p = self.log_p.detach().exp()
        return ((p * t - p * (p * t).sum(-1, keepdim=True)) / t.shape[0],)
