"""Checkpoints of trained policies: a documented, versioned file format, and loading as a
helmsman.

A checkpoint is one file written by ``torch.save`` (atomically, :mod:`usvsim.common.fileio`)
holding a dict of plain data and tensors only, so that it loads with
``torch.load(weights_only=True)`` (no pickled code runs when a file is opened):

=====================  =========================================================================
key                    value
=====================  =========================================================================
``format``             ``"usvsim.checkpoint"`` (identifies the file)
``version``            :data:`VERSION` (an int; a reader refuses newer versions)
``setup``              setup name, e.g. ``"rl-gaussian-positional"``
                       (:mod:`learning.experiments.setups`)
``observation``        observation kind the policy needs: ``positional`` | ``radar+goal``
``action``             action kind it produces: ``gaussian`` | ``categorical``
``setup_params``       the setup used (:func:`learning.experiments.setups.setup_params`: its
                       fields, the algorithm's config nested; older files: flat)
``algorithm``          registered name of the algorithm whose agent ``agent`` holds
                       (:mod:`learning.algorithms.registry`); ``"trpo"`` when absent (older
                       files, and IL runs: GAIL trains a TRPO policy)
``agent``              the agent's ``state_dict`` (e.g. :meth:`learning.algorithms.trpo.TRPOAgent.
                       state_dict`): config, observation and action spaces, policy weights,
                       observation-normaliser statistics (mean, var, count as lists), and —
                       unless ``slim`` — critic, critic optimiser, random generator and
                       counters needed to resume training
``slim``               True when only what acting needs is stored (policy + normaliser)
``weights_dtype``      ``"float32"``, or ``"float16"`` when the policy's floating-point
                       tensors were stored in half precision (converted back on load)
``git_revision``       ``git describe --always --dirty`` of the code that trained it, or
                       ``"unknown"``
``created_utc``        ISO 8601 time of writing
``train_args``         the command-line options of the run (dict)
``validation``         the validation record this checkpoint was saved at (dict, or None):
                       iteration, env_steps, wall_time_s, successes, n_episodes, success_rate,
                       mean_return, min_pole_distance_m, kl, entropy
``history``            every validation record of the run up to this checkpoint (list)
=====================  =========================================================================

:func:`load_checkpoint` checks all of it and raises :class:`CheckpointError` with the file's path
and what is wrong (unreadable or truncated file, not a checkpoint, newer version, missing keys,
another setup or observation kind than expected, weights that do not fit the network).
:func:`load_helmsman` wraps the policy's deterministic action as a
:class:`usvsim.helm.protocol.Helmsman` that declares its ``observation`` and ``action`` kinds
(read by :func:`usvsim.helm.registry.helmsman_kinds`). Agents are built and restored through
:mod:`learning.algorithms.registry`, whatever the algorithm.
"""

from __future__ import annotations

import datetime as _dt
import os
import pickle
import subprocess
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import numpy as np
import torch
from numpy.typing import NDArray

from learning.algorithms.base import Agent
from learning.algorithms.networks import space_to_spec
from learning.algorithms.registry import get_algorithm
from learning.experiments.memory_start import (
    policy_observation_space,
    setup_goal_mark,
    start_state,
)
from learning.experiments.setups import RLSetup, get_setup, setup_params
from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_open
from usvsim.task.batch import ActionKind, action_space
from usvsim.task.goal_mark import with_goal_mark
from usvsim.task.observations import ObservationKind
from usvsim.task.radar_memory import RadarMemory, memory_frames

__all__ = [
    "FORMAT",
    "VERSION",
    "Checkpoint",
    "CheckpointError",
    "NonFiniteWeightsError",
    "PolicyHelmsman",
    "checkpoint_kinds",
    "git_revision",
    "load_agent",
    "load_checkpoint",
    "load_helmsman",
    "save_checkpoint",
    "slim_copy",
    "starting_policy",
]

FORMAT = "usvsim.checkpoint"
VERSION = 1
_REQUIRED = ("setup", "observation", "action", "setup_params", "agent", "slim", "weights_dtype")


class CheckpointError(UserError):
    """A checkpoint file that cannot be used: unreadable, not a checkpoint, or mismatched."""


class NonFiniteWeightsError(ValueError):
    """Refused to save a policy holding NaN or ±inf (the file on disk is left as it was)."""


def git_revision(repo: str | os.PathLike[str] | None = None) -> str:
    """``git describe --always --dirty`` of ``repo`` (default: this package's), or "unknown"."""
    cwd = Path(repo) if repo is not None else Path(__file__).resolve().parent
    try:
        out = subprocess.run(
            ["git", "describe", "--always", "--dirty"],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=10,
            check=True,
        )
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() or "unknown"


def _plain(value: Any) -> Any:
    """Numpy arrays and scalars → lists and Python numbers (recursively), tensors kept."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _cast_floats(state: dict[str, Any], dtype: torch.dtype) -> dict[str, Any]:
    return {
        k: v.to(dtype) if isinstance(v, torch.Tensor) and v.is_floating_point() else v
        for k, v in state.items()
    }


@dataclass
class Checkpoint:
    """A checkpoint in memory (see the module table for the meaning of each field)."""

    setup: str
    observation: str
    action: str
    setup_params: dict[str, Any]
    agent: dict[str, Any]
    slim: bool = False
    weights_dtype: str = "float32"
    git_revision: str = "unknown"
    created_utc: str = ""
    train_args: dict[str, Any] = field(default_factory=dict)
    validation: dict[str, Any] | None = None
    history: list[dict[str, Any]] = field(default_factory=list)
    algorithm: str = "trpo"  # registered algorithm of ``agent`` (learning.algorithms.registry)

    @classmethod
    def from_agent(
        cls,
        agent: Agent,
        setup: Any,
        *,
        train_args: dict[str, Any] | None = None,
        validation: dict[str, Any] | None = None,
        history: list[dict[str, Any]] | None = None,
    ) -> Checkpoint:
        """The full (resumable) checkpoint of ``agent`` trained on ``setup`` (an RL or IL setup:
        ``name``, ``observation``, ``action``, ``algorithm`` and its fields)."""
        return cls(
            setup=setup.name,
            observation=setup.observation,
            action=setup.action,
            setup_params=_plain(setup_params(setup)),
            algorithm=setup.algorithm,
            agent=_plain(agent.state_dict()),
            git_revision=git_revision(),
            train_args=_plain(dict(train_args or {})),
            validation=None if validation is None else _plain(dict(validation)),
            history=[_plain(dict(h)) for h in history or []],
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": VERSION,
            "setup": self.setup,
            "observation": self.observation,
            "action": self.action,
            "setup_params": self.setup_params,
            "algorithm": self.algorithm,
            "agent": self.agent,
            "slim": self.slim,
            "weights_dtype": self.weights_dtype,
            "git_revision": self.git_revision,
            "created_utc": self.created_utc
            or _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "train_args": self.train_args,
            "validation": self.validation,
            "history": self.history,
        }

    def make_agent(self) -> Agent:
        """The agent: fully restored (resumable) unless slim, else policy and normaliser only."""
        algorithm = get_algorithm(self.algorithm)
        if not self.slim:
            return algorithm.from_state_dict(self.agent)
        state = self.agent
        observation, action = checkpoint_kinds(self)
        agent = algorithm.make_agent(
            policy_observation_space(observation, self.setup_params),
            action_space(action),
            algorithm.config_from_dict(state["config"]),
        )
        agent.policy.load_state_dict(_cast_floats(state["policy"], torch.float32))
        agent.normalizer.load_state_dict(state["normalizer"])
        agent.iteration, agent.env_steps = int(state["iteration"]), int(state["env_steps"])
        return agent


def save_checkpoint(checkpoint: Checkpoint, path: str | os.PathLike[str]) -> None:
    """Write ``checkpoint`` to ``path`` atomically (the old file stays whole if this fails).

    Refuses (:class:`NonFiniteWeightsError`, nothing written) a policy holding NaN or ±inf.
    """
    for name, tensor in checkpoint.agent["policy"].items():
        if isinstance(tensor, torch.Tensor) and tensor.is_floating_point():
            if not bool(torch.isfinite(tensor).all()):
                raise NonFiniteWeightsError(
                    f"refusing to save a policy with non-finite weights ({name})"
                )
    with atomic_open(path, "wb") as handle:
        torch.save(checkpoint.to_dict(), handle)


def slim_copy(checkpoint: Checkpoint, half: bool = False) -> Checkpoint:
    """What acting needs only (policy + normaliser), optionally with float16 weights.

    The shipped models in ``usvsim/models`` are slim copies: a few MB instead of the full
    training state (critic and Adam moments triple the size).
    """
    keep = ("format", "config", "observation_space", "action_space", "normalizer")
    agent = {k: checkpoint.agent[k] for k in keep}
    agent["iteration"], agent["env_steps"] = (
        checkpoint.agent["iteration"],
        checkpoint.agent["env_steps"],
    )
    policy = checkpoint.agent["policy"]
    agent["policy"] = _cast_floats(policy, torch.float16) if half else dict(policy)
    return Checkpoint(
        setup=checkpoint.setup,
        observation=checkpoint.observation,
        action=checkpoint.action,
        setup_params=checkpoint.setup_params,
        agent=agent,
        slim=True,
        weights_dtype="float16" if half else "float32",
        git_revision=checkpoint.git_revision,
        created_utc=checkpoint.created_utc,
        train_args=checkpoint.train_args,
        validation=checkpoint.validation,
        history=checkpoint.history,
        algorithm=checkpoint.algorithm,
    )


def _read(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise CheckpointError(f"{path}: no such checkpoint file")
    # torch.save writes a zip archive with CRCs: check it first, so a truncated or overwritten
    # file is named as such rather than failing somewhere inside the unpickler.
    try:
        with zipfile.ZipFile(path) as archive:
            bad = archive.testzip()
    # ValueError: e.g. UnicodeDecodeError for a member name flagged UTF-8 that is not (found
    # by hypothesis); NotImplementedError: a compression method zipfile does not know
    except (zipfile.BadZipFile, OSError, EOFError, ValueError, NotImplementedError) as err:
        raise CheckpointError(
            f"{path}: not a readable checkpoint (corrupt or truncated file?): {err}"
        ) from None
    if bad is not None:
        raise CheckpointError(f"{path}: not a readable checkpoint (corrupt member {bad})")
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except (
        RuntimeError,
        pickle.UnpicklingError,
        EOFError,
        OSError,
        IndexError,
        ValueError,
    ) as err:
        raise CheckpointError(
            f"{path}: not a readable checkpoint (corrupt or truncated file?): {err}"
        ) from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise CheckpointError(f"{path}: not a usvsim checkpoint (no format {FORMAT!r})")
    version = data.get("version")
    if not isinstance(version, int) or version > VERSION:
        raise CheckpointError(
            f"{path}: checkpoint version {version!r} is not supported (this code reads ≤ {VERSION})"
        )
    missing = [k for k in _REQUIRED if k not in data]
    if missing:
        raise CheckpointError(f"{path}: checkpoint lacks {missing}")
    return data


_TYPES: dict[str, tuple[type, ...]] = {
    "setup": (str,),
    "observation": (str,),
    "action": (str,),
    "setup_params": (dict,),
    "agent": (dict,),
    "slim": (bool,),
    "weights_dtype": (str,),
    "train_args": (dict, type(None)),
    "validation": (dict, type(None)),
    "history": (list, type(None)),
    "algorithm": (str,),
}


def _check_types(path: Path, data: dict[str, Any]) -> None:
    """Each stored field of the type the reader expects (found by the property tests: a
    ``None`` where a dict belongs raised ``TypeError`` from deep inside)."""
    for key, types in _TYPES.items():
        if key in data and not isinstance(data[key], types):
            allowed = " or ".join(t.__name__ for t in types)
            raise CheckpointError(
                f"{path}: checkpoint field {key!r} must be {allowed}, got "
                f"{type(data[key]).__name__}"
            )


def _check_spaces(path: Path, data: dict[str, Any]) -> None:
    """The stored spaces must be those of the stored observation/action kinds."""
    try:
        params = data.get("setup_params")
        obs_spec = space_to_spec(
            policy_observation_space(
                data["observation"], params if isinstance(params, dict) else {}
            )
        )
        act_spec = space_to_spec(action_space(data["action"]))
    except ValueError as err:
        raise CheckpointError(f"{path}: {err}") from None
    agent = data["agent"]
    if agent.get("observation_space") != obs_spec:
        raise CheckpointError(
            f"{path}: its policy's observation space does not match observation "
            f"{data['observation']!r} (file edited or written by other code)"
        )
    if agent.get("action_space") != act_spec:
        raise CheckpointError(
            f"{path}: its policy's action space does not match action {data['action']!r}"
        )


def load_checkpoint(
    path: str | os.PathLike[str], expected_setup: str | RLSetup | None = None
) -> Checkpoint:
    """Read and check a checkpoint file; optionally require it to be of ``expected_setup``.

    Raises
    ------
    CheckpointError
        If the file is missing, unreadable, not a usvsim checkpoint, of a newer version,
        incomplete, internally inconsistent, or of another setup (then the message names both
        setups and their observation/action kinds).
    """
    p = Path(path)
    data = _read(p)
    _check_types(p, data)
    if expected_setup is not None:
        want = get_setup(expected_setup) if isinstance(expected_setup, str) else expected_setup
        if (data["setup"], data["observation"], data["action"]) != (
            want.name,
            want.observation,
            want.action,
        ):
            raise CheckpointError(
                f"{p}: checkpoint is for setup {data['setup']!r} (observation "
                f"{data['observation']!r}, action {data['action']!r}), expected {want.name!r} "
                f"(observation {want.observation!r}, action {want.action!r})"
            )
    _check_spaces(p, data)
    ckpt = Checkpoint(
        setup=str(data["setup"]),
        observation=str(data["observation"]),
        action=str(data["action"]),
        setup_params=dict(data["setup_params"]),
        agent=dict(data["agent"]),
        slim=bool(data["slim"]),
        weights_dtype=str(data["weights_dtype"]),
        git_revision=str(data.get("git_revision", "unknown")),
        created_utc=str(data.get("created_utc", "")),
        train_args=dict(data.get("train_args") or {}),
        validation=data.get("validation"),
        history=list(data.get("history") or []),
        algorithm=str(data.get("algorithm", "trpo")),
    )
    try:
        get_algorithm(ckpt.algorithm)
    except ValueError as err:
        raise CheckpointError(f"{p}: {err}") from None
    return ckpt


def starting_policy(path: str | os.PathLike[str], setup: RLSetup) -> dict[str, Any]:
    """The agent state of the checkpoint at ``path`` (slim or full; float32 weights) for a run
    of ``setup`` to start from (``Agent.load_policy``): any setup's, e.g. a GAIL run's, as long
    as its observation and action kinds are ``setup``'s.

    Raises :class:`CheckpointError` (as :func:`load_checkpoint`) or where the kinds differ.
    """
    ckpt = load_checkpoint(path)
    if (ckpt.observation, ckpt.action) != (setup.observation, setup.action):
        raise CheckpointError(
            f"{path}: a {ckpt.observation}/{ckpt.action} policy ({ckpt.setup}) cannot start a "
            f"{setup.observation}/{setup.action} run ({setup.name})"
        )
    state = {**ckpt.agent, "policy": _cast_floats(ckpt.agent["policy"], torch.float32)}
    try:  # the image channels of the setup's policy (radar memory, goal mark)
        return start_state(state, ckpt.setup_params, setup)
    except ValueError as err:
        raise CheckpointError(f"{path}: {err}") from None


def load_agent(checkpoint: Checkpoint, path: str | os.PathLike[str] = "<memory>") -> Agent:
    """``checkpoint.make_agent()`` with weight errors reported as :class:`CheckpointError`."""
    try:
        return checkpoint.make_agent()
    # AttributeError/IndexError: nested state of the wrong shape (found by the property tests)
    except (KeyError, TypeError, ValueError, RuntimeError, AttributeError, IndexError) as err:
        raise CheckpointError(
            f"{path}: weights do not fit the {checkpoint.setup} networks: {err}"
        ) from None


@dataclass
class PolicyHelmsman:
    """A trained policy as a :class:`usvsim.helm.protocol.Helmsman`: deterministic actions.

    ``observation`` and ``action`` name the kinds it needs
    (``usvsim.helm.registry.helmsman_kinds``); Gaussian actions are the mean clipped to [-1, 1],
    categorical ones the most likely bin.
    """

    agent: Agent
    observation: ObservationKind
    action: ActionKind
    name: str = "policy"
    goal_mark: bool = False  # its image's last channel is the goal mark (usvsim.task.goal_mark)

    def __post_init__(self) -> None:
        # a policy with radar memory (usvsim.task.radar_memory) keeps each boat's earlier
        # images itself, and draws its goal mark itself: the simulations give the image now
        frames = memory_frames(self.agent.observation_space) - int(self.goal_mark)
        self.memory = RadarMemory(frames) if frames > 1 else None

    def reset(self, n_boats: int) -> None:
        self._n = n_boats
        if self.memory is not None:
            self.memory.reset(n_boats)

    def act(self, observation: Any) -> NDArray[Any]:
        if self.memory is not None:
            observation = self.memory(observation)
        if self.goal_mark:
            observation = with_goal_mark(observation)
        return self.agent.act(observation, deterministic=True)


def load_helmsman(path: str | os.PathLike[str]) -> PolicyHelmsman:
    """The policy of the checkpoint at ``path`` as a helmsman named after the file's stem."""
    ckpt = load_checkpoint(path)
    agent = load_agent(ckpt, path)
    return PolicyHelmsman(
        agent, *checkpoint_kinds(ckpt), name=Path(path).stem,
        goal_mark=setup_goal_mark(ckpt.setup_params),
    )  # fmt: skip


def checkpoint_kinds(checkpoint: Checkpoint) -> tuple[ObservationKind, ActionKind]:
    """The observation and action kinds of a loaded checkpoint (checked by
    :func:`load_checkpoint`)."""
    return (
        cast(ObservationKind, checkpoint.observation),
        cast(ActionKind, checkpoint.action),
    )
