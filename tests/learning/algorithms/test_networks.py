"""Networks, action distributions and observation normalisation."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from gymnasium import spaces
from torch import distributions as td

from learning.algorithms.distributions import Categorical, DiagGaussian
from learning.algorithms.networks import (
    CNNTrunk,
    NetworkConfig,
    fused_passes,
    make_critic,
    make_policy,
    refresh_batchnorm,
    space_from_spec,
    space_to_spec,
)
from learning.algorithms.normalization import ObservationNormalizer, RunningMeanStd

POSITIONAL = spaces.Box(-1e4, 1e4, (4,), np.float32)
GAUSSIAN = spaces.Box(-1.0, 1.0, (1,), np.float32)
CATEGORICAL = spaces.Discrete(41)


def _radar_goal(shape: tuple[int, int, int] = (1, 50, 119)) -> spaces.Dict:
    return spaces.Dict(
        {
            "radar": spaces.Box(0, 255, shape, np.uint8),
            "goal": spaces.Box(-5.0, 5.0, (2,), np.float32),
        }
    )


def _dict_obs(B: int, shape: tuple[int, int, int] = (1, 50, 119)) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(0)
    return {
        "radar": (torch.rand((B, *shape), generator=g) < 0.05).float(),
        "goal": torch.randn((B, 2), generator=g),
    }


def test_mlp_policy_and_critic_shapes() -> None:
    obs = torch.randn(7, 4)
    gauss = make_policy(POSITIONAL, GAUSSIAN)
    cat = make_policy(POSITIONAL, CATEGORICAL)
    critic = make_critic(POSITIONAL)
    assert [m.out_features for m in gauss.trunk.body if isinstance(m, torch.nn.Linear)] == [
        400,
        300,
    ]
    dist = gauss(obs)
    assert isinstance(dist, DiagGaussian) and dist.mean.shape == (7, 1)
    assert dist.log_std.shape == (1,)
    logits = cat(obs)
    assert isinstance(logits, Categorical) and logits.logits.shape == (7, 41)
    assert critic(obs).shape == (7,)


def test_cnn_policy_on_dict_observation() -> None:
    space = _radar_goal()
    policy = make_policy(space, GAUSSIAN)
    assert isinstance(policy.trunk, CNNTrunk)
    assert policy.trunk.conv_features == 10 * 11 * 29  # (50-7)//4+1 = 11, (119-7)//4+1 = 29
    assert policy.trunk.fc[0].in_features == 3190 + 2  # late fusion of the goal
    obs = _dict_obs(5)
    assert policy(obs).mean.shape == (5, 1)
    assert make_policy(space, CATEGORICAL)(obs).logits.shape == (5, 41)
    assert make_critic(space)(obs).shape == (5,)


def test_balanced_fusion_gives_the_goal_the_image_share_of_fc1_input_variance() -> None:
    space, obs = _radar_goal(), _dict_obs(64)
    torch.manual_seed(3)
    plain = make_policy(space, GAUSSIAN)
    torch.manual_seed(3)
    balanced = make_policy(space, GAUSSIAN, NetworkConfig(balanced_fusion=True))
    trunk = balanced.trunk
    assert isinstance(trunk, CNNTrunk)
    assert trunk.vector_scale == pytest.approx(np.sqrt(3190 / 2))
    # same weights; the only difference is the fixed factor on the goal
    scaled = {**obs, "goal": obs["goal"] * trunk.vector_scale}
    with torch.no_grad():
        torch.testing.assert_close(balanced(obs).mean, plain(scaled).mean)
        trunk.norm.train()  # batch statistics: every varying conv feature has unit variance
        image = trunk.image_features(obs["radar"])
        goal = trunk.vector_scale * obs["goal"]
    # FC 1 input power of each part: Σ over features of the batch variance
    image_power, goal_power = image.var(0).sum(), goal.var(0).sum()
    assert 0.7 < float(goal_power / image_power) < 1.4
    assert make_policy(space, GAUSSIAN).trunk.vector_scale == 1.0  # the study's fusion by default


def _plain_trunk(trunk: CNNTrunk, obs: dict[str, torch.Tensor]) -> torch.Tensor:
    """The trunk as the module docstring writes it: Conv → ReLU → BatchNorm → [·, vectors] →
    MLP, every step a pass of its own."""
    x = trunk.norm(torch.relu(trunk.conv(obs["radar"]))).flatten(1)
    return trunk.fc(torch.cat([x, trunk.vector_scale * obs["goal"]], dim=-1))


def test_fused_passes_are_the_conv_relu_batchnorm_trunk() -> None:
    torch.manual_seed(5)
    policy = make_policy(_radar_goal(), GAUSSIAN, NetworkConfig(balanced_fusion=True))
    trunk = policy.trunk
    assert isinstance(trunk, CNNTrunk)
    obs = _dict_obs(32)
    with torch.no_grad():  # running statistics away from (0, 1), two channels with γ < 0
        trunk.norm.running_mean.uniform_(0.0, 0.5)
        trunk.norm.running_var.uniform_(0.2, 2.0)
        trunk.norm.weight.uniform_(0.5, 1.5)[:2].neg_()
        trunk.norm.bias.uniform_(-0.3, 0.3)
    trunk.eval()
    assert trunk.eval_affine() is not None
    with torch.no_grad():  # outside fused_passes: the plain passes, bit for bit
        torch.testing.assert_close(trunk(obs), _plain_trunk(trunk, obs), rtol=0, atol=0)
    trunk.fused = True
    params = list(trunk.parameters())
    # values and reverse-mode gradients of every parameter
    out, plain = trunk(obs), _plain_trunk(trunk, obs)
    torch.testing.assert_close(out, plain, rtol=1e-5, atol=1e-6)
    weights = torch.randn_like(plain)
    grads = torch.autograd.grad((out * weights).sum(), params)
    plain_grads = torch.autograd.grad((plain * weights).sum(), params)
    for g, p in zip(grads, plain_grads, strict=True):  # float32 rounding of sums over 32 rows
        torch.testing.assert_close(g, p, rtol=1e-4, atol=1e-5 * float(p.abs().max()))
    # forward mode (J v of the Fisher-vector product)
    names = [n for n, _ in trunk.named_parameters()]
    primals = tuple(p.detach() for p in params)
    tangents = tuple(torch.randn_like(p) for p in primals)

    def folded(*values: torch.Tensor) -> torch.Tensor:
        out: torch.Tensor = torch.func.functional_call(
            trunk, dict(zip(names, values, strict=True)), (obs,)
        )
        return out

    class Plain(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.trunk = trunk

        def forward(self, o: dict[str, torch.Tensor]) -> torch.Tensor:
            return _plain_trunk(self.trunk, o)

    def unfolded(*values: torch.Tensor) -> torch.Tensor:
        by_name = {f"trunk.{n}": v for n, v in zip(names, values, strict=True)}
        out: torch.Tensor = torch.func.functional_call(Plain(), by_name, (obs,))
        return out

    jv = torch.func.jvp(folded, primals, tangents)[1]
    jv_plain = torch.func.jvp(unfolded, primals, tangents)[1]
    torch.testing.assert_close(jv, jv_plain, rtol=1e-4, atol=1e-5 * float(jv_plain.abs().max()))
    # train mode (batch statistics) runs the plain passes
    trunk.train()
    assert trunk.eval_affine() is None
    torch.testing.assert_close(trunk(obs), _plain_trunk(trunk, obs), rtol=0, atol=0)


def test_fused_passes_hold_only_within_the_block() -> None:
    policy = make_policy(_radar_goal(), CATEGORICAL)
    critic = make_critic(_radar_goal())
    trunks = [policy.trunk, critic.trunk]
    assert not any(t.fused for t in trunks)
    with pytest.raises(RuntimeError), fused_passes(policy, critic):
        assert all(t.fused for t in trunks)
        raise RuntimeError("an update that fails")
    assert not any(t.fused for t in trunks)


def test_cnn_image_shape_is_a_parameter() -> None:
    shape = (2, 30, 60)
    policy = make_policy(_radar_goal(shape), CATEGORICAL, NetworkConfig(hidden=(16, 8)))
    assert policy.trunk.conv_features == 10 * 6 * 14
    assert policy(_dict_obs(3, shape)).logits.shape == (3, 41)
    image_only = make_policy(spaces.Box(0, 255, shape, np.uint8), GAUSSIAN)
    assert image_only(torch.zeros(3, *shape)).mean.shape == (3, 1)


def test_gaussian_mean_stays_within_action_bounds() -> None:
    box = spaces.Box(np.array([-0.5], np.float32), np.array([2.0], np.float32))
    policy = make_policy(POSITIONAL, box)
    with torch.no_grad():
        policy.head.weight.mul_(1e4)
    with torch.no_grad():
        mean = policy(1e3 * torch.randn(1000, 4)).mean
    assert float(mean.min()) >= -0.5 and float(mean.max()) <= 2.0
    assert float(mean.min()) < 0.0 and float(mean.max()) > 1.5  # both ends are reached
    # zero features → the centre of the range (tanh(0) = 0)
    with torch.no_grad():
        policy.head.weight.zero_()
    assert policy(torch.randn(3, 4)).mean.tolist() == [[0.75]] * 3
    # initial σ = 0.5 · half-width
    assert float(policy.log_std.detach().exp()) == pytest.approx(0.5 * 1.25)


def test_eval_mode_policy_output_is_independent_of_the_batch() -> None:
    policy = make_policy(_radar_goal(), GAUSSIAN)
    obs = _dict_obs(6)
    full = policy(obs).mean
    one = policy({k: v[:1] for k, v in obs.items()}).mean
    torch.testing.assert_close(one, full[:1])


def test_refresh_batchnorm_updates_running_stats_only() -> None:
    policy = make_policy(_radar_goal(), GAUSSIAN)
    norm = policy.trunk.norm
    before = norm.running_mean.clone()
    weights = [p.detach().clone() for p in policy.parameters()]
    refresh_batchnorm(policy, _dict_obs(64), batch_size=16)
    assert not torch.equal(before, norm.running_mean)
    assert int(norm.num_batches_tracked) == 4
    assert not norm.training and not policy.training
    assert all(torch.equal(a, b) for a, b in zip(weights, policy.parameters(), strict=True))


def test_gaussian_matches_torch_distributions() -> None:
    mean, log_std = torch.randn(5, 2), torch.randn(2)
    other_mean, other_log_std = torch.randn(5, 2), torch.randn(2)
    p, q = DiagGaussian(mean, log_std), DiagGaussian(other_mean, other_log_std)
    ref_p = td.Independent(td.Normal(mean, log_std.exp()), 1)
    ref_q = td.Independent(td.Normal(other_mean, other_log_std.exp()), 1)
    a = torch.randn(5, 2)
    torch.testing.assert_close(p.log_prob(a), ref_p.log_prob(a))
    torch.testing.assert_close(p.entropy(), ref_p.entropy())
    torch.testing.assert_close(p.kl(q), td.kl_divergence(ref_p, ref_q))


def test_categorical_matches_torch_distributions() -> None:
    logits, other = torch.randn(5, 41), torch.randn(5, 41)
    p, q = Categorical(logits), Categorical(other)
    ref_p, ref_q = td.Categorical(logits=logits), td.Categorical(logits=other)
    a = torch.tensor([0, 3, 40, 7, 20])
    torch.testing.assert_close(p.log_prob(a), ref_p.log_prob(a))
    torch.testing.assert_close(p.entropy(), ref_p.entropy())
    torch.testing.assert_close(p.kl(q), td.kl_divergence(ref_p, ref_q))
    assert p.mode().tolist() == logits.argmax(-1).tolist()


def test_running_mean_std_equals_numpy_over_all_batches() -> None:
    rng = np.random.default_rng(0)
    batches = [rng.normal(3.0, 2.0, (n, 4)) for n in (1, 17, 200)]
    rms = RunningMeanStd((4,))
    for b in batches:
        rms.update(b)
    every = np.concatenate(batches)
    np.testing.assert_allclose(rms.mean, every.mean(0), rtol=1e-12)
    np.testing.assert_allclose(rms.var, every.var(0), rtol=1e-12)
    assert rms.count == 218


def test_observation_normalizer_dict_and_round_trip() -> None:
    space = _radar_goal()
    norm = ObservationNormalizer(space, clip=5.0)
    rng = np.random.default_rng(1)
    obs = {
        "radar": np.full((10, 1, 50, 119), 255, np.uint8),
        "goal": rng.normal(2.0, 3.0, (10, 2)).astype(np.float32),
    }
    norm.update(obs)
    out = norm(obs)
    assert isinstance(out, dict)
    assert out["radar"].dtype == np.float32 and float(out["radar"].max()) == 1.0
    np.testing.assert_allclose(out["goal"].mean(0), 0.0, atol=1e-6)
    np.testing.assert_allclose(out["goal"].std(0), 1.0, atol=1e-6)
    again = ObservationNormalizer(space, clip=5.0)
    again.load_state_dict(norm.state_dict())
    np.testing.assert_array_equal(again(obs)["goal"], out["goal"])  # type: ignore[index]
    with pytest.raises(ValueError, match="keys mismatch"):
        ObservationNormalizer(POSITIONAL).load_state_dict(norm.state_dict())
    with pytest.raises(ValueError, match="non-finite"):
        norm.update({"radar": obs["radar"], "goal": np.full((1, 2), np.nan, np.float32)})


def test_space_spec_round_trip() -> None:
    for space in (POSITIONAL, GAUSSIAN, CATEGORICAL, _radar_goal()):
        assert space_from_spec(space_to_spec(space)) == space


def test_scene_scaling_is_fixed_and_zeroes_empty_slots() -> None:
    """``scaling="scene"``: no statistics to drift, an empty slot all zeros, a rarely filled
    slot's obstacle on the same scale as the first slot's (running stats would blow it up)."""
    from learning.algorithms.normalization import ObservationNormalizer
    from usvsim.task.observations import SCENE_FEATURES, observation_space

    space = observation_space("scene")
    norm = ObservationNormalizer(space, scaling="scene")
    running = ObservationNormalizer(space)
    obs = np.zeros((200, 52), dtype=np.float32)
    obs[:, 0], obs[:, 4:10] = 100.0, [30.0, 0.5, 1.0, -3.0, 0.0, 1.0]
    obs[0, 4 + SCENE_FEATURES * 7 : 4 + SCENE_FEATURES * 8] = [30.0, 0.5, 1.0, -3.0, 0.0, 1.0]
    norm.update(obs)
    running.update(obs)
    z, zr = norm(obs), running(obs)
    assert norm.state_dict() == {}
    assert np.array_equal(z[0, 4:10], z[0, -6:])  # the same obstacle, the same inputs
    assert np.all(z[1, -6:] == 0.0)  # an empty slot
    assert np.abs(zr[0, -6:]).max() == 10.0  # running statistics: clipped at ±10
    with pytest.raises(ValueError, match="observation scaling must be one of"):
        ObservationNormalizer(space, scaling="minmax")


def test_set_encoder_ignores_slot_order_and_empty_slots() -> None:
    """Deep Sets trunk: permuting the valid slots, or what an empty slot holds, changes nothing;
    changing an obstacle does."""
    from learning.algorithms.networks import NetworkConfig, SetTrunk, make_trunk
    from usvsim.task.observations import observation_space

    cfg = NetworkConfig(set_encoder=(32, 32))
    trunk = make_trunk(observation_space("scene"), cfg)
    assert isinstance(trunk, SetTrunk)
    g = torch.Generator().manual_seed(0)
    obs = torch.randn(5, 52, generator=g)
    slots = obs[:, 4:].reshape(5, 8, 6)
    slots[:, :3, 5], slots[:, 3:, 5] = 1.0, 0.0  # three obstacles, five empty slots
    base = trunk(obs)
    swapped = slots[:, [2, 0, 1, 3, 4, 5, 6, 7]].reshape(5, -1)
    assert torch.allclose(trunk(torch.cat([obs[:, :4], swapped], 1)), base, atol=1e-6)
    junk = slots.clone()
    junk[:, 3:, :5] = 99.0  # an empty slot's other entries do not count
    assert torch.allclose(trunk(torch.cat([obs[:, :4], junk.reshape(5, -1)], 1)), base, atol=1e-6)
    moved = slots.clone()
    moved[:, 0, 0] += 1.0
    assert not torch.allclose(trunk(torch.cat([obs[:, :4], moved.reshape(5, -1)], 1)), base)
    with pytest.raises(ValueError, match="set_layout"):
        SetTrunk(51, cfg)
