"""What every learning algorithm provides: the :class:`Agent` protocol, its update statistics
(:class:`UpdateStats`) and configuration (:class:`AlgorithmConfig`), and :func:`config_from_dict`.

An algorithm is one module (``learning.algorithms.trpo`` is the model) with a frozen config
dataclass, an agent class that meets :class:`Agent`, and a stats dataclass that meets
:class:`UpdateStats`; one line in :data:`learning.algorithms.registry.ALGORITHMS` makes it
trainable (:func:`learning.algorithms.loop.train`), storable in checkpoints and usable as a
helmsman (:mod:`learning.experiments.checkpoint`). The loop owns rollouts; the agent owns its
networks, its update and what it saves (the split of Stable-Baselines3's ``OnPolicyAlgorithm``,
Raffin et al. 2021).

=====================  ==================================================================
member                 meaning
=====================  ==================================================================
``config``             the algorithm's frozen config (:class:`AlgorithmConfig` fields)
``observation_space``  single-env gymnasium space of the raw observations
``action_space``       single-env gymnasium action space
``policy``             the policy network (``learning.algorithms.networks.Policy``)
``normalizer``         the observation normaliser the policy's inputs pass through
``iteration``          completed updates
``env_steps``          valid transitions learned from
``info_keys``          boolean per-step ``info`` arrays the update needs (``RolloutBatch.info``)
``obs_info_keys``      optional: ``info`` arrays describing s_t the update needs
                       (``RolloutBatch.aux``; absent: none)
``sample(obs)``        (actions, log-probabilities) for a rollout, arrays (N, ...), (N,)
``act(obs, det)``      environment-ready actions (N, ...)
``update(batch)``      one learning step on a :class:`RolloutBatch`; its :class:`UpdateStats`
``state_dict()``       plain data and tensors, with a ``"format"`` and a ``"config"`` entry
``load_state_dict``    restore a ``state_dict`` (raises ``ValueError`` on another format)
``load_policy``        take the policy and normaliser of a ``state_dict`` (fine-tuning)
=====================  ==================================================================

Every update's statistics carry :class:`UpdateTimes`, where its wall-clock went (measured with
:class:`Stopwatch`); with the rollout's time they are the ``log.csv`` columns
:data:`learning.algorithms.loop.TIME_FIELDS`.
"""

from __future__ import annotations

import dataclasses
import time
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, TypeVar, runtime_checkable

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from torch import nn

from learning.algorithms.networks import NetworkConfig
from learning.algorithms.normalization import ObservationNormalizer
from learning.algorithms.rollout import Obs, RolloutBatch

__all__ = [
    "Agent",
    "AlgorithmConfig",
    "Stopwatch",
    "UpdateStats",
    "UpdateTimes",
    "config_from_dict",
    "log_row",
]

C = TypeVar("C")


class AlgorithmConfig(Protocol):
    """The fields the training loop reads from any algorithm's config (all of them frozen)."""

    @property
    def seed(self) -> int: ...
    @property
    def iterations(self) -> int: ...
    @property
    def num_envs(self) -> int: ...  # N environments stepped together
    @property
    def steps_per_env(self) -> int: ...  # T steps per environment and iteration
    @property
    def gamma(self) -> float: ...  # γ, discount
    @property
    def network(self) -> NetworkConfig: ...


@dataclass(frozen=True)
class UpdateTimes:
    """Where one update's wall-clock went, s (``time.perf_counter``; parts it does not have: 0)."""

    batch_s: float = 0.0  # V(s) of the batch, GAE, checked tensors; the statistics refresh after
    policy_step_s: float = 0.0  # the policy step (TRPO: gradient, conjugate gradient, line search)
    critic_s: float = 0.0  # the critic's regression (fit_critic)
    discriminator_s: float = 0.0  # GAIL: the discriminator's step and the imitation rewards


class Stopwatch:
    """Splits wall-clock into the parts of :class:`UpdateTimes`: each :meth:`lap` adds the time
    since the previous lap (or since the stopwatch was made) to one part."""

    def __init__(self) -> None:
        self.parts = dict.fromkeys((f.name for f in dataclasses.fields(UpdateTimes)), 0.0)
        self.last = time.perf_counter()

    def lap(self, part: str) -> None:
        now = time.perf_counter()
        self.parts[part] += now - self.last
        self.last = now

    def times(self) -> UpdateTimes:
        return UpdateTimes(**self.parts)


@runtime_checkable
class UpdateStats(Protocol):
    """What one update did. ``LOG_FIELDS`` name the attributes written to ``log.csv``, in
    order (booleans are written as 0/1); ``kl`` and ``entropy`` (nats) are shown by every run;
    ``times`` is where the update's wall-clock went."""

    LOG_FIELDS: ClassVar[tuple[str, ...]]

    @property
    def kl(self) -> float: ...
    @property
    def entropy(self) -> float: ...
    @property
    def times(self) -> UpdateTimes: ...


class Agent(Protocol):
    """A learning algorithm's state and its update (module table)."""

    observation_space: spaces.Space
    action_space: spaces.Space
    iteration: int
    env_steps: int

    @property
    def config(self) -> AlgorithmConfig: ...
    @property
    def policy(self) -> nn.Module: ...
    @property
    def normalizer(self) -> ObservationNormalizer: ...
    @property
    def info_keys(self) -> tuple[str, ...]: ...

    def sample(self, obs: Obs) -> tuple[NDArray[Any], NDArray[Any]]: ...
    def act(self, obs: Obs, deterministic: bool = True) -> NDArray[Any]: ...
    def update(self, batch: RolloutBatch) -> UpdateStats: ...
    def state_dict(self) -> dict[str, Any]: ...
    def load_state_dict(self, state: dict[str, Any]) -> None: ...
    def load_policy(self, state: dict[str, Any]) -> None: ...


def log_row(stats: UpdateStats) -> dict[str, float | int]:
    """The ``log.csv`` columns of ``stats`` (``LOG_FIELDS``; booleans as 0/1)."""
    row: dict[str, float | int] = {}
    for name in stats.LOG_FIELDS:
        value = getattr(stats, name)
        row[name] = int(value) if isinstance(value, bool) else value
    return row


def config_from_dict(cls: type[C], data: Mapping[str, Any]) -> C:
    """Rebuild the (frozen) dataclass ``cls`` from ``dataclasses.asdict`` output.

    Nested dataclasses (e.g. :class:`NetworkConfig`) are rebuilt recursively and lists become
    tuples where the field is a tuple; absent keys keep their defaults. Unknown keys raise
    ``ValueError`` naming them.

    >>> config_from_dict(NetworkConfig, {"hidden": [64, 64]}).hidden
    (64, 64)
    """
    if not (isinstance(cls, type) and dataclasses.is_dataclass(cls)):
        raise TypeError(f"{cls!r} is not a dataclass")
    fields = {f.name for f in dataclasses.fields(cls) if f.init}
    unknown = sorted(set(data) - fields)
    if unknown:
        raise ValueError(f"unknown {cls.__name__} keys {unknown}; known: {sorted(fields)}")
    hints = typing.get_type_hints(cls)
    return cls(**{k: _rebuild(hints[k], v) for k, v in data.items()})


def _rebuild(hint: Any, value: Any) -> Any:
    """``value`` as the annotated type ``hint`` needs it (dataclass, tuple), else unchanged."""
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        for arg in typing.get_args(hint):
            if dataclasses.is_dataclass(arg) and isinstance(value, Mapping):
                return _rebuild(arg, value)
        return value
    if isinstance(hint, type) and dataclasses.is_dataclass(hint) and isinstance(value, Mapping):
        return config_from_dict(hint, value)
    if origin is tuple and isinstance(value, (list, tuple, np.ndarray)):
        return tuple(value)
    return value
