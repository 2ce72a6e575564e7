"""Generative Adversarial Imitation Learning (Ho & Ermon 2016) on top of
:mod:`learning.algorithms.trpo`; the discriminator and its training are in
:mod:`learning.imitation.discriminator`.

One iteration, top to bottom (:func:`train_gail`):

1. Roll out π_θ on N envs for T steps (:func:`learning.algorithms.loop.iterate`); the env's
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
4. TRPO step on those rewards (:meth:`learning.algorithms.trpo.TRPOAgent.update`: GAE, natural
   gradient, critic). :class:`GAILAgent` is steps 2-4 as one
   :meth:`~learning.algorithms.base.Agent.update`.

Discriminator inputs (the study's Sect. "Networks", with its suspected flaw fixed):

==================  =========================================================================
part                fed as
==================  =========================================================================
positional s        ``POSITIONAL_STANDARDIZATION`` (fixed constants) ⊕ a ⊕ z → MLP 400-300
scene s             ``standardize_scene`` (fixed constants, empty slots 0) ⊕ a ⊕ z → MLP
radar+goal s        image / 255 → the study's CNN; goal (already standardised) ⊕ a ⊕ z join
                    after the convolution ("late"), → FC 400-300
action a            NORMALISED: the heading change as a fraction of the ±30° bound, in [-1, 1]
                    (gaussian: the clipped action the env executed; categorical: (k − 20)/20).
                    The study fed raw actions and suspected it hurt IL with radar.
z (2,)              absorbing-state indicator [goal end, collision end] (see below)
==================  =========================================================================

``GAILConfig(disc_observation="scene")`` gives D the scene row's input whatever the policy
sees: the demonstrations' true scene and, for the policy's pairs, the env's
``info["observation_scene"]`` (``OpenWaterVectorEnv(info_observation="scene")``, kept beside
s_t in ``RolloutBatch.aux``). A radar policy is then judged on where it steers among the
obstacles, not on how its images look: D cannot tell the expert from the policy by radar noise
or clutter that the policy does not cause (privileged information for the learner only, as an
asymmetric actor-critic's critic; the policy, its checkpoint and its helmsman see the radar).

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
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch
from gymnasium import spaces
from gymnasium.vector import VectorEnv
from numpy.typing import NDArray
from torch import Tensor

from learning.algorithms.base import UpdateTimes
from learning.algorithms.device_loop import device_update, iterate_on_device, place_agent
from learning.algorithms.device_rollout import DeviceBatch, flat_rows
from learning.algorithms.loop import IterationStats, iterate
from learning.algorithms.networks import CNNTrunk, refresh_batchnorm
from learning.algorithms.rollout import Obs, RolloutBatch
from learning.algorithms.trpo import TRPOAgent, TRPOConfig
from learning.imitation.discriminator import (
    N_ABSORBING,
    REWARDS,
    GAILConfig,
    GAILTrainer,
    cat_obs,
    index_obs,
    normalize_actions,
    reward_from_logits,
)
from learning.imitation.preprocess import ExpertData

__all__ = [
    "REWARDS",
    "GAILAgent",
    "GAILConfig",
    "GAILStats",
    "GAILTrainer",
    "behavioral_cloning",
    "normalize_actions",
    "reward_from_logits",
    "train_gail",
    "train_gail_on_device",
]

AGENT_FORMAT = "usvsim.learning.gail-agent/1"
BATCHNORM_CHUNK = 256  # rows per BatchNorm refresh pass (refresh_batchnorm's default)
END_INFO = ("reached_goal", "collision")  # the env's info keys telling how an episode ended


def behavioral_cloning(agent: TRPOAgent, expert: ExpertData, config: GAILConfig) -> float:
    """Warm start: maximise log π(a_E | s_E) by Adam (``bc_epochs`` epochs); final mean loss.

    The observation normaliser and the BatchNorm statistics are first fitted to the expert's
    observations, so that the cloned policy sees what it will see in the first rollouts. The
    expert's observations stay raw (uint8 images) and each minibatch is normalised when it is
    used: the normalisation is element-wise, so this is the same computation as normalising all
    of them first, without a float32 copy of every image (3.8 GB for the 160,620 pairs of
    ``il-gaussian-radar-ow-colreg``, 7.6 GB with two images of radar memory).
    """
    agent.normalizer.update(expert.obs)
    actions = torch.as_tensor(expert.actions)
    opt = torch.optim.Adam(agent.policy.parameters(), lr=config.bc_lr)
    n, losses = len(expert), [math.nan]
    for _ in range(config.bc_epochs):
        _settle_batchnorm(agent, expert.obs, n)
        perm = torch.randperm(n, generator=agent.generator)
        losses = []
        for i in range(0, n, config.bc_minibatch):
            idx = perm[i : i + config.bc_minibatch]
            obs = agent.policy_input(index_obs(expert.obs, idx.numpy()))
            loss = -agent.policy(obs).log_prob(actions[idx]).mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            losses.append(float(loss.detach()))
    _settle_batchnorm(agent, expert.obs, n)
    return float(np.mean(losses))


def _settle_batchnorm(
    agent: TRPOAgent, obs: Obs, n: int, passes: int = 8, chunk: int = BATCHNORM_CHUNK
) -> None:
    """Bring the CNN's BatchNorm running statistics to those of the raw observations ``obs``
    (``n`` rows) under the current weights (momentum 0.1 per chunk of ``chunk`` rows: 8 passes
    leave < 1 % of the old statistics), so that the cloned policy acts with the statistics it
    was trained with and the trainer's later refreshes (on rollouts of a policy that behaves
    like the expert) change them little. Each chunk is normalised when it is used: the passes
    of :func:`learning.algorithms.networks.refresh_batchnorm` over the whole set, chunk by
    chunk. Measured: cloned with a single refresh, the radar policy went from 15/15 to 5/15 on
    validation once its statistics were refreshed. No-op for MLP policies."""
    if not any(isinstance(m, CNNTrunk) for m in agent.policy.modules()):
        return
    for _ in range(passes):
        for start in range(0, n, chunk):
            part = index_obs(obs, slice(start, start + chunk))
            refresh_batchnorm(agent.policy, agent.policy_input(part), batch_size=chunk)


def _input_stats(agent: TRPOAgent) -> tuple[dict[str, Any], dict[str, Tensor]]:
    """Copies of the observation-normaliser state and the policy's BatchNorm buffers."""
    buffers = {
        k: v.clone()
        for k, v in agent.policy.state_dict().items()
        if k.endswith(("running_mean", "running_var", "num_batches_tracked"))
    }
    return copy.deepcopy(agent.normalizer.state_dict()), buffers


@dataclass(frozen=True)
class GAILStats:
    """What one :meth:`GAILAgent.update` did (``LOG_FIELDS`` go to an IL run's ``log.csv``)."""

    LOG_FIELDS: ClassVar[tuple[str, ...]] = (
        "goal_rate",
        "kl",
        "entropy",
        "line_search_accepted",
        "mean_reward",
        "disc_loss",
        "expert_accuracy",
        "policy_accuracy",
        "mean_d_expert",
        "mean_d_policy",
    )

    goal_rate: float  # finished episodes that reached the goal (NaN if none finished)
    disc_loss: float
    expert_accuracy: float
    policy_accuracy: float
    mean_d_expert: float
    mean_d_policy: float
    mean_reward: float  # mean imitation reward of the batch's valid steps
    kl: float
    entropy: float
    line_search_accepted: bool
    times: UpdateTimes = field(default_factory=UpdateTimes, compare=False)  # wall-clock split


def end_kinds(batch: RolloutBatch) -> NDArray[np.bool_]:
    """(T, N, 2) [reached goal, collided without reaching it] per step (``END_INFO``)."""
    goal = batch.info[END_INFO[0]]
    hit = batch.info[END_INFO[1]]
    return np.stack([goal, hit & ~goal], axis=-1)


class GAILAgent:
    """GAIL as a :class:`learning.algorithms.base.Agent`: a TRPO policy agent trained on the
    rewards of a discriminator (:class:`GAILTrainer`) fitted to ``expert``.

    ``config`` is the policy's :class:`TRPOConfig`; acting, ``policy``, ``normalizer`` and
    the counters are the policy agent's. :meth:`update` is steps 2-4 of the module docstring.
    """

    info_keys = END_INFO
    env_reward = False  # the env's rewards are replaced by the imitation rewards

    def __init__(
        self,
        observation_space: spaces.Space,
        action_space: spaces.Space,
        config: TRPOConfig,
        gail_config: GAILConfig,
        expert: ExpertData,
    ) -> None:
        self.observation_space, self.action_space = observation_space, action_space
        self.config, self.gail_config, self.expert = config, gail_config, expert
        self.policy_agent = TRPOAgent(observation_space, action_space, config)
        key = gail_config.disc_info_key
        self.obs_info_keys: tuple[str, ...] = () if key is None else (key,)
        self.trainer = GAILTrainer(
            observation_space, action_space, expert, gail_config, seed=config.seed
        )

    @property
    def policy(self) -> Any:
        return self.policy_agent.policy

    @property
    def normalizer(self) -> Any:
        return self.policy_agent.normalizer

    @property
    def iteration(self) -> int:
        return self.policy_agent.iteration

    @iteration.setter
    def iteration(self, value: int) -> None:
        self.policy_agent.iteration = value

    @property
    def env_steps(self) -> int:
        return self.policy_agent.env_steps

    @env_steps.setter
    def env_steps(self, value: int) -> None:
        self.policy_agent.env_steps = value

    def sample(self, obs: Obs) -> tuple[NDArray[Any], NDArray[Any]]:
        return self.policy_agent.sample(obs)

    def act(self, obs: Obs, deterministic: bool = True) -> NDArray[Any]:
        return self.policy_agent.act(obs, deterministic)

    def warm_start(self) -> float:
        """Behavioural cloning of the expert (:func:`behavioral_cloning`); final mean loss."""
        return behavioral_cloning(self.policy_agent, self.expert, self.gail_config)

    def update(self, batch: RolloutBatch) -> GAILStats:
        """Discriminator step, imitation rewards into ``batch.rewards``, TRPO step."""
        agent, gail = self.policy_agent, self.trainer
        start = time.perf_counter()
        ends = end_kinds(batch)
        obs, az, abs_obs, abs_az = gail.policy_samples(batch, ends)
        if abs_az.shape[0]:
            obs, az = cat_obs([obs, abs_obs]), torch.cat([az, abs_az])
        diag = gail.update_discriminator(obs, az)
        batch.rewards = gail.rewards(batch, ends, self.config.gamma)
        discriminator_s = time.perf_counter() - start
        step = self._policy_step(lambda: agent.update(batch))
        done = batch.episode_end & batch.valid
        n_goal = int((ends[..., 0] & batch.terminated).sum())
        return GAILStats(
            goal_rate=n_goal / int(done.sum()) if done.any() else math.nan,
            mean_reward=float(batch.rewards[batch.valid].mean()),
            kl=step.kl,
            entropy=step.entropy,
            line_search_accepted=step.line_search_accepted,
            times=dataclasses.replace(step.times, discriminator_s=discriminator_s),
            **diag,
        )

    def _policy_step(self, update: Callable[[], Any]) -> Any:
        """The TRPO step ``update()`` with GAIL's warm-up and frozen input statistics."""
        agent, cfg = self.policy_agent, self.gail_config
        # warm-up: the critic learns the imitation reward's values (and D its task) before
        # the first policy step, so that noisy advantages do not undo the cloned policy
        frozen = agent.iteration < cfg.policy_warmup
        agent.config = dataclasses.replace(self.config, max_kl=1e-9) if frozen else self.config
        saved = _input_stats(agent) if cfg.freeze_input_stats else None
        step = update()
        agent.config = self.config
        if saved is not None:
            # GAIL drives the state distribution towards the expert's, so the expert's input
            # statistics are the ones to keep; refreshed from the rollouts of an early, still
            # poor policy they shift and change what the cloned policy does (measured on
            # radar: a cloned 15/15 policy fell to 1/15 in 10 iterations with its step frozen)
            agent.normalizer.load_state_dict(saved[0])
            agent.policy.load_state_dict(saved[1], strict=False)
        return step

    # -- on a torch device (issue 40; learning.algorithms.device_loop.iterate_on_device) ------

    def place(self, device: torch.device) -> None:
        """Move the policy agent and the discriminator (with its expert samples) to
        ``device``."""
        place_agent(self.policy_agent, device)
        self.trainer.to(device)

    def update_on_device(self, batch: DeviceBatch) -> GAILStats:
        """:meth:`update` on a :class:`learning.algorithms.device_rollout.DeviceBatch` (every
        step valid; ``batch.info`` holds :data:`END_INFO`): discriminator step, imitation
        rewards, TRPO step, all on the batch's device (the discriminator's minibatch indices
        drawn on the CPU, as on the CPU path). A discriminator on another view of the state
        (``disc_observation="scene"``) reads it from ``batch.aux``."""
        gail = self.trainer
        start = time.perf_counter()
        T, N = batch.rewards.shape
        goal, hit = batch.info[END_INFO[0]], batch.info[END_INFO[1]]
        ends = torch.stack([goal, hit & ~goal], dim=-1)  # end_kinds
        view = batch.aux[self.obs_info_keys[0]] if self.obs_info_keys else batch.obs
        obs = gail.disc_obs_tensor(flat_rows(view))
        az = gail.az_tensor(batch.actions.reshape(T * N, *batch.actions.shape[2:]))
        kinds = (ends & batch.terminated[..., None]).reshape(-1, N_ABSORBING)
        kinds = kinds[kinds.any(dim=1)]  # one read of its size a batch, not a step
        pol_obs, pol_az = obs, az
        if kinds.shape[0]:
            zero_a = torch.zeros((kinds.shape[0], 1), dtype=torch.float32, device=az.device)
            abs_obs = gail.absorbing_obs(obs, kinds.shape[0])
            pol_obs = cat_obs([obs, abs_obs])
            pol_az = torch.cat([az, gail.az_tensor(zero_a, kinds.to(torch.float32))])
        diag = gail.update_discriminator(pol_obs, pol_az)
        rewards = gail.rewards_tensor(obs, az, batch.terminated, ends, batch.log_probs,
                                      self.config.gamma)  # fmt: skip
        discriminator_s = time.perf_counter() - start
        imitation = dataclasses.replace(batch, rewards=rewards)
        step = self._policy_step(lambda: device_update(self.policy_agent, imitation))
        done = int(batch.episode_end.sum())
        n_goal = int((ends[..., 0] & batch.terminated).sum())
        return GAILStats(
            goal_rate=n_goal / done if done else math.nan,
            mean_reward=float(rewards.mean()),
            kl=step.kl,
            entropy=step.entropy,
            line_search_accepted=step.line_search_accepted,
            times=dataclasses.replace(step.times, discriminator_s=discriminator_s),
            **diag,
        )

    def state_dict(self) -> dict[str, Any]:
        """``{"format", "agent": TRPOAgent.state_dict(), "gail": GAILTrainer.state_dict()}``."""
        return {
            "format": AGENT_FORMAT,
            "agent": self.policy_agent.state_dict(),
            "gail": self.trainer.state_dict(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore a :meth:`state_dict` (``"format"`` may be absent: a checkpoint's ``agent``
        and its ``latest.gail.pt`` sidecar)."""
        if state.get("format", AGENT_FORMAT) != AGENT_FORMAT:
            raise ValueError(f"not a GAIL agent state (format {state.get('format')!r})")
        self.policy_agent.load_state_dict(state["agent"])
        self.trainer.load_state_dict(state["gail"])

    def load_policy(self, state: dict[str, Any]) -> None:
        """Start from another run's policy and normaliser (``TRPOAgent.load_policy``)."""
        self.policy_agent.load_policy(state)


def train_gail(
    gail_config: GAILConfig,
    trpo_config: TRPOConfig,
    make_vector_env: Callable[[int], VectorEnv],
    expert: ExpertData,
    *,
    callback: Callable[[IterationStats, GAILAgent], bool | None] | None = None,
    state: dict[str, Any] | None = None,
) -> GAILAgent:
    """GAIL until ``trpo_config.iterations`` iterations or ``callback`` returns True.

    ``state`` (a :meth:`GAILAgent.state_dict`) resumes a run (no behavioural cloning then); the
    envs restart from a reset seeded ``seed + iteration``
    (:func:`learning.algorithms.loop.iterate`).
    """
    env = make_vector_env(trpo_config.num_envs)
    try:
        return iterate(_started_agent(env, gail_config, trpo_config, expert, state), env, callback)
    finally:
        env.close()


def _started_agent(
    env: Any, gail_config: GAILConfig, trpo_config: TRPOConfig, expert: ExpertData,
    state: dict[str, Any] | None,
) -> GAILAgent:  # fmt: skip
    """A GAIL agent for ``env``'s spaces: resumed from ``state``, else cloned from the expert
    when the config asks for behavioural cloning."""
    agent = GAILAgent(
        env.single_observation_space, env.single_action_space, trpo_config, gail_config, expert
    )
    if state is not None:
        agent.load_state_dict(state)
    elif gail_config.bc_epochs > 0:
        agent.warm_start()
    return agent


def train_gail_on_device(
    gail_config: GAILConfig,
    trpo_config: TRPOConfig,
    make_env: Callable[[int], Any],
    expert: ExpertData,
    *,
    callback: Callable[[IterationStats, GAILAgent], bool | None] | None = None,
    state: dict[str, Any] | None = None,
) -> GAILAgent:
    """:func:`train_gail` on a torch env (``make_env(num_envs)``:
    :class:`usvsim.task.torch_env.TorchPoleAvoidanceEnv` or
    :class:`usvsim.task.torch_openwater.TorchOpenWaterEnv`): rollouts, the discriminator's
    steps, the imitation rewards, GAE and the TRPO step on the env's device
    (:func:`learning.algorithms.device_loop.iterate_on_device`); behavioural cloning and the
    callback (validation, checkpoints) on the CPU."""
    env = make_env(trpo_config.num_envs)
    agent = _started_agent(env, gail_config, trpo_config, expert, state)
    result: GAILAgent = iterate_on_device(agent, env, callback)
    return result
