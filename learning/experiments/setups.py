"""The four RL setups of the study (Vedeler 2019, Table 4.1), one hyperparameter dataclass each.

=============================  ===========  ===========  =====================================
setup                          observation  action       network
=============================  ===========  ===========  =====================================
``rl-gaussian-positional``     positional   gaussian     MLP 400-300 tanh, Gaussian head
``rl-categorical-positional``  positional   categorical  MLP 400-300 tanh, 41 logits
``rl-gaussian-radar``          radar+goal   gaussian     CNN, late goal fusion, FC 400-300
``rl-categorical-radar``       radar+goal   categorical  CNN, late goal fusion, FC 400-300
=============================  ===========  ===========  =====================================

"radar" setups use the ``radar+goal`` observation: the study's RL radar setups fed the
standardised goal vector to the CNN after the convolution ("late fusion"); with the image alone
the goal is invisible once the pole is passed (``shared/reference/table-4-1.md``,
"Observations"). The name keeps the study's label.

The reward is the study's (:class:`usvsim.task.reward.GaussianReward`) and is not tuned here. One
thing differs from the study by necessity: usvsim ends an episode at a collision or at the goal
(the study ran fixed-length episodes). Every reward of the study is negative, so with early
termination a collision *ends the penalties*: TRPO quickly learns to ram the pole (measured: 0/15
validation, episodes of ~12 decisions, after 90 iterations). :class:`FixedHorizonReturn` restores
the study's fixed-length episode for training: on a terminating step the reward gets the
discounted return of the decisions left until the time limit, with the boat staying where the
episode ended (at the pole: about −2.5 per decision; at the goal: about −0.005)::

    r'_t = r_t + r_t · Σ_{k=1}^{m} γ^k = r_t · (1 + γ (1 − γ^m) / (1 − γ)),   m = K − (t + 1)

(K decisions in the time limit). Leaving the area (a truncation in the environment) is treated
the same way, as an absorbing state: the boat stays out with the reward of the step it left.
Otherwise GAE would bootstrap from V(s) of states beyond the area's edge, which no rollout ever
continues from, so nothing grounds their value and leaving early can look as cheap as ramming
the pole did. Only the time limit stays a truncation (bootstrapped). The per-step reward is
unchanged; evaluation uses the plain environment.

What is tuned: the batch (``num_envs`` × ``steps_per_env``), γ, λ, δ, the Fisher sub-sample
and the critic. The radar setups also scale the goal vector up to the image's share of the first
fully connected layer's input (``balanced_fusion``, :mod:`learning.algorithms.networks`): with the study's
plain concatenation rl-gaussian-radar needed 230 iterations to its first 15/15, with it 65.
Each setup is a frozen dataclass whose :meth:`RLSetup.trpo_config` gives the
:class:`learning.algorithms.trpo.TRPOConfig` of a run; the command line (``usvsim train``) overrides only
the seed, the iteration budget and the number of boats, so a setup name plus a seed reproduces
a run.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium.vector import VectorEnv, VectorWrapper

from learning.algorithms.networks import NetworkConfig
from learning.algorithms.trpo import TRPOConfig
from usvsim.task.vector_env import PoleAvoidanceVectorEnv

__all__ = ["SETUPS", "FixedHorizonReturn", "RLSetup", "get_setup", "setup_names"]


class FixedHorizonReturn(VectorWrapper):
    """Adds the fixed-length episode's remaining return to terminating rewards (module docstring).

    Wraps a :class:`usvsim.task.vector_env.PoleAvoidanceVectorEnv`; ``gamma`` must be the γ of the
    training run. Leaving the area becomes a termination; the time limit stays a truncation.
    """

    def __init__(self, env: PoleAvoidanceVectorEnv, gamma: float) -> None:
        super().__init__(env)
        if not 0.0 <= gamma < 1.0:
            raise ValueError(f"gamma must lie in [0, 1), got {gamma}")
        self.gamma = gamma
        scenario = env.sim.scenario
        self.max_decisions = scenario.max_decisions
        self.decision_period_s = scenario.decision_period_s
        self.metadata = env.metadata

    def step(self, actions: Any) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(actions)
        left = np.asarray(info["out_of_area"]) & np.asarray(truncated)
        if np.any(left):
            terminated, truncated = terminated | left, truncated & ~left
        if np.any(terminated):
            reward = np.array(reward, dtype=np.float64)
            decisions = np.rint(np.asarray(info["time_s"]) / self.decision_period_s)
            m = np.maximum(self.max_decisions - decisions, 0.0)[terminated]
            g = self.gamma
            reward[terminated] *= 1.0 + g * (1.0 - g**m) / (1.0 - g)
        return obs, reward, terminated, truncated, info


@dataclass(frozen=True)
class RLSetup:
    """One RL setup: the task's observation/action kinds and the TRPO hyperparameters."""

    name: str  # e.g. "rl-gaussian-positional"
    observation: str  # usvsim.task.observations kind: "positional" | "radar+goal"
    action: str  # usvsim.task.batch action kind: "gaussian" | "categorical"
    iterations: int = 300  # budget of TRPO iterations (early stop usually comes first)
    num_envs: int = 32  # N boats stepped together
    steps_per_env: int = 64  # T decisions per boat per iteration; batch B = N·T
    gamma: float = 0.99  # γ; an episode is ≤ 75 decisions, 1/(1-γ) = 100 covers it
    gae_lambda: float = 0.97  # λ of GAE
    max_kl: float = 0.02  # δ, nats
    cg_iters: int = 10
    cg_damping: float = 0.1
    fvp_fraction: float = 0.25  # share of the batch in Fisher-vector products
    critic_lr: float = 1e-3  # Adam
    critic_epochs: int = 5
    critic_minibatch: int = 256
    init_std_fraction: float = 0.5  # Gaussian: initial σ / action half-width
    balanced_fusion: bool = False  # learning.algorithms.networks.NetworkConfig.balanced_fusion
    validate_every: int = 5  # iterations between validations on the 15 episodes
    study_iterations: int = 0  # the study's iterations to its best validation (Table 4.1)

    def trpo_config(self, seed: int = 0, iterations: int | None = None) -> TRPOConfig:
        """The :class:`TRPOConfig` of a run of this setup."""
        return trpo_config_of(self, seed, iterations)

    def make_vector_env(self, num_envs: int, **env_kwargs: Any) -> VectorEnv:
        """The training environment: ``num_envs`` boats with :class:`FixedHorizonReturn`."""
        env = PoleAvoidanceVectorEnv(
            num_envs, observation=self.observation, action=self.action, **env_kwargs
        )
        return FixedHorizonReturn(env, self.gamma)

    def replace(self, **changes: object) -> RLSetup:
        """A copy with some fields changed (unknown names raise ``TypeError``)."""
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


@dataclass(frozen=True)
class GaussianPositional(RLSetup):
    """MLP, Gaussian head, positional observation (study: ~2400 iterations to 15/15)."""

    name: str = "rl-gaussian-positional"
    observation: str = "positional"
    action: str = "gaussian"
    study_iterations: int = 2400


@dataclass(frozen=True)
class CategoricalPositional(RLSetup):
    """MLP, 41 categories, positional observation (study: ~1000 iterations)."""

    name: str = "rl-categorical-positional"
    observation: str = "positional"
    action: str = "categorical"
    study_iterations: int = 1000


@dataclass(frozen=True)
class GaussianRadar(RLSetup):
    """CNN with late goal fusion, Gaussian head, radar+goal (study: ~1300 iterations)."""

    name: str = "rl-gaussian-radar"
    observation: str = "radar+goal"
    action: str = "gaussian"
    num_envs: int = 64  # the CNN's 1.3 M weights fit noise in small batches: B = 4096
    fvp_fraction: float = 0.1  # 410 rows suffice for the Fisher-vector products
    critic_epochs: int = 2  # the critic's CNN dominates the update's cost
    critic_minibatch: int = 512
    balanced_fusion: bool = True  # the goal's weight in FC 1 (learning.algorithms.networks)
    study_iterations: int = 1300


@dataclass(frozen=True)
class CategoricalRadar(RLSetup):
    """CNN with late goal fusion, 41 categories, radar+goal (study: ~4300 iterations)."""

    name: str = "rl-categorical-radar"
    observation: str = "radar+goal"
    action: str = "categorical"
    num_envs: int = 64  # as GaussianRadar
    fvp_fraction: float = 0.1
    critic_epochs: int = 2
    critic_minibatch: int = 512
    balanced_fusion: bool = True  # the goal's weight in FC 1 (learning.algorithms.networks)
    study_iterations: int = 4300


SETUPS: dict[str, RLSetup] = {
    s.name: s
    for s in (GaussianPositional(), CategoricalPositional(), GaussianRadar(), CategoricalRadar())
}


def setup_names() -> tuple[str, ...]:
    return tuple(SETUPS)


def get_setup(name: str) -> RLSetup:
    """The setup called ``name``; ``ValueError`` naming the known setups otherwise."""
    try:
        return SETUPS[name]
    except KeyError:
        raise ValueError(f"unknown setup {name!r}; known setups: {', '.join(SETUPS)}") from None


def trpo_config_of(setup: Any, seed: int = 0, iterations: int | None = None) -> TRPOConfig:
    """The :class:`TRPOConfig` of a setup (RL or IL) that has the TRPO hyperparameter fields."""
    return TRPOConfig(
        seed=seed,
        iterations=setup.iterations if iterations is None else iterations,
        num_envs=setup.num_envs,
        steps_per_env=setup.steps_per_env,
        gamma=setup.gamma,
        gae_lambda=setup.gae_lambda,
        max_kl=setup.max_kl,
        cg_iters=setup.cg_iters,
        cg_damping=setup.cg_damping,
        fvp_fraction=setup.fvp_fraction,
        critic_lr=setup.critic_lr,
        critic_epochs=setup.critic_epochs,
        critic_minibatch=setup.critic_minibatch,
        network=NetworkConfig(
            init_std_fraction=setup.init_std_fraction,
            balanced_fusion=setup.balanced_fusion,
        ),
    )
