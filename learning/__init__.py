"""usvsim's learning package: the study's networks and TRPO (Schulman et al. 2015) in PyTorch.

==========================  ====================================================================
module                      contents
==========================  ====================================================================
``learning.algorithms.networks``       MLP and CNN trunks, Gaussian/categorical policy, critic
``learning.algorithms.distributions``  diagonal Gaussian and categorical distributions with explicit KL
``learning.algorithms.normalization``  running mean/std observation normaliser (saved with the model)
``learning.algorithms.gae``            GAE(γ, λ) with terminated/truncated kept apart
``learning.algorithms.rollout``        batched rollouts from a gymnasium 1.x VectorEnv (both autoreset modes)
``learning.algorithms.trpo``           TRPOConfig, the TRPO step and its parts, TRPOAgent, train()
==========================  ====================================================================
"""

from learning.algorithms.gae import gae
from learning.algorithms.networks import NetworkConfig, make_critic, make_policy
from learning.algorithms.normalization import ObservationNormalizer, RunningMeanStd
from learning.algorithms.rollout import NonFiniteError, RolloutBatch, RolloutCollector
from learning.algorithms.trpo import IterationStats, TRPOAgent, TRPOConfig, train

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
