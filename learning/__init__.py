"""usvsim's learning package: the study's networks and TRPO (Schulman et al. 2015) in PyTorch.

==========================  ====================================================================
module                      contents
==========================  ====================================================================
``learning.networks``       MLP and CNN trunks, Gaussian/categorical policy, critic
``learning.distributions``  diagonal Gaussian and categorical distributions with explicit KL
``learning.normalization``  running mean/std observation normaliser (saved with the model)
``learning.gae``            GAE(γ, λ) with terminated/truncated kept apart
``learning.rollout``        batched rollouts from a gymnasium 1.x VectorEnv (both autoreset modes)
``learning.trpo``           TRPOConfig, the TRPO step and its parts, TRPOAgent, train()
==========================  ====================================================================
"""

from learning.gae import gae
from learning.networks import NetworkConfig, make_critic, make_policy
from learning.normalization import ObservationNormalizer, RunningMeanStd
from learning.rollout import NonFiniteError, RolloutBatch, RolloutCollector
from learning.trpo import IterationStats, TRPOAgent, TRPOConfig, train

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
