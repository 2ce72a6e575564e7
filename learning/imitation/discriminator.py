"""The GAIL discriminator D_w(s, a) = σ(f_w(s, a, z)), what feeds it and how it learns (Ho &
Ermon 2016; absorbing states after Kostrikov et al. 2019): :class:`GAILConfig`, the network,
the action normalisation, the reward forms computed from its logits, and
:class:`GAILTrainer` (its Adam steps and the imitation rewards of a batch). The module
docstring of :mod:`learning.imitation.gail` has the input table and the algorithm.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal, get_args

import numpy as np
import torch
from gymnasium import spaces
from numpy.typing import NDArray
from torch import Tensor, nn
from torch.nn import functional

from learning.algorithms.networks import NetworkConfig, make_trunk
from learning.algorithms.rollout import Obs, RolloutBatch, flatten_obs
from learning.imitation.preprocess import ExpertData
from usvsim.task.batch import N_CATEGORIES
from usvsim.task.observations import (
    POSITIONAL_STANDARDIZATION,
    SCENE_FEATURES,
    SCENE_K,
    SCENE_STANDARDIZATION,
    observation_space,
    standardize_scene,
)

SCENE_WIDTH = 4 + SCENE_FEATURES * SCENE_K  # floats of a scene observation (its standardisation)
_SCENE_SPACE = observation_space("scene")

__all__ = [
    "DISC_OBSERVATIONS",
    "N_ABSORBING",
    "REWARDS",
    "SCENE_INFO_KEY",
    "DiscObservation",
    "Discriminator",
    "GAILConfig",
    "GAILTrainer",
    "RewardKind",
    "cat_obs",
    "index_obs",
    "normalize_actions",
    "reward_from_logits",
]

RewardKind = Literal["-log(1-D)", "logit", "log_d"]
REWARDS: tuple[str, ...] = get_args(RewardKind)
DiscObservation = Literal["policy", "scene"]
DISC_OBSERVATIONS: tuple[str, ...] = get_args(DiscObservation)
SCENE_INFO_KEY = "observation_scene"  # usvsim.task.openwater_env: info_observation="scene"
N_ABSORBING = 2  # [goal end, collision end]
STATE_FORMAT = "usvsim.learning.gail/1"


def normalize_actions(actions: NDArray[Any], space: spaces.Space) -> NDArray[np.float32]:
    """Env actions → heading change as a fraction of the bound, (B, 1) in [-1, 1]."""
    a = np.asarray(actions)
    if isinstance(space, spaces.Discrete):
        half = (N_CATEGORIES - 1) / 2
        return ((a.reshape(-1, 1).astype(np.float32) - half) / half).astype(np.float32)
    return np.clip(a.reshape(-1, 1), -1.0, 1.0).astype(np.float32)


def reward_from_logits(logits: Tensor, kind: RewardKind) -> Tensor:
    """Policy reward from discriminator logits f (D = σ(f)); step 3 of
    :mod:`learning.imitation.gail`."""
    if kind == "-log(1-D)":
        return functional.softplus(logits)  # −log(1 − σ(f)) = log(1 + e^f)
    if kind == "logit":
        return logits
    if kind == "log_d":
        return -functional.softplus(-logits)  # log σ(f)
    raise ValueError(f"reward must be one of {REWARDS}, got {kind!r}")


class Discriminator(nn.Module):
    """f_w(s, a, z) → logit (B,); trunks as the policy's (module table)."""

    def __init__(
        self, observation_space: spaces.Space, hidden: tuple[int, ...], balanced: bool = False
    ) -> None:
        super().__init__()
        extra = spaces.Box(-np.inf, np.inf, (1 + N_ABSORBING,), dtype=np.float32)
        cfg = NetworkConfig(hidden=hidden, balanced_fusion=balanced)
        if isinstance(observation_space, spaces.Dict):
            space: spaces.Space = spaces.Dict({**observation_space.spaces, "zz_action": extra})
        elif isinstance(observation_space, spaces.Box) and len(observation_space.shape) == 3:
            space = spaces.Dict({"image": observation_space, "zz_action": extra})
        else:
            size = int(np.prod(observation_space.shape or ())) + extra.shape[0]
            space = spaces.Box(-np.inf, np.inf, (size,), dtype=np.float32)
        self.kind = "image" if isinstance(space, spaces.Dict) else "vector"
        self.trunk = make_trunk(space, cfg)
        self.head = nn.Linear(self.trunk.out_features, 1)

    def forward(self, obs: Tensor | dict[str, Tensor], az: Tensor) -> Tensor:
        """``obs`` standardised (:meth:`learning.imitation.gail.GAILTrainer.disc_obs`),
        ``az`` (B, 3) = [a, z]."""
        if isinstance(obs, dict):
            return self.head(self.trunk({**obs, "zz_action": az})).squeeze(-1)
        return self.head(self.trunk(torch.cat([obs, az], dim=-1))).squeeze(-1)


def _obs_to(obs: Tensor | dict[str, Tensor], device: torch.device) -> Any:
    return {k: v.to(device) for k, v in obs.items()} if isinstance(obs, dict) else obs.to(device)


def index_obs(obs: Obs | dict[str, Tensor] | Tensor, idx: Any) -> Any:
    """Rows ``idx`` of observations (an array or tensor, or a dict of them)."""
    return {k: v[idx] for k, v in obs.items()} if isinstance(obs, dict) else obs[idx]


def cat_obs(parts: list[Any]) -> Any:
    """Tensor observations (tensors or dicts of tensors) concatenated along axis 0."""
    if isinstance(parts[0], dict):
        return {k: torch.cat([p[k] for p in parts]) for k in parts[0]}
    return torch.cat(parts)


@dataclass(frozen=True)
class GAILConfig:
    """Hyperparameters of the discriminator and the imitation reward."""

    reward: RewardKind = "-log(1-D)"  # one of REWARDS (module docstring, step 3)
    disc_hidden: tuple[int, ...] = (400, 300)  # study: the policy's trunk widths
    balanced_fusion: bool = False  # D's CNN: learning.algorithms.networks.NetworkConfig
    disc_lr: float = 3e-4  # Adam
    disc_steps: int = 10  # Adam steps per iteration
    disc_minibatch: int = 256  # expert pairs and as many policy pairs per step
    gradient_penalty: float = 0.0  # λ_GP (Gulrajani et al. 2017 form, as in Kostrikov 2019)
    entropy_bonus: float = 0.0  # λ_H, nats → reward
    absorbing: bool = True  # absorbing states at terminations (module docstring)
    reward_clip: float = 10.0  # |r| per step at most (keeps GAE finite when D saturates)
    bc_epochs: int = 0  # behavioural-cloning warm start (epochs over the expert data)
    bc_lr: float = 1e-3
    bc_minibatch: int = 128
    policy_warmup: int = 0  # iterations with the policy frozen (δ → 1e-9) after the warm start
    freeze_input_stats: bool = False
    # keep the policy's observation-normaliser and BatchNorm statistics at the expert's (fitted
    # by the warm start) instead of refreshing them from rollouts (GAILAgent.update, gail.py)
    disc_observation: DiscObservation = "policy"
    # what D sees of the state: "policy" the policy's own observation; "scene" the true scene's
    # k-nearest form (the env's info["observation_scene"], the demonstrations' scene), whatever
    # the policy sees: an asymmetric discriminator that judges the boat's conduct, not its image

    def __post_init__(self) -> None:
        if self.reward not in REWARDS:
            raise ValueError(f"reward must be one of {REWARDS}, got {self.reward!r}")
        if self.disc_observation not in DISC_OBSERVATIONS:
            raise ValueError(
                f"disc_observation must be one of {DISC_OBSERVATIONS}, "
                f"got {self.disc_observation!r}"
            )

    @property
    def disc_info_key(self) -> str | None:
        """The env ``info`` key of D's observation (None: the policy's observation)."""
        return None if self.disc_observation == "policy" else SCENE_INFO_KEY


class GAILTrainer:
    """Discriminator, its optimiser and the expert data of one GAIL run."""

    def __init__(
        self,
        observation_space: spaces.Space,
        action_space: spaces.Space,
        expert: ExpertData,
        config: GAILConfig,
        seed: int = 0,
    ) -> None:
        self.config, self.observation_space, self.action_space = (
            config,
            observation_space,
            action_space,
        )
        expert_obs = expert.obs
        if config.disc_observation == "scene":
            if expert.disc_obs is None:
                raise ValueError(
                    "disc_observation='scene' needs the expert's scene observations "
                    "(ExpertData.disc_obs, from scene demonstrations)"
                )
            observation_space, expert_obs = _SCENE_SPACE, expert.disc_obs
        self.disc_space = observation_space
        with torch.random.fork_rng():
            torch.manual_seed(seed + 7)
            self.disc = Discriminator(observation_space, config.disc_hidden, config.balanced_fusion)
        self.optimizer = torch.optim.Adam(self.disc.parameters(), lr=config.disc_lr)
        self.generator = torch.Generator().manual_seed(seed + 11)
        obs = self.disc_obs(expert_obs)
        az = self._az(normalize_actions(expert.actions, action_space), np.zeros((len(expert), 2)))
        if config.absorbing:  # one goal-absorbing sample per expert run
            n_runs = int(expert.last.sum())
            obs = cat_obs([obs, self.absorbing_obs(obs, n_runs)])
            z = np.tile([1.0, 0.0], (n_runs, 1))
            az = torch.cat([az, self._az(np.zeros((n_runs, 1), np.float32), z)])
        self.expert_obs, self.expert_az = obs, az

    # -- inputs --------------------------------------------------------------------------

    def disc_obs(self, obs: Obs) -> Tensor | dict[str, Tensor]:
        """Raw env observations → the discriminator's fixed standardisation (module table)."""
        if isinstance(obs, dict):
            return {
                k: torch.as_tensor(v, dtype=torch.float32) / (255.0 if v.dtype == np.uint8 else 1.0)
                for k, v in obs.items()
            }
        if obs.dtype == np.uint8:
            return {"image": torch.as_tensor(obs, dtype=torch.float32) / 255.0}
        if obs.shape[-1] == SCENE_WIDTH:
            return torch.as_tensor(standardize_scene(obs))
        return torch.as_tensor(POSITIONAL_STANDARDIZATION.apply(obs))

    @staticmethod
    def _az(a: NDArray[np.float32], z: NDArray[Any]) -> Tensor:
        return torch.as_tensor(np.concatenate([a, z], axis=1), dtype=torch.float32)

    @staticmethod
    def absorbing_obs(like: Tensor | dict[str, Tensor], n: int) -> Any:
        """``n`` absorbing-state observations (all zeros) shaped and placed as ``like``'s."""
        if isinstance(like, dict):
            return {k: torch.zeros((n, *v.shape[1:]), device=v.device) for k, v in like.items()}
        return torch.zeros((n, like.shape[1]), device=like.device)

    def batch_obs(self, batch: RolloutBatch) -> Obs:
        """The raw observations D sees of ``batch``'s steps (T, N, ...): the policy's, or the
        env info the config names (:attr:`GAILConfig.disc_info_key`, ``batch.aux``)."""
        key = self.config.disc_info_key
        if key is None:
            return batch.obs
        if key not in batch.aux:
            raise KeyError(f"the rollout has no {key!r}: make the env with info_observation")
        return batch.aux[key]

    def policy_samples(
        self, batch: RolloutBatch, ends: NDArray[np.bool_]
    ) -> tuple[Any, Tensor, Tensor, Tensor]:
        """(obs, az) of the batch's valid steps, then of its absorbing samples; and the kinds."""
        valid = batch.valid.reshape(-1)
        obs = self.disc_obs(index_obs(flatten_obs(self.batch_obs(batch), 2), valid))
        acts = batch.actions.reshape(-1, *batch.actions.shape[2:])[valid]
        az = self._az(normalize_actions(acts, self.action_space), np.zeros((int(valid.sum()), 2)))
        kinds = (ends & batch.terminated[..., None]).reshape(-1, N_ABSORBING)
        kinds = kinds[kinds.any(axis=1)].astype(np.float32)
        abs_obs = self.absorbing_obs(obs, kinds.shape[0])
        abs_az = self._az(np.zeros((kinds.shape[0], 1), np.float32), kinds)
        return obs, az, abs_obs, abs_az

    # -- learning ------------------------------------------------------------------------

    def _gradient_penalty(self, obs_e: Any, az_e: Tensor, obs_p: Any, az_p: Tensor) -> Tensor:
        """E[(‖∇ f(x̂)‖ − 1)²] at x̂ = εx_E + (1 − ε)x_π (Gulrajani et al. 2017)."""
        eps = torch.rand(az_e.shape[0], 1, generator=self.generator).to(az_e.device)

        def mix(a: Tensor, b: Tensor) -> Tensor:
            e = eps.view(-1, *([1] * (a.dim() - 1)))
            return (e * a + (1 - e) * b).requires_grad_(True)

        obs = (
            {k: mix(obs_e[k], obs_p[k]) for k in obs_e}
            if isinstance(obs_e, dict)
            else mix(obs_e, obs_p)
        )
        az = mix(az_e, az_p)
        inputs = [*obs.values(), az] if isinstance(obs, dict) else [obs, az]
        grads = torch.autograd.grad(self.disc(obs, az).sum(), inputs, create_graph=True)
        norm = torch.sqrt(torch.stack([g.pow(2).flatten(1).sum(1) for g in grads]).sum(0) + 1e-12)
        return (norm - 1.0).pow(2).mean()

    def update_discriminator(self, pol_obs: Any, pol_az: Tensor) -> dict[str, float]:
        """``disc_steps`` Adam steps on BCE-with-logits; diagnostics of the last step."""
        cfg = self.config
        self.disc.train()
        n_e, n_p = self.expert_az.shape[0], pol_az.shape[0]
        m = min(cfg.disc_minibatch, n_e, n_p)
        out: dict[str, float] = {}
        for _ in range(cfg.disc_steps):
            # drawn by the CPU generator on any device (the same draws), used where the data is
            ie = torch.randint(n_e, (m,), generator=self.generator).to(self.expert_az.device)
            ip = torch.randint(n_p, (m,), generator=self.generator).to(pol_az.device)
            obs_e, az_e = index_obs(self.expert_obs, ie), self.expert_az[ie]
            obs_p, az_p = index_obs(pol_obs, ip), pol_az[ip]
            logits = self.disc(cat_obs([obs_e, obs_p]), torch.cat([az_e, az_p]))
            labels = torch.cat([torch.ones(m), torch.zeros(m)]).to(logits.device)
            loss = functional.binary_cross_entropy_with_logits(logits, labels)
            if cfg.gradient_penalty > 0:
                loss = loss + cfg.gradient_penalty * self._gradient_penalty(
                    obs_e, az_e, obs_p, az_p
                )
            self.optimizer.zero_grad(set_to_none=True)
            loss.backward()
            self.optimizer.step()
            with torch.no_grad():
                d = torch.sigmoid(logits)
                out = {
                    "disc_loss": float(loss),
                    "expert_accuracy": float((d[:m] > 0.5).float().mean()),
                    "policy_accuracy": float((d[m:] < 0.5).float().mean()),
                    "mean_d_expert": float(d[:m].mean()),
                    "mean_d_policy": float(d[m:].mean()),
                }
        self.disc.eval()
        return out

    @torch.no_grad()
    def logits(self, obs: Any, az: Tensor, chunk: int = 4096) -> Tensor:
        """f_w for many pairs, in eval mode, in chunks."""
        self.disc.eval()
        n = az.shape[0]
        parts = [
            self.disc(index_obs(obs, slice(i, i + chunk)), az[i : i + chunk])
            for i in range(0, n, chunk)
        ]
        return torch.cat(parts) if parts else torch.zeros(0, device=az.device)

    # -- on a torch device (issue 40: GAIL with the env and TRPO on the device) ---------------

    def to(self, device: torch.device) -> None:
        """Move the discriminator, its optimiser's state and the expert samples to ``device``
        (the random generator stays on the CPU: the same draws anywhere)."""
        self.disc.to(device)
        for state in self.optimizer.state.values():
            for key, value in state.items():
                if isinstance(value, torch.Tensor) and key != "step":
                    state[key] = value.to(device)
        self.expert_obs = _obs_to(self.expert_obs, device)
        self.expert_az = self.expert_az.to(device)

    def disc_obs_tensor(self, obs: Tensor | dict[str, Tensor]) -> Tensor | dict[str, Tensor]:
        """:meth:`disc_obs` of raw observation tensors (..., F) on their device, the same
        numbers (the standardisations in float64, then float32, as NumPy's)."""
        if isinstance(obs, dict):
            return {k: v.to(torch.float32) / (255.0 if v.dtype == torch.uint8 else 1.0)
                    for k, v in obs.items()}  # fmt: skip
        if obs.dtype == torch.uint8:
            return {"image": obs.to(torch.float32) / 255.0}
        table = (
            SCENE_STANDARDIZATION if obs.shape[-1] == SCENE_WIDTH else POSITIONAL_STANDARDIZATION
        )
        mean = torch.as_tensor(np.asarray(table.mean), dtype=torch.float64, device=obs.device)
        std = torch.as_tensor(np.asarray(table.std), dtype=torch.float64, device=obs.device)
        x = ((obs.to(torch.float64) - mean) / std).to(torch.float32)
        if obs.shape[-1] == SCENE_WIDTH:  # standardize_scene: every empty slot all zeros
            shape = (*obs.shape[:-1], SCENE_K, SCENE_FEATURES)
            valid = obs[..., 4:].reshape(shape)[..., 5:6] > 0.5
            x = torch.cat([x[..., :4], (x[..., 4:].reshape(shape) * valid).flatten(-2)], -1)
        return x

    def az_tensor(self, actions: Tensor, z: Tensor | None = None) -> Tensor:
        """[a, z] (B, 3) of env action tensors (:func:`normalize_actions`; z zeros by
        default), float32 on the actions' device."""
        if isinstance(self.action_space, spaces.Discrete):
            half = (N_CATEGORIES - 1) / 2
            a = (actions.reshape(-1, 1).to(torch.float32) - half) / half
        else:
            a = actions.reshape(-1, 1).clamp(-1.0, 1.0).to(torch.float32)
        if z is None:
            z = torch.zeros((a.shape[0], N_ABSORBING), dtype=torch.float32, device=a.device)
        return torch.cat([a, z.to(torch.float32)], dim=1)

    def rewards_tensor(
        self, obs: Any, az: Tensor, terminated: Tensor, ends: Tensor, log_probs: Tensor,
        gamma: float,
    ) -> Tensor:  # fmt: skip
        """:meth:`rewards` of a device batch: ``obs``, ``az`` its T·N steps' discriminator
        inputs (:meth:`disc_obs_tensor`, :meth:`az_tensor`), ``terminated`` and ``log_probs``
        (T, N), ``ends`` (T, N, 2) [reached the goal, collided]; (T, N) float32."""
        cfg = self.config
        T, N = terminated.shape
        clip = cfg.reward_clip
        r = reward_from_logits(self.logits(obs, az), cfg.reward).clamp(-clip, clip)
        r = r.to(torch.float64).reshape(T, N)
        if cfg.absorbing:
            kinds = torch.eye(N_ABSORBING, dtype=torch.float32, device=az.device)
            zero_a = torch.zeros((N_ABSORBING, 1), dtype=torch.float32, device=az.device)
            abs_logits = self.logits(
                self.absorbing_obs(obs, N_ABSORBING), torch.cat([zero_a, kinds], dim=1)
            )
            r_abs = reward_from_logits(abs_logits, cfg.reward).clamp(-clip, clip)
            v_abs = gamma / (1.0 - gamma) * r_abs  # γ r(s_a) / (1 − γ), float32 as NumPy's
            for kind in range(N_ABSORBING):
                r = r + torch.where(terminated & ends[..., kind], v_abs[kind], 0.0)
        if cfg.entropy_bonus > 0:
            r = r + cfg.entropy_bonus * -log_probs
        return r.to(torch.float32)

    def rewards(self, batch: RolloutBatch, ends: NDArray[np.bool_], gamma: float) -> Any:
        """Imitation rewards (T, N) for ``batch`` (steps 3 of the module docstring)."""
        cfg = self.config
        T, N = batch.rewards.shape
        obs = self.disc_obs(flatten_obs(self.batch_obs(batch), 2))
        acts = batch.actions.reshape(-1, *batch.actions.shape[2:])
        az = self._az(normalize_actions(acts, self.action_space), np.zeros((T * N, 2)))
        clip = cfg.reward_clip
        logits = self.logits(obs, az)
        r = reward_from_logits(logits, cfg.reward).clamp(-clip, clip).numpy().astype(np.float64)
        r = r.reshape(T, N)
        if cfg.absorbing:
            kinds = np.eye(N_ABSORBING, dtype=np.float32)
            abs_logits = self.logits(
                self.absorbing_obs(obs, N_ABSORBING),
                self._az(np.zeros((N_ABSORBING, 1), np.float32), kinds),
            )
            r_abs = reward_from_logits(abs_logits, cfg.reward).clamp(-clip, clip).numpy()
            v_abs = gamma / (1.0 - gamma) * r_abs  # γ r(s_a) / (1 − γ)
            term = batch.terminated
            r += np.where(term & ends[..., 0], v_abs[0], 0.0)
            r += np.where(term & ends[..., 1], v_abs[1], 0.0)
        if cfg.entropy_bonus > 0:
            r += cfg.entropy_bonus * -batch.log_probs
        return r.astype(np.float32)

    def state_dict(self) -> dict[str, Any]:
        return {
            "format": STATE_FORMAT,
            "config": dataclasses.asdict(self.config),
            "discriminator": self.disc.state_dict(),
            "optimizer": self.optimizer.state_dict(),
            "generator": self.generator.get_state(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        if state.get("format") != STATE_FORMAT:
            raise ValueError(f"not a GAIL state (format {state.get('format')!r})")
        self.disc.load_state_dict(state["discriminator"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.generator.set_state(state["generator"])
