"""Generative Adversarial Imitation Learning (Ho & Ermon 2016) on top of :mod:`learning.algorithms.trpo`.

One iteration, top to bottom (:func:`train_gail`):

1. Roll out π_θ on N envs for T steps (:class:`learning.algorithms.rollout.RolloutCollector`); the env's
   handcrafted reward is ignored (kept only as a diagnostic).
2. Discriminator step (:meth:`GAILTrainer.update_discriminator`): D_w(s, a) = σ(f_w(s, a)) is
   trained to tell expert pairs (label 1) from policy pairs (label 0) by Adam on the binary
   cross-entropy with logits,

       L(w) = − Ê_E[log D_w(s, a)] − Ê_π[log(1 − D_w(s, a))]  (+ λ_GP · gradient penalty)

3. Policy reward from the updated discriminator (:func:`reward_from_logits`), by default
   r(s, a) = −log(1 − D(s, a)) (= softplus(f), always ≥ 0); selectable: ``"logit"``
   r = log D − log(1 − D) = f (AIRL's form, Fu et al. 2018) and ``"log_d"`` r = log D (≤ 0).
   Optional entropy bonus: r += λ_H · (−log π(a|s)) (the causal-entropy term of Ho & Ermon's
   objective, as a per-step reward).
4. TRPO step on those rewards (:meth:`learning.algorithms.trpo.TRPOAgent.update`: GAE, natural gradient,
   critic).

Discriminator inputs (the study's Sect. "Networks", with its suspected flaw fixed):

==================  =========================================================================
part                fed as
==================  =========================================================================
positional s        ``POSITIONAL_STANDARDISATION`` (fixed constants) ⊕ a ⊕ z → MLP 400-300
radar+goal s        image / 255 → the study's CNN; goal (already standardised) ⊕ a ⊕ z join
                    after the convolution ("late"), → FC 400-300
action a            NORMALISED: the heading change as a fraction of the ±30° bound, in [-1, 1]
                    (gaussian: the clipped action the env executed; categorical: (k − 20)/20).
                    The study fed raw actions and suspected it hurt IL with radar.
z (2,)              absorbing-state indicator [goal end, collision end] (see below)
==================  =========================================================================

Variable-length episodes: absorbing states (Kostrikov et al. 2019, "Discriminator-Actor-
Critic"). An episode that *terminates* (goal reached or collision; truncation is not an end of
the MDP and is bootstrapped as usual) moves to an absorbing state s_a that it never leaves; its
reward r(s_a) is learned by the discriminator like any other, so the value of terminating is
r(s_a)/(1 − γ) and a terminated step's reward becomes r_t + γ r(s_a)/(1 − γ). Without this, a
positive reward −log(1 − D) pays the policy to delay every end (goal included) and a negative
one pays it to end early (collisions included). Expert runs end at their goal: each gives one
goal-absorbing sample. Unlike Kostrikov et al., whose tasks have one kind of end, goal and
collision are two distinct absorbing states (the env tells which): with one, a collision would
inherit the value the expert's arrivals give the absorbing state.

Diagnostics per iteration (:class:`GAILStats`): discriminator loss, expert accuracy (D > ½ on
expert pairs), policy accuracy (D < ½ on policy pairs), mean D on each, mean policy reward, the
fraction of finished episodes that reached the goal, and the handcrafted return.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from gymnasium.vector import VectorEnv, VectorWrapper
from numpy.typing import NDArray
from torch import Tensor, nn
from torch.nn import functional

from learning.algorithms.networks import NetworkConfig, make_trunk, refresh_batchnorm
from learning.algorithms.rollout import Obs, RolloutBatch, RolloutCollector, flatten_obs
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.imitation.preprocess import ExpertData
from usvsim.task.batch import N_CATEGORIES
from usvsim.task.observations import POSITIONAL_STANDARDISATION

__all__ = [
    "REWARDS",
    "Discriminator",
    "GAILConfig",
    "GAILStats",
    "GAILTrainer",
    "behavioural_cloning",
    "normalise_actions",
    "reward_from_logits",
    "train_gail",
]

STATE_FORMAT = "usvsim.learning.gail/1"
REWARDS = ("-log(1-D)", "logit", "log_d")
N_ABSORBING = 2  # [goal end, collision end]


@dataclass(frozen=True)
class GAILConfig:
    """Hyperparameters of the discriminator and the imitation reward."""

    reward: str = "-log(1-D)"  # one of REWARDS (module docstring, step 3)
    disc_hidden: tuple[int, ...] = (400, 300)  # study: the policy's trunk widths
    balanced_fusion: bool = (
        False  # D's CNN: learning.algorithms.networks.NetworkConfig.balanced_fusion
    )
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
    # by the warm start) instead of refreshing them from rollouts (see train_gail)

    def __post_init__(self) -> None:
        if self.reward not in REWARDS:
            raise ValueError(f"reward must be one of {REWARDS}, got {self.reward!r}")


def normalise_actions(actions: NDArray[Any], space: spaces.Space) -> NDArray[np.float32]:
    """Env actions → heading change as a fraction of the bound, (B, 1) in [-1, 1]."""
    a = np.asarray(actions)
    if isinstance(space, spaces.Discrete):
        half = (N_CATEGORIES - 1) / 2
        return ((a.reshape(-1, 1).astype(np.float32) - half) / half).astype(np.float32)
    return np.clip(a.reshape(-1, 1), -1.0, 1.0).astype(np.float32)


def reward_from_logits(logits: Tensor, kind: str) -> Tensor:
    """Policy reward from discriminator logits f (D = σ(f)); module docstring, step 3."""
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
        """``obs`` standardised (:meth:`GAILTrainer.disc_obs`), ``az`` (B, 3) = [a, z]."""
        if isinstance(obs, dict):
            return self.head(self.trunk({**obs, "zz_action": az})).squeeze(-1)
        return self.head(self.trunk(torch.cat([obs, az], dim=-1))).squeeze(-1)


def _index(obs: Obs | dict[str, Tensor] | Tensor, idx: Any) -> Any:
    return {k: v[idx] for k, v in obs.items()} if isinstance(obs, dict) else obs[idx]


def _cat(parts: list[Any]) -> Any:
    if isinstance(parts[0], dict):
        return {k: torch.cat([p[k] for p in parts]) for k in parts[0]}
    return torch.cat(parts)


@dataclass(frozen=True)
class GAILStats:
    """What one GAIL iteration did (handed to the :func:`train_gail` callback)."""

    iteration: int
    env_steps: int
    episodes: int
    goal_rate: float  # finished episodes that reached the goal (NaN if none finished)
    env_return: float  # mean handcrafted return of finished episodes (diagnostic only)
    disc_loss: float
    expert_accuracy: float
    policy_accuracy: float
    mean_d_expert: float
    mean_d_policy: float
    mean_reward: float
    kl: float
    entropy: float
    line_search_accepted: bool
    wall_time_s: float


class _EndKinds(VectorWrapper):
    """Records, per step, which boats reached the goal and which collided (info arrays)."""

    def __init__(self, env: VectorEnv) -> None:
        super().__init__(env)
        self.log: list[NDArray[np.bool_]] = []

    def step(self, actions: Any) -> Any:
        obs, reward, term, trunc, info = self.env.step(actions)
        n = self.num_envs
        goal = np.asarray(info.get("reached_goal", np.zeros(n, dtype=bool)), dtype=bool)
        hit = np.asarray(info.get("collision", np.zeros(n, dtype=bool)), dtype=bool)
        self.log.append(np.stack([goal, hit & ~goal], axis=-1))
        return obs, reward, term, trunc, info

    def take(self) -> NDArray[np.bool_]:
        """(T, N, 2) end kinds of the steps since the last call."""
        out, self.log = np.stack(self.log), []
        return out


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
        with torch.random.fork_rng():
            torch.manual_seed(seed + 7)
            self.disc = Discriminator(observation_space, config.disc_hidden, config.balanced_fusion)
        self.optimizer = torch.optim.Adam(self.disc.parameters(), lr=config.disc_lr)
        self.generator = torch.Generator().manual_seed(seed + 11)
        obs = self.disc_obs(expert.obs)
        az = self._az(normalise_actions(expert.actions, action_space), np.zeros((len(expert), 2)))
        if config.absorbing:  # one goal-absorbing sample per expert run
            n_runs = int(expert.last.sum())
            obs = _cat([obs, self._absorbing_obs(obs, n_runs)])
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
        return torch.as_tensor(POSITIONAL_STANDARDISATION.apply(obs))

    @staticmethod
    def _az(a: NDArray[np.float32], z: NDArray[Any]) -> Tensor:
        return torch.as_tensor(np.concatenate([a, z], axis=1), dtype=torch.float32)

    @staticmethod
    def _absorbing_obs(like: Tensor | dict[str, Tensor], n: int) -> Any:
        if isinstance(like, dict):
            return {k: torch.zeros((n, *v.shape[1:])) for k, v in like.items()}
        return torch.zeros((n, like.shape[1]))

    def policy_samples(
        self, batch: RolloutBatch, ends: NDArray[np.bool_]
    ) -> tuple[Any, Tensor, Tensor, Tensor]:
        """(obs, az) of the batch's valid steps, then of its absorbing samples; and the kinds."""
        valid = batch.valid.reshape(-1)
        obs = self.disc_obs(_index(flatten_obs(batch.obs, 2), valid))
        acts = batch.actions.reshape(-1, *batch.actions.shape[2:])[valid]
        az = self._az(normalise_actions(acts, self.action_space), np.zeros((int(valid.sum()), 2)))
        kinds = (ends & batch.terminated[..., None]).reshape(-1, N_ABSORBING)
        kinds = kinds[kinds.any(axis=1)].astype(np.float32)
        abs_obs = self._absorbing_obs(obs, kinds.shape[0])
        abs_az = self._az(np.zeros((kinds.shape[0], 1), np.float32), kinds)
        return obs, az, abs_obs, abs_az

    # -- learning ------------------------------------------------------------------------

    def _gradient_penalty(self, obs_e: Any, az_e: Tensor, obs_p: Any, az_p: Tensor) -> Tensor:
        """E[(‖∇ f(x̂)‖ − 1)²] at x̂ = εx_E + (1 − ε)x_π (Gulrajani et al. 2017)."""
        eps = torch.rand(az_e.shape[0], 1, generator=self.generator)

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
            ie = torch.randint(n_e, (m,), generator=self.generator)
            ip = torch.randint(n_p, (m,), generator=self.generator)
            obs_e, az_e = _index(self.expert_obs, ie), self.expert_az[ie]
            obs_p, az_p = _index(pol_obs, ip), pol_az[ip]
            logits = self.disc(_cat([obs_e, obs_p]), torch.cat([az_e, az_p]))
            labels = torch.cat([torch.ones(m), torch.zeros(m)])
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
            self.disc(_index(obs, slice(i, i + chunk)), az[i : i + chunk])
            for i in range(0, n, chunk)
        ]
        return torch.cat(parts) if parts else torch.zeros(0)

    def rewards(self, batch: RolloutBatch, ends: NDArray[np.bool_], gamma: float) -> Any:
        """Imitation rewards (T, N) for ``batch`` (steps 3 of the module docstring)."""
        cfg = self.config
        T, N = batch.rewards.shape
        obs = self.disc_obs(flatten_obs(batch.obs, 2))
        acts = batch.actions.reshape(-1, *batch.actions.shape[2:])
        az = self._az(normalise_actions(acts, self.action_space), np.zeros((T * N, 2)))
        clip = cfg.reward_clip
        logits = self.logits(obs, az)
        r = reward_from_logits(logits, cfg.reward).clamp(-clip, clip).numpy().astype(np.float64)
        r = r.reshape(T, N)
        if cfg.absorbing:
            kinds = np.eye(N_ABSORBING, dtype=np.float32)
            abs_logits = self.logits(
                self._absorbing_obs(obs, N_ABSORBING),
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


def behavioural_cloning(agent: TRPOAgent, expert: ExpertData, config: GAILConfig) -> float:
    """Warm start: maximise log π(a_E | s_E) by Adam (``bc_epochs`` epochs); final mean loss.

    The observation normaliser and the BatchNorm statistics are first fitted to the expert's
    observations, so that the cloned policy sees what it will see in the first rollouts.
    """
    agent.normalizer.update(expert.obs)
    obs = agent._tensor(expert.obs)  # the agent's own input pipeline
    actions = torch.as_tensor(expert.actions)
    opt = torch.optim.Adam(agent.policy.parameters(), lr=config.bc_lr)
    n, losses = len(expert), [math.nan]
    for _ in range(config.bc_epochs):
        _settle_batchnorm(agent, obs)
        perm = torch.randperm(n, generator=agent.generator)
        losses = []
        for i in range(0, n, config.bc_minibatch):
            idx = perm[i : i + config.bc_minibatch]
            loss = -agent.policy(_index(obs, idx)).log_prob(actions[idx]).mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            losses.append(float(loss.detach()))
    _settle_batchnorm(agent, obs)
    return float(np.mean(losses))


def _settle_batchnorm(agent: TRPOAgent, obs: Tensor | dict[str, Tensor], passes: int = 8) -> None:
    """Bring the CNN's BatchNorm running statistics to those of ``obs`` under the current
    weights (momentum 0.1 per chunk: 8 passes leave < 1 % of the old statistics), so that the
    cloned policy acts with the statistics it was trained with and the trainer's later
    refreshes (on rollouts of a policy that behaves like the expert) change them little.
    Measured: cloned with a single refresh, the radar policy went from 15/15 to 5/15 on
    validation once its statistics were refreshed. No-op for MLP policies."""
    for _ in range(passes):
        refresh_batchnorm(agent.policy, obs)


def _input_stats(agent: TRPOAgent) -> tuple[dict[str, Any], dict[str, Tensor]]:
    """Copies of the observation-normaliser state and the policy's BatchNorm buffers."""
    buffers = {
        k: v.clone()
        for k, v in agent.policy.state_dict().items()
        if k.endswith(("running_mean", "running_var", "num_batches_tracked"))
    }
    return copy.deepcopy(agent.normalizer.state_dict()), buffers


def train_gail(
    gail_config: GAILConfig,
    trpo_config: TRPOConfig,
    make_vector_env: Callable[[int], VectorEnv],
    expert: ExpertData,
    *,
    callback: Callable[[GAILStats, TRPOAgent, GAILTrainer], bool | None] | None = None,
    state: dict[str, Any] | None = None,
) -> tuple[TRPOAgent, GAILTrainer]:
    """GAIL until ``trpo_config.iterations`` iterations or ``callback`` returns True.

    ``state`` = ``{"agent": TRPOAgent.state_dict(), "gail": GAILTrainer.state_dict()}`` resumes
    a run (no behavioural cloning then); the envs restart from a reset seeded
    ``seed + iteration`` as in :func:`learning.algorithms.trpo.train`.
    """
    env = _EndKinds(make_vector_env(trpo_config.num_envs))
    try:
        agent = TRPOAgent(env.single_observation_space, env.single_action_space, trpo_config)
        gail = GAILTrainer(
            env.single_observation_space,
            env.single_action_space,
            expert,
            gail_config,
            seed=trpo_config.seed,
        )
        if state is not None:
            agent.load_state_dict(state["agent"])
            gail.load_state_dict(state["gail"])
        elif gail_config.bc_epochs > 0:
            behavioural_cloning(agent, expert, gail_config)
        collector = RolloutCollector(env, seed=trpo_config.seed + agent.iteration)
        start = time.perf_counter()
        while agent.iteration < trpo_config.iterations:
            batch = collector.collect(agent.sample, trpo_config.steps_per_env)
            ends = env.take()
            obs, az, abs_obs, abs_az = gail.policy_samples(batch, ends)
            if abs_az.shape[0]:
                obs, az = _cat([obs, abs_obs]), torch.cat([az, abs_az])
            diag = gail.update_discriminator(obs, az)
            batch.rewards = gail.rewards(batch, ends, trpo_config.gamma)
            # warm-up: the critic learns the imitation reward's values (and D its task) before
            # the first policy step, so that noisy advantages do not undo the cloned policy
            frozen = agent.iteration < gail_config.policy_warmup
            agent.config = dataclasses.replace(trpo_config, max_kl=1e-9) if frozen else trpo_config
            saved = _input_stats(agent) if gail_config.freeze_input_stats else None
            step, _ = agent.update(batch)
            agent.config = trpo_config
            if saved is not None:
                # GAIL drives the state distribution towards the expert's, so the expert's input
                # statistics are the ones to keep; refreshed from the rollouts of an early, still
                # poor policy they shift and change what the cloned policy does (measured on
                # radar: a cloned 15/15 policy fell to 1/15 in 10 iterations with its step frozen)
                agent.normalizer.load_state_dict(saved[0])
                agent.policy.load_state_dict(saved[1], strict=False)
            done = batch.episode_end & batch.valid
            n_goal = int((ends[..., 0] & batch.terminated).sum())
            stats = GAILStats(
                iteration=agent.iteration,
                env_steps=agent.env_steps,
                episodes=int(done.sum()),
                goal_rate=n_goal / int(done.sum()) if done.any() else math.nan,
                env_return=float(np.mean(batch.episode_returns))
                if batch.episode_returns
                else math.nan,
                mean_reward=float(batch.rewards[batch.valid].mean()),
                kl=step.line_search.kl,
                entropy=step.entropy,
                line_search_accepted=step.line_search.accepted,
                wall_time_s=time.perf_counter() - start,
                **diag,
            )
            if callback is not None and callback(stats, agent, gail):
                break
        return agent, gail
    finally:
        env.close()
