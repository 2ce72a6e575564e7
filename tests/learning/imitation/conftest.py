"""Shared helpers of the imitation tests."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest


class GreedyHelmsman:
    """A trained agent's deterministic actions as a positional, gaussian helmsman (for
    :func:`usvsim.evaluation.likeness.helmsman_likeness`)."""

    observation, action = "positional", "gaussian"

    def __init__(self, agent: Any) -> None:
        self.agent = agent

    def reset(self, n_boats: int) -> None:
        pass

    def act(self, obs: np.ndarray) -> np.ndarray:
        return np.asarray(self.agent.act(obs))


@pytest.fixture
def greedy() -> type[GreedyHelmsman]:
    """The :class:`GreedyHelmsman` class."""
    return GreedyHelmsman
