"""J v for a CNN policy with its forward pass kept: the tangent half of the radar policies'
Fisher-vector products (:func:`learning.algorithms.trust_region.jacobian_fisher_vector_product`).

A conjugate-gradient solve makes ~11 products J v at the same θ_old on the same rows.
``torch.func.jvp`` recomputes the forward pass with every one (measured on rl-gaussian-radar's
410-row sub-sample: 36 ms per J v against 10 ms for the forward, two threads).
:func:`linearize_cnn_policy` runs the forward once, keeps what the derivative needs (the
convolution's ReLU mask, the BatchNorm output, each tanh output) and returns the linear map
v ↦ J v, which costs one convolution and the layers' two products each (the product rule:
d(W h) = dW h + W dh).

The policy must be in eval mode (BatchNorm as the per-channel map y = α relu(z) + β of
:meth:`learning.algorithms.networks.CNNTrunk.eval_affine`, with α, β functions of γ and the bias
b: dα = dγ / sqrt(σ² + ε), dβ = db − μ dα) and have the module table's layers:

==================  ============================  ============================================
part                forward (cached)              tangent
==================  ============================  ============================================
convolution         z = conv(x, W) + c, z > 0     dz = conv(x, dW) + dc
ReLU, BatchNorm     y = α relu(z) + β             dy = dα relu(z) + α [z > 0] dz + dβ
FC k, tanh          h_k = tanh(W_k h_k−1 + b_k)   dh_k = (1 − h_k²)(dW_k h_k−1 + W_k dh_k−1 + db_k)
head                q = W h + b                   dq = dW h + W dh + db
Gaussian mean       c + s tanh(q)                 s (1 − tanh² q) dq; d log σ = dlog σ
Categorical logits  q                             dq
==================  ============================  ============================================

The vector parts (the goal) enter FC 1 as constants. :func:`supports` says whether a policy has
exactly these layers; the tests hold the map to ``torch.func.jvp`` of the policy.
"""

from __future__ import annotations

from collections.abc import Callable

import torch
from torch import Tensor, nn

from learning.algorithms.networks import CNNTrunk, Policy, TensorObs

__all__ = ["linearize_cnn_policy", "supports"]


def _fc_layers(trunk: CNNTrunk) -> list[nn.Linear] | None:
    """The trunk's fully connected layers if ``trunk.fc`` is (Linear, Tanh) pairs, else None."""
    layers = list(trunk.fc)
    linears = layers[0::2]
    if len(layers) % 2 or not all(isinstance(m, nn.Linear) for m in linears):
        return None
    if not all(isinstance(m, nn.Tanh) for m in layers[1::2]):
        return None
    return [m for m in linears if isinstance(m, nn.Linear)]


def supports(policy: Policy) -> bool:
    """Whether :func:`linearize_cnn_policy` knows every layer of ``policy`` (module table)."""
    trunk = policy.trunk
    return (
        isinstance(trunk, CNNTrunk)
        and trunk.conv.bias is not None
        and trunk.norm.affine
        and trunk.norm.track_running_stats
        and _fc_layers(trunk) is not None
        and policy.kind in ("gaussian", "categorical")
    )


def linearize_cnn_policy(
    policy: Policy, obs: TensorObs
) -> Callable[[dict[str, Tensor]], tuple[Tensor, ...]]:
    """v ↦ J v at the policy's current parameters on ``obs``: the derivative of the
    distribution's parameters (``ActionDistribution.params``: Gaussian mean (B, A) and log σ
    (A,), or the logits (B, K)) along the tangent v, given per parameter name as
    ``policy.named_parameters`` names them (every trainable parameter).

    One forward pass now (no gradients); each call then costs one convolution and the layers'
    two products (module docstring). Raises ``ValueError`` if the policy has other layers
    (:func:`supports`) or is in train mode.
    """
    if not supports(policy):
        raise ValueError("linearize_cnn_policy: the policy's layers are not the module table's")
    trunk = policy.trunk
    assert isinstance(trunk, CNNTrunk)
    affine = trunk.eval_affine()
    if affine is None:
        raise ValueError("linearize_cnn_policy needs the policy in eval mode")
    linears = _fc_layers(trunk)
    assert linears is not None
    norm, conv = trunk.norm, trunk.conv
    image, vectors = trunk.split(obs)
    with torch.no_grad():
        alpha, beta = affine
        running_var, mean_run = norm.running_var, norm.running_mean
        assert running_var is not None and mean_run is not None  # eval_affine checked them
        inv_std = torch.rsqrt(running_var + norm.eps)
        z = conv(image)
        mask = z > 0
        relu_z = torch.relu(z)
        features = (alpha[:, None, None] * relu_z + beta[:, None, None]).flatten(1)
        vector = trunk.vector_scale * torch.cat(vectors, dim=-1) if vectors else None
        h_in = features if vector is None else torch.cat([features, vector], dim=-1)
        inputs, outputs = [], []  # of each FC layer: its input, its tanh output
        h = h_in
        for layer in linears:
            inputs.append(h)
            h = torch.tanh(layer(h))
            outputs.append(h)
        q = policy.head(h)
        squash = torch.tanh(q) if policy.kind == "gaussian" else None
        # the weights the tangent multiplies, as they are now (the line search moves θ later)
        weights = [m.weight.detach().clone() for m in linears]
        weights[0] = weights[0][:, : features.shape[1]]
        head_weight = policy.head.weight.detach().clone()
    names = {id(p): n for n, p in policy.named_parameters()}

    def name(p: Tensor | None) -> str:
        assert p is not None
        return names[id(p)]

    @torch.no_grad()
    def jv(v: dict[str, Tensor]) -> tuple[Tensor, ...]:
        dz = nn.functional.conv2d(
            image,
            v[name(conv.weight)],
            v[name(conv.bias)],
            conv.stride,
            conv.padding,
            conv.dilation,
            conv.groups,
        )
        d_alpha = v[name(norm.weight)] * inv_std
        d_beta = v[name(norm.bias)] - mean_run * d_alpha
        dy = d_alpha[:, None, None] * relu_z + alpha[:, None, None] * (dz * mask)
        dy = (dy + d_beta[:, None, None]).flatten(1)
        dh: Tensor | None = None
        for k, (layer, w, x, y) in enumerate(zip(linears, weights, inputs, outputs, strict=True)):
            dw, db = v[name(layer.weight)], v[name(layer.bias)]
            d_in = dy if k == 0 else dh
            assert d_in is not None
            da = torch.addmm(db, x, dw.T).addmm_(d_in, w.T)
            dh = (1 - y * y) * da
        assert dh is not None
        head = policy.head
        dq = torch.addmm(v[name(head.bias)], outputs[-1], v[name(head.weight)].T)
        dq = dq.addmm_(dh, head_weight.T)
        if squash is None:
            return (dq,)
        return policy.action_half * (1 - squash * squash) * dq, v[name(policy.log_std)]

    return jv
