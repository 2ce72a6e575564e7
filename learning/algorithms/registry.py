"""The one registry of learning algorithms, by name.

Each entry gives the algorithm's config type, how to build its agent (``(observation_space,
action_space, config) -> Agent``), how to rebuild one from a ``state_dict``, and its update
statistics type. The training loop (:mod:`learning.algorithms.loop`), the checkpoints and the
policy helmsman (:mod:`learning.experiments.checkpoint`) go through it, so a new algorithm is
one module plus one line in :data:`ALGORITHMS` (:mod:`learning.algorithms.base` says what the
module must provide). GAIL (:mod:`learning.imitation.gail`) is not an entry: it trains the
policy of a registered algorithm (TRPO) against a learned reward, and what its checkpoints store
is that algorithm's agent.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gymnasium import spaces

from learning.algorithms.base import Agent, UpdateStats, config_from_dict
from learning.algorithms.ppo import PPOAgent, PPOConfig, PPOUpdateStats
from learning.algorithms.trpo import TRPOAgent, TRPOConfig, TRPOUpdateStats

__all__ = ["ALGORITHMS", "Algorithm", "algorithm_for", "get_algorithm"]


@dataclass(frozen=True)
class Algorithm:
    """One registered algorithm (module docstring)."""

    name: str
    config_type: type[Any]
    make_agent: Callable[[spaces.Space, spaces.Space, Any], Agent]
    from_state_dict: Callable[[dict[str, Any]], Agent]
    stats_type: type[UpdateStats]

    def config_from_dict(self, data: dict[str, Any]) -> Any:
        """The config stored as ``dataclasses.asdict`` (unknown keys raise ``ValueError``)."""
        return config_from_dict(self.config_type, data)


ALGORITHMS: dict[str, Algorithm] = {
    a.name: a
    for a in (
        Algorithm("trpo", TRPOConfig, TRPOAgent, TRPOAgent.from_state_dict, TRPOUpdateStats),
        Algorithm("ppo", PPOConfig, PPOAgent, PPOAgent.from_state_dict, PPOUpdateStats),
    )
}


def get_algorithm(name: str) -> Algorithm:
    """The algorithm called ``name``; ``ValueError`` naming the known ones otherwise."""
    try:
        return ALGORITHMS[name]
    except KeyError:
        raise ValueError(f"unknown algorithm {name!r}; known: {', '.join(ALGORITHMS)}") from None


def algorithm_for(config: Any) -> Algorithm:
    """The algorithm whose config type ``config`` is; ``TypeError`` if none."""
    for algorithm in ALGORITHMS.values():
        if type(config) is algorithm.config_type:
            return algorithm
    raise TypeError(f"no registered algorithm takes a {type(config).__name__}")
