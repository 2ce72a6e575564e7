"""Policy and value networks of the study (Vedeler 2019, Sect. "Networks"), in float32 PyTorch.

Trunks (chosen from the observation space by :func:`make_trunk`):

===================  =====================================  =====================================
observation          input tensor(s)                        trunk
===================  =====================================  =====================================
``Box`` vector (D,)  (B, D) float, normalised               MLP: Linear-tanh 400, Linear-tanh 300
``Box`` uint8 image  (B, C, H, W) float in [0, 1]           CNN: Conv 10×7×7 stride 4 → ReLU →
(C, H, W)                                                   BatchNorm → flatten → MLP 400-300
``Dict``: one image  {"radar": (B, C, H, W),                the CNN, with the vector parts
+ vector parts       "goal": (B, 2)}                        concatenated after the flatten
                                                            ("late fusion"), keys sorted
===================  =====================================  =====================================

With the study's radar image (1, 50, 119) the convolution gives 10 × 11 × 29 = 3190 features.

Balanced fusion (``NetworkConfig.balanced_fusion``, used by the radar setups; a departure from
the study): the V vector features (the 2-D goal; for the GAIL discriminator also the action) are
multiplied by the fixed factor sqrt(3190 / V) ≈ 40 before the concatenation, so that the image
and the vectors bring the same input variance to FC 1 (the conv features have unit variance
after BatchNorm, the vectors are standardised). Without it the goal is 2 of 3192 unit-variance
inputs: the random FC features of a fresh network explain 64-70 % of the variance of a
goal-homing action (ridge fit; 90-95 % with the factor, 92-93 % for the positional MLP), and
TRPO's rl-gaussian-radar spent its first ~170 iterations leaving the area (~55 of ~70 episodes
per iteration still at iteration 38) before it learned to use the goal. With it: out-of-area
episodes fell to ~8 per iteration by iteration 10, validation reached 14/15 at iteration 60
(3/15 without) and the shipped model's run its first 15/15 at iteration 65 (230 without);
rl-categorical-radar went from 80 iterations to 15; behavioural cloning of the radar expert:
15/15 and 10.4 m from the expert's paths, against 14/15 and 13.2 m (``usvsim.evaluation.likeness``).

The hidden activation of the fully connected layers is tanh for both trunks (the study gives it
for the MLP only).

Set encoder (``NetworkConfig.set_encoder``, a departure from the study for the k-nearest ``scene``
form; Zaheer et al. 2017, "Deep Sets"): the vector is read as ``set_layout = (own, slot)`` own
features followed by slots of ``slot`` features whose last one is the validity flag (1 for an
obstacle; an empty slot all zeros, as the ``scene`` scaling leaves it). One shared MLP
``set_encoder`` maps each slot, its outputs are pooled over the valid slots (mean and max; zeros
without one) and joined to the own features before the MLP 400-300. The input order of the
obstacles no longer matters, and an obstacle moving from slot 3 to slot 2 as the ranges change
is the same input (to a plain MLP it is a jump).

Heads (:func:`make_policy`, :func:`make_critic`):

- Gaussian (``Box`` actions, shape (A,)): mean = c + h · tanh(W f + b) with c, h the centre and
  half-width of the action box, so the mean always lies inside the bounds. The study passes the
  output through a sigmoid scaled to the range, low + (high − low) · σ(z) = c + h · tanh(z / 2):
  the same squashing with the input scale halved; tanh is used because a zero output is the
  range's centre (no heading change) with the usual initialisation. The log standard deviation
  is one learned vector, independent of the state. Samples are *not* squashed: a sample outside
  the bounds is clipped by the rollout before it reaches the environment (its log-probability is
  that of the unclipped sample, as in Stable-Baselines3).
- Categorical (``Discrete(K)``, the study's K = 41 heading-change bins): K logits.
- Critic: the same trunk shape with its own weights, and one linear output V(s).

BatchNorm and TRPO: the natural-gradient step needs one deterministic policy function, so the
policy is always evaluated in eval mode (running statistics), in rollouts and in the TRPO step
alike. Its running statistics are refreshed between iterations by :func:`refresh_batchnorm`
(train-mode passes of the convolution only, no gradients). The critic trains in train mode
(batch statistics) and predicts in eval mode, as usual.

Fused passes (:func:`fused_passes`, the agents' updates): in eval mode the CNN trunk's ReLU and
BatchNorm are folded into the convolution and FC 1, and FC 1 takes the image and the vectors as
two products instead of one concatenation. The same function (tested against the plain passes:
values, gradients, forward-mode derivatives); it saves memory passes over the (B, 3190) features,
not arithmetic. Rollouts, acting and evaluation run the plain passes, so that a trained policy's
actions do not depend on whether it is being trained.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from torch import Tensor, nn

from learning.algorithms.distributions import ActionDistribution, Categorical, DiagGaussian
from learning.algorithms.normalization import is_image_space

__all__ = [
    "CNNTrunk",
    "Critic",
    "MLPTrunk",
    "NetworkConfig",
    "Policy",
    "TensorObs",
    "fused_passes",
    "make_critic",
    "make_policy",
    "make_trunk",
    "obs_to_tensor",
    "refresh_batchnorm",
    "rows",
    "space_from_spec",
    "space_to_spec",
]

TensorObs = Tensor | dict[str, Tensor]


@dataclass(frozen=True)
class NetworkConfig:
    """Layer sizes (study defaults) and the initial policy spread."""

    hidden: tuple[int, ...] = (400, 300)  # fully connected widths, study
    conv_kernels: int = 10  # study
    conv_size: int = 7  # kernel side, pixels, study
    conv_stride: int = 4  # pixels, study
    init_std_fraction: float = 0.5  # initial Gaussian σ as a fraction of the action half-width
    # late fusion with the vector parts scaled by sqrt(conv features / vector features), so that
    # both parts carry the same input variance into FC 1 (module docstring, "Balanced fusion")
    balanced_fusion: bool = False
    # vector observations: a Deep Sets encoder over slots (module docstring, "Set encoder");
    # () is the study's plain MLP
    set_encoder: tuple[int, ...] = ()
    set_layout: tuple[int, int] = (4, 6)  # own features, features per slot (the scene form)


def _mlp(in_features: int, hidden: Sequence[int]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for width in hidden:
        linear = nn.Linear(in_features, width)
        nn.init.orthogonal_(linear.weight, math.sqrt(2.0))
        nn.init.zeros_(linear.bias)
        layers += [linear, nn.Tanh()]
        in_features = width
    return nn.Sequential(*layers)


class MLPTrunk(nn.Module):
    """(B, D) → (B, hidden[-1])."""

    def __init__(self, in_features: int, hidden: Sequence[int]) -> None:
        super().__init__()
        self.body = _mlp(in_features, hidden)
        self.out_features = hidden[-1] if hidden else in_features

    def forward(self, obs: TensorObs) -> Tensor:
        assert isinstance(obs, Tensor)
        return self.body(obs)


class SetTrunk(nn.Module):
    """(B, own + slot · k) → (B, hidden[-1]) through a per-slot encoder and pooling (module
    docstring, "Set encoder")."""

    def __init__(self, in_features: int, cfg: NetworkConfig) -> None:
        super().__init__()
        own, slot = cfg.set_layout
        if (in_features - own) % slot or in_features <= own:
            raise ValueError(
                f"set_layout {cfg.set_layout} does not divide an observation of {in_features}"
            )
        self.own, self.slot = own, slot
        self.encoder = _mlp(slot, cfg.set_encoder)
        width = cfg.set_encoder[-1]
        self.body = _mlp(own + 2 * width, cfg.hidden)
        self.out_features = cfg.hidden[-1] if cfg.hidden else own + 2 * width

    def forward(self, obs: TensorObs) -> Tensor:
        assert isinstance(obs, Tensor)
        slots = obs[:, self.own :].reshape(obs.shape[0], -1, self.slot)  # (B, k, slot)
        valid = (slots[..., -1:] > 0.5).to(obs.dtype)  # (B, k, 1)
        h = self.encoder(slots) * valid
        count = valid.sum(dim=1)
        mean = h.sum(dim=1) / count.clamp(min=1.0)
        peak = torch.where(valid > 0, h, torch.full_like(h, -torch.inf)).amax(dim=1)
        peak = torch.where(count > 0, peak, torch.zeros_like(peak))
        return self.body(torch.cat([obs[:, : self.own], mean, peak], dim=-1))


class CNNTrunk(nn.Module):
    """Image (B, C, H, W) [+ late-fused vectors (B, V)] → (B, hidden[-1]); see the module table."""

    def __init__(
        self,
        image_shape: tuple[int, int, int],
        image_key: str | None,
        vector_keys: Sequence[str],
        vector_features: int,
        cfg: NetworkConfig,
    ) -> None:
        super().__init__()
        c, h, w = image_shape
        self.image_key, self.vector_keys = image_key, list(vector_keys)
        self.conv = nn.Conv2d(c, cfg.conv_kernels, cfg.conv_size, stride=cfg.conv_stride)
        nn.init.orthogonal_(self.conv.weight, math.sqrt(2.0))
        assert self.conv.bias is not None
        nn.init.zeros_(self.conv.bias)
        self.norm = nn.BatchNorm2d(cfg.conv_kernels)
        h_out = (h - cfg.conv_size) // cfg.conv_stride + 1
        w_out = (w - cfg.conv_size) // cfg.conv_stride + 1
        self.conv_features = cfg.conv_kernels * h_out * w_out
        balanced = cfg.balanced_fusion and vector_features > 0
        self.vector_scale = math.sqrt(self.conv_features / vector_features) if balanced else 1.0
        self.fc = _mlp(self.conv_features + vector_features, cfg.hidden)
        self.out_features = cfg.hidden[-1]
        self.fused = False  # the faster passes of the same function (fused_passes)

    def image_features(self, image: Tensor) -> Tensor:
        """Conv → ReLU → BatchNorm → flatten: (B, C, H, W) → (B, conv_features)."""
        return self.norm(torch.relu(self.conv(image))).flatten(1)

    @property
    def fc1(self) -> nn.Linear:
        """FC 1, of [conv features, vector parts] (B, conv_features + V) → (B, hidden[0])."""
        layer = self.fc[0]
        assert isinstance(layer, nn.Linear)
        return layer

    def eval_affine(self) -> tuple[Tensor, Tensor] | None:
        """The eval-mode BatchNorm as the per-channel map y = α x + β (α, β of shape (K,)):
        α = γ / sqrt(σ² + ε), β = b − μ α from the running statistics; ``None`` in train mode
        (batch statistics) or without running statistics."""
        norm = self.norm
        if norm.training or norm.running_mean is None or norm.running_var is None:
            return None
        alpha = torch.rsqrt(norm.running_var + norm.eps)
        if norm.weight is not None:
            alpha = norm.weight * alpha
        beta = -norm.running_mean * alpha
        if norm.bias is not None:
            beta = norm.bias + beta
        return alpha, beta

    def folded_first_layer(self, image: Tensor, alpha: Tensor, beta: Tensor) -> Tensor:
        """FC 1's pre-activation from the image part, W_img · features + b (B, hidden[0]), with
        the eval-mode BatchNorm y = α x + β (:meth:`eval_affine`) folded in.

        Per channel α·relu(z) + β = s·relu(|α| z) + β with s = sign α: |α| scales the
        convolution's weight and bias, s the matching columns of W_img, and W_img β joins the
        bias, so that neither the ReLU nor the BatchNorm is a pass of its own over the
        (B, conv_features) features. The same function of the same parameters (gradients and
        forward-mode derivatives included); float32 rounding differs (tested).
        """
        fc1, conv = self.fc1, self.conv
        assert conv.bias is not None
        w_img = fc1.weight[:, : self.conv_features]
        scale, per_channel = alpha.abs(), self.conv_features // alpha.shape[0]
        z = nn.functional.conv2d(
            image, conv.weight * scale[:, None, None, None], conv.bias * scale, conv.stride
        )
        sign = alpha.sign().repeat_interleave(per_channel)
        bias = torch.addmv(fc1.bias, w_img, beta.repeat_interleave(per_channel))
        return nn.functional.linear(torch.relu(z).flatten(1), w_img * sign, bias)

    def split(self, obs: TensorObs) -> tuple[Tensor, list[Tensor]]:
        if isinstance(obs, Tensor):
            return obs, []
        assert self.image_key is not None
        return obs[self.image_key], [obs[k] for k in self.vector_keys]

    def forward(self, obs: TensorObs) -> Tensor:
        image, vectors = self.split(obs)
        affine = self.eval_affine() if self.fused else None
        if affine is None:  # the passes as the module table writes them
            x = self.image_features(image)
            if vectors:
                x = torch.cat([x, *(self.vector_scale * v for v in vectors)], dim=-1)
            out: Tensor = self.fc(x)
            return out
        # FC 1 of [features, vectors] as W_img · features + W_vec · vectors: no (B, 3192) copy
        h = self.folded_first_layer(image, *affine)
        if vectors:
            w_vec = self.fc1.weight[:, self.conv_features :]
            h = h + nn.functional.linear(self.vector_scale * torch.cat(vectors, dim=-1), w_vec)
        out = self.fc[1:](h)
        return out


@contextlib.contextmanager
def fused_passes(*nets: nn.Module) -> Iterator[None]:
    """Within the block, every CNN trunk of ``nets`` in eval mode runs with the ReLU and the
    BatchNorm folded into the convolution and FC 1, and FC 1 split by part (no concatenation)
    (:meth:`CNNTrunk.folded_first_layer`): the same function, float32 rounding apart, with less
    memory traffic (``benchmarks/radar_update.py``). Train mode (batch statistics: the critic's
    fit) runs the plain passes.

    The agents' updates run inside it; acting, rollouts and evaluation do not, so a policy's
    actions are bit for bit those of the plain passes (a Gaussian radar policy's closed loop
    turns a 1e-7 change of an action into metres over an episode)."""
    trunks = [m for net in nets for m in net.modules() if isinstance(m, CNNTrunk)]
    before = [t.fused for t in trunks]
    for t in trunks:
        t.fused = True
    try:
        yield
    finally:
        for t, was in zip(trunks, before, strict=True):
            t.fused = was


def make_trunk(space: spaces.Space, cfg: NetworkConfig) -> MLPTrunk | CNNTrunk | SetTrunk:
    """The trunk for one observation ``space`` (see the module table)."""
    if isinstance(space, spaces.Box) and is_image_space(space):
        shape = (int(space.shape[0]), int(space.shape[1]), int(space.shape[2]))
        return CNNTrunk(shape, None, [], 0, cfg)
    if isinstance(space, spaces.Box) and cfg.set_encoder:
        return SetTrunk(int(np.prod(space.shape)), cfg)
    if isinstance(space, spaces.Box):
        return MLPTrunk(int(np.prod(space.shape)), cfg.hidden)
    if isinstance(space, spaces.Dict):
        images = [k for k, s in space.spaces.items() if is_image_space(s)]
        if len(images) != 1:
            raise ValueError(f"a Dict observation needs exactly one image part, got {images}")
        vector_keys = sorted(k for k in space.spaces if k != images[0])
        for k in vector_keys:
            sub = space.spaces[k]
            if not (isinstance(sub, spaces.Box) and len(sub.shape) == 1):
                raise ValueError(f"Dict part {k!r} must be a 1-D Box, got {sub}")
        n_vec = sum(int(np.prod(space.spaces[k].shape or ())) for k in vector_keys)
        img_shape = space.spaces[images[0]].shape or ()
        shape = (int(img_shape[0]), int(img_shape[1]), int(img_shape[2]))
        return CNNTrunk(shape, images[0], vector_keys, n_vec, cfg)
    raise TypeError(f"unsupported observation space {space}")


class Policy(nn.Module):
    """π(a|s): trunk + Gaussian or categorical head; ``forward`` returns the distribution."""

    def __init__(
        self,
        trunk: MLPTrunk | CNNTrunk | SetTrunk,
        action_space: spaces.Space,
        cfg: NetworkConfig,
    ) -> None:
        super().__init__()
        self.trunk = trunk
        self.action_space = action_space
        if isinstance(action_space, spaces.Discrete):
            self.kind = "categorical"
            self.head = nn.Linear(trunk.out_features, int(action_space.n))
        elif isinstance(action_space, spaces.Box) and len(action_space.shape) == 1:
            self.kind = "gaussian"
            low = torch.as_tensor(action_space.low, dtype=torch.float32)
            high = torch.as_tensor(action_space.high, dtype=torch.float32)
            if not (torch.isfinite(low).all() and torch.isfinite(high).all()):
                raise ValueError("a Gaussian policy needs finite action bounds")
            self.action_centre: Tensor
            self.action_half: Tensor
            self.register_buffer("action_centre", (high + low) / 2)
            self.register_buffer("action_half", (high - low) / 2)
            self.head = nn.Linear(trunk.out_features, int(action_space.shape[0]))
            init = torch.log(cfg.init_std_fraction * (high - low) / 2)
            self.log_std = nn.Parameter(init.clone())
        else:
            raise TypeError(f"unsupported action space {action_space}")
        nn.init.orthogonal_(self.head.weight, 0.01)
        nn.init.zeros_(self.head.bias)

    def forward(self, obs: TensorObs) -> ActionDistribution:
        z = self.head(self.trunk(obs))
        if self.kind == "categorical":
            return Categorical(z)
        return DiagGaussian(self.action_centre + self.action_half * torch.tanh(z), self.log_std)


class Critic(nn.Module):
    """V(s): trunk + one linear output; ``forward`` returns (B,)."""

    def __init__(self, trunk: MLPTrunk | CNNTrunk | SetTrunk) -> None:
        super().__init__()
        self.trunk = trunk
        self.head = nn.Linear(trunk.out_features, 1)
        nn.init.orthogonal_(self.head.weight, 1.0)
        nn.init.zeros_(self.head.bias)

    def forward(self, obs: TensorObs) -> Tensor:
        return self.head(self.trunk(obs)).squeeze(-1)


def make_policy(
    observation_space: spaces.Space, action_space: spaces.Space, cfg: NetworkConfig | None = None
) -> Policy:
    """The policy network for single-env spaces, in eval mode (see the module docstring)."""
    cfg = cfg or NetworkConfig()
    return Policy(make_trunk(observation_space, cfg), action_space, cfg).eval()


def make_critic(observation_space: spaces.Space, cfg: NetworkConfig | None = None) -> Critic:
    """The value network for a single-env observation space."""
    cfg = cfg or NetworkConfig()
    return Critic(make_trunk(observation_space, cfg))


def rows(obs: TensorObs, idx: Tensor | slice) -> TensorObs:
    """The rows ``idx`` of a batch of tensor observations (a tensor or a dict of them); a slice
    gives views, an index tensor copies."""
    return {k: v[idx] for k, v in obs.items()} if isinstance(obs, dict) else obs[idx]


def obs_to_tensor(obs: np.ndarray | dict[str, np.ndarray]) -> TensorObs:
    """Normalised numpy observation(s) → float32 tensor(s) sharing memory where possible."""
    if isinstance(obs, dict):
        return {k: torch.as_tensor(v, dtype=torch.float32) for k, v in obs.items()}
    return torch.as_tensor(obs, dtype=torch.float32)


@torch.no_grad()
def refresh_batchnorm(net: nn.Module, obs: TensorObs, batch_size: int = 256) -> None:
    """Update the running statistics of every CNN trunk's BatchNorm from ``obs`` (no gradients).

    Train-mode passes of the convolution only, over chunks of ``batch_size`` rows (momentum as
    configured in the layer); the network's mode is restored afterwards. No-op for MLP trunks.
    """
    for module in net.modules():
        if not isinstance(module, CNNTrunk):
            continue
        image, _ = module.split(obs)
        was_training = module.norm.training
        module.norm.train()
        for start in range(0, image.shape[0], batch_size):
            module.image_features(image[start : start + batch_size])
        module.norm.train(was_training)


def space_to_spec(space: spaces.Space) -> dict[str, Any]:
    """A plain-data description of a Box, Discrete or Dict space (saved in checkpoints)."""
    if isinstance(space, spaces.Box):
        return {
            "type": "Box",
            "shape": list(space.shape),
            "dtype": str(space.dtype),
            "low": space.low.tolist(),
            "high": space.high.tolist(),
        }
    if isinstance(space, spaces.Discrete):
        return {"type": "Discrete", "n": int(space.n), "start": int(space.start)}
    if isinstance(space, spaces.Dict):
        return {"type": "Dict", "spaces": {k: space_to_spec(s) for k, s in space.spaces.items()}}
    raise TypeError(f"unsupported space {space}")


def space_from_spec(spec: dict[str, Any]) -> spaces.Space:
    """Inverse of :func:`space_to_spec`."""
    if spec["type"] == "Box":
        dtype = np.dtype(spec["dtype"])
        return spaces.Box(
            np.asarray(spec["low"], dtype=dtype),
            np.asarray(spec["high"], dtype=dtype),
            tuple(spec["shape"]),
            dtype=dtype,
        )
    if spec["type"] == "Discrete":
        return spaces.Discrete(spec["n"], start=spec["start"])
    if spec["type"] == "Dict":
        return spaces.Dict({k: space_from_spec(s) for k, s in spec["spaces"].items()})
    raise ValueError(f"unknown space type {spec['type']!r}")
