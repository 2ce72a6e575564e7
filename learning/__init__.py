"""usvsim's learning package: the study's networks and TRPO (Schulman et al. 2015) in PyTorch.

=======================================  =========================================================
module                                   contents
=======================================  =========================================================
``learning.algorithms.networks``         MLP and CNN trunks, Gaussian/categorical policy, critic
``learning.algorithms.distributions``    diagonal Gaussian and categorical distributions, KL
``learning.algorithms.normalization``    running mean/std observation normaliser (saved)
``learning.algorithms.gae``              GAE(γ, λ) with terminated/truncated kept apart
``learning.algorithms.rollout``          batched rollouts from a gymnasium 1.x VectorEnv
``learning.algorithms.base``             the Agent protocol every algorithm meets, config_from_dict
``learning.algorithms.trust_region``     conjugate gradient, Fisher-vector products, line search
``learning.algorithms.trpo``             TRPOConfig, the TRPO step, TRPOAgent
``learning.algorithms.registry``         the one registry of algorithms by name
``learning.algorithms.loop``             the on-policy training loop, generic over Agent
``learning.imitation``                   demonstrations, preprocessing, GAIL (discriminator)
``learning.experiments``                 setups, checkpoints, validation, the training runs
``learning.cli``                         ``usvsim train`` and ``usvsim evaluate``
=======================================  =========================================================
"""

from learning.algorithms.gae import gae
from learning.algorithms.loop import IterationStats, train
from learning.algorithms.networks import NetworkConfig, make_critic, make_policy
from learning.algorithms.normalization import ObservationNormalizer, RunningMeanStd
from learning.algorithms.rollout import NonFiniteError, RolloutBatch, RolloutCollector
from learning.algorithms.trpo import TRPOAgent, TRPOConfig

__all__ = [
    "IterationStats",
    "NetworkConfig",
    "NonFiniteError",
    "ObservationNormalizer",
    "RolloutBatch",
    "RolloutCollector",
    "RunningMeanStd",
    "TRPOAgent",
    "TRPOConfig",
    "gae",
    "make_critic",
    "make_policy",
    "train",
]
