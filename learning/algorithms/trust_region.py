"""Natural-gradient building blocks shared by trust-region policy steps (Schulman et al. 2015,
"TRPO", Sect. 6 and Appendix C): flat parameter vectors, conjugate gradient, Fisher-vector
products and the backtracking line search. :func:`learning.algorithms.trpo.trpo_step` composes
them; each is tested on its own (``tests/test_trpo.py``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import torch
from torch import Tensor, nn

from learning.algorithms import linearized
from learning.algorithms.networks import CNNTrunk, Policy, TensorObs

__all__ = [
    "LineSearchResult",
    "conjugate_gradient",
    "fisher_vector_product",
    "flat_grad",
    "get_flat",
    "jacobian_fisher_vector_product",
    "kl_hessian_vector_product",
    "line_search",
    "policy_jvp",
    "set_flat",
    "trainable_params",
]


def trainable_params(module: nn.Module) -> list[nn.Parameter]:
    """The parameters of ``module`` that require gradients, in registration order."""
    return [p for p in module.parameters() if p.requires_grad]


def flat_grad(y: Tensor, params: Sequence[Tensor], **kwargs: Any) -> Tensor:
    """∂y/∂θ as one flat vector."""
    return torch.cat([g.reshape(-1) for g in torch.autograd.grad(y, params, **kwargs)])


def get_flat(params: Sequence[Tensor]) -> Tensor:
    return torch.cat([p.detach().reshape(-1) for p in params]).clone()


@torch.no_grad()
def set_flat(params: Sequence[Tensor], flat: Tensor) -> None:
    """Copy ``flat`` into the parameters in place (bit-exact, storage kept)."""
    i = 0
    for p in params:
        p.copy_(flat[i : i + p.numel()].view_as(p))
        i += p.numel()


def conjugate_gradient(
    Avp: Callable[[Tensor], Tensor], b: Tensor, iters: int = 10, residual_tol: float = 1e-10
) -> Tensor:
    """Approximate solution of A x = b for symmetric positive-definite A given only x ↦ A x.

    Hestenes and Stiefel (1952); TRPO, Appendix C. Starts from x = 0; stops after ``iters``
    iterations or when the squared residual falls below ``residual_tol``.
    """
    x = torch.zeros_like(b)
    r = b.clone()
    p = b.clone()
    rr = r @ r
    for _ in range(iters):
        if rr < residual_tol:
            break
        Ap = Avp(p)
        alpha = rr / (p @ Ap)
        x += alpha * p
        r -= alpha * Ap
        rr_new = r @ r
        p = r + (rr_new / rr) * p
        rr = rr_new
    return x


def fisher_vector_product(
    policy: Policy, obs: TensorObs, damping: float
) -> Callable[[Tensor], Tensor]:
    """v ↦ (∇²_θ D̄_KL(θ_old, θ)|_θold + damping·I) v on ``obs`` (TRPO, Appendix C.1).

    Two exact forms of the same matrix, built at the current θ (θ_old during the
    conjugate-gradient solve): :func:`jacobian_fisher_vector_product` for a CNN policy (~30 %
    cheaper there, ``benchmarks/radar_update.py``) and :func:`kl_hessian_vector_product` for an
    MLP (the same cost; kept so that MLP runs stay bit for bit those before the Jacobian form).
    They differ by float32 rounding only: both lie within 3e-7 (relative) of the float64 product
    on the radar policies. The policy must be in eval mode (one deterministic function).
    """
    if isinstance(policy.trunk, CNNTrunk):
        return jacobian_fisher_vector_product(policy, obs, damping)
    return kl_hessian_vector_product(policy, obs, damping)


def kl_hessian_vector_product(
    policy: Policy, obs: TensorObs, damping: float
) -> Callable[[Tensor], Tensor]:
    """:func:`fisher_vector_product` by double backward: the mean KL and its gradient (with
    ``create_graph``) are built once; every product is then one backward pass of ∇D̄_KL · v
    through that graph."""
    params = trainable_params(policy)
    dist = policy(obs)
    mean_kl = dist.detach().kl(dist).mean()
    grad_kl = flat_grad(mean_kl, params, create_graph=True)

    def fvp(v: Tensor) -> Tensor:
        return flat_grad(grad_kl @ v, params, retain_graph=True) + damping * v

    return fvp


def jacobian_fisher_vector_product(
    policy: Policy, obs: TensorObs, damping: float
) -> Callable[[Tensor], Tensor]:
    """:func:`fisher_vector_product` as Jᵀ M J v: at θ_old the Hessian of the mean KL is the
    Fisher matrix F = Jᵀ M J (TRPO, Appendix C.1; Martens 2014, Sect. 9), J the Jacobian of the
    distribution's parameters (``ActionDistribution.params``: the Gaussian's mean and log σ, the
    logits) in θ and M their Fisher information (``ActionDistribution.fisher``). Each product is
    one forward-mode pass for J v (:func:`policy_jvp`: for the CNN policies, the tangent half
    of a forward pass kept from the start) and one backward pass for Jᵀ (M J v) through a
    forward graph built once."""
    named = [(n, p) for n, p in policy.named_parameters() if p.requires_grad]
    names, params = [n for n, _ in named], [p for _, p in named]
    dist = policy(obs)
    outputs = dist.params()
    jv_of = policy_jvp(policy, obs, names)

    def fvp(v: Tensor) -> Tensor:
        chunks = v.split([p.numel() for p in params])
        tangents = tuple(t.view_as(p) for t, p in zip(chunks, params, strict=True))
        jv = jv_of(tangents)
        grads = torch.autograd.grad(
            outputs, params, dist.fisher(jv), retain_graph=True, allow_unused=True
        )
        flat = [torch.zeros_like(p) if g is None else g for g, p in zip(grads, params, strict=True)]
        return torch.cat([g.reshape(-1) for g in flat]) + damping * v

    return fvp


def policy_jvp(
    policy: Policy, obs: TensorObs, names: Sequence[str]
) -> Callable[[tuple[Tensor, ...]], tuple[Tensor, ...]]:
    """(t_1, ...) ↦ J t, the derivative of the distribution's parameters on ``obs`` along
    tangents of the parameters called ``names`` (the others held): by
    :func:`learning.algorithms.linearized.linearize_cnn_policy` (the forward pass kept) for
    the CNN policies it knows, else by ``torch.func.jvp`` (the forward pass again per call)."""
    if linearized.supports(policy) and set(names) == {n for n, _ in policy.named_parameters()}:
        jv = linearized.linearize_cnn_policy(policy, obs)
        return lambda tangents: jv(dict(zip(names, tangents, strict=True)))
    by_name = dict(policy.named_parameters())
    primals = tuple(by_name[n].detach() for n in names)

    def dist_params(*values: Tensor) -> tuple[Tensor, ...]:
        values_by_name = dict(zip(names, values, strict=True))
        out: tuple[Tensor, ...] = torch.func.functional_call(
            policy, values_by_name, (obs,)
        ).params()
        return out

    def jv_func(tangents: tuple[Tensor, ...]) -> tuple[Tensor, ...]:
        with warnings.catch_warnings():  # torch's jvp decompositions, loaded on first use
            warnings.filterwarnings("ignore", "`torch.jit.script` is deprecated")
            out: tuple[Tensor, ...] = torch.func.jvp(dist_params, primals, tangents)[1]
        return out

    return jv_func


@dataclass(frozen=True)
class LineSearchResult:
    accepted: bool
    step_fraction: float  # of the full natural-gradient step; 0 when rejected
    trials: int  # evaluations made
    kl: float  # mean KL at the accepted θ (0 when rejected)
    improvement: float  # L(θ) − L(θ_old) at the accepted θ (0 when rejected)


def line_search(
    params: Sequence[Tensor],
    full_step: Tensor,
    evaluate: Callable[[], tuple[float, float]],
    surrogate_old: float,
    max_kl: float,
    steps: int,
    decay: float,
) -> LineSearchResult:
    """Backtracking line search along ``full_step`` from the current θ (= θ_old).

    Tries θ_old + decayⁱ · full_step for i = 0 … steps − 1, accepting the first with
    D̄_KL ≤ ``max_kl`` and L > ``surrogate_old`` (``evaluate`` returns (L, D̄_KL) at the current
    parameters). If none is accepted, θ_old is restored bit for bit.
    """
    theta_old = get_flat(params)
    for i in range(steps):
        fraction = decay**i
        set_flat(params, theta_old + fraction * full_step)
        surrogate, kl = evaluate()
        improvement = surrogate - surrogate_old
        if math.isfinite(kl) and kl <= max_kl and improvement > 0:
            return LineSearchResult(True, fraction, i + 1, kl, improvement)
    set_flat(params, theta_old)
    return LineSearchResult(False, 0.0, steps, 0.0, 0.0)
