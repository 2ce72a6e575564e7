"""J v of a CNN policy with its forward pass kept (``learning.algorithms.linearized``) against
``torch.func.jvp`` of the policy itself, in float64."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from gymnasium import spaces

from learning.algorithms.linearized import linearize_cnn_policy, supports
from learning.algorithms.networks import NetworkConfig, Policy, make_policy
from learning.algorithms.trust_region import policy_jvp

RADAR_GOAL = spaces.Dict(
    {
        "radar": spaces.Box(0, 255, (1, 15, 19), np.uint8),
        "goal": spaces.Box(-5.0, 5.0, (2,), np.float32),
    }
)
CFG = NetworkConfig(hidden=(6, 5), conv_kernels=3, conv_size=3, conv_stride=2)


def _policy(action_space: spaces.Space, balanced: bool) -> Policy:
    torch.manual_seed(0)
    cfg = NetworkConfig(**{**CFG.__dict__, "balanced_fusion": balanced})
    policy = make_policy(RADAR_GOAL, action_space, cfg).double()
    with torch.no_grad():  # a head that is not almost zero; BatchNorm with γ < 0 on one channel
        policy.head.weight.normal_()
        norm = policy.trunk.norm
        norm.running_mean.uniform_(0.1, 0.3)
        norm.running_var.uniform_(0.5, 2.0)
        norm.weight.copy_(torch.tensor([0.8, -1.3, 1.1]))
        norm.bias.uniform_(-0.2, 0.2)
    return policy


def _obs(n: int) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(1)
    return {
        "radar": (torch.rand((n, 1, 15, 19), generator=g, dtype=torch.float64) < 0.2).double(),
        "goal": torch.randn((n, 2), generator=g, dtype=torch.float64),
    }


@pytest.mark.parametrize("balanced", [False, True], ids=["study", "balanced"])
@pytest.mark.parametrize(
    "action_space",
    [spaces.Box(-2.0, 2.0, (2,), np.float32), spaces.Discrete(5)],
    ids=["gaussian", "categorical"],
)
def test_cached_jvp_equals_torch_func_jvp(action_space: spaces.Space, balanced: bool) -> None:
    policy, obs = _policy(action_space, balanced), _obs(7)
    named = list(policy.named_parameters())
    names = [n for n, _ in named]
    g = torch.Generator().manual_seed(2)
    tangents = tuple(torch.randn(p.shape, generator=g, dtype=torch.float64) for _, p in named)

    def dist_params(*values: torch.Tensor) -> tuple[torch.Tensor, ...]:
        return torch.func.functional_call(
            policy, dict(zip(names, values, strict=True)), (obs,)
        ).params()

    primals = tuple(p.detach() for _, p in named)
    expected = torch.func.jvp(dist_params, primals, tangents)[1]
    got = linearize_cnn_policy(policy, obs)(dict(zip(names, tangents, strict=True)))
    assert len(got) == len(expected) == (2 if policy.kind == "gaussian" else 1)
    for a, b in zip(got, expected, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-12, atol=1e-12)
    assert float(expected[0].abs().max()) > 1e-2  # not 0 == 0
    # and through the trust region's entry point (the CNN policy takes the cached path)
    for a, b in zip(policy_jvp(policy, obs, names)(tangents), expected, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-12, atol=1e-12)


def test_the_map_is_taken_at_the_parameters_of_its_creation() -> None:
    policy, obs = _policy(spaces.Discrete(5), True), _obs(4)
    names = [n for n, _ in policy.named_parameters()]
    tangents = {n: torch.ones_like(p) for n, p in policy.named_parameters()}
    jv = linearize_cnn_policy(policy, obs)
    before = jv(tangents)[0].clone()
    with torch.no_grad():  # the line search moves θ after the solve; the map does not
        for p in policy.parameters():
            p.add_(0.5)
    torch.testing.assert_close(jv(tangents)[0], before, rtol=0, atol=0)
    assert set(tangents) == set(names)


def test_other_layers_or_train_mode_are_refused() -> None:
    mlp = make_policy(spaces.Box(-1.0, 1.0, (3,), np.float32), spaces.Discrete(3), CFG)
    assert not supports(mlp)
    with pytest.raises(ValueError, match="not the module table's"):
        linearize_cnn_policy(mlp, torch.zeros(2, 3))
    policy = _policy(spaces.Discrete(5), False)
    assert supports(policy)
    policy.train()
    with pytest.raises(ValueError, match="eval mode"):
        linearize_cnn_policy(policy, _obs(3))
