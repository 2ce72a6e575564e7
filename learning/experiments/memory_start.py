"""Starting and loading policies with radar memory (:mod:`usvsim.task.radar_memory`).

A policy with radar memory reads K radar images as K channels; its checkpoint says K in its
setup's ``radar_frames``. :func:`policy_observation_space` is the space such a policy reads (the
checkpoint reader checks the stored weights against it); :func:`widened_policy_state` turns a
one-image policy into the first policy of a memory run with the same actions.
:func:`check_cpu_only_options` refuses the options of the CPU env only (radar memory, the goal
mark, and unsafe ends, an env argument kept with them so that RL and IL refuse in one place)
on another ``--device``.
"""

from __future__ import annotations

from typing import Any, cast

import torch
from gymnasium import spaces

from learning.algorithms.networks import space_from_spec, space_to_spec
from usvsim.common.errors import UserError
from usvsim.task.goal_mark import marked_space
from usvsim.task.observations import ObservationKind, observation_space
from usvsim.task.radar_memory import memory_frames, stacked_space

__all__ = [
    "check_cpu_only_options",
    "image_channels",
    "policy_observation_space",
    "setup_goal_mark",
    "start_state",
    "widened_policy_state",
]


def policy_observation_space(kind: str, setup_params: dict[str, Any]) -> spaces.Space:
    """The single-boat observation space a policy of observation ``kind`` reads: the kind's,
    with the setup's radar memory (``radar_frames`` in ``setup_params``; absent: 1) stacked and
    its goal mark (``goal_mark``; absent: none, :mod:`usvsim.task.goal_mark`) added."""
    space = observation_space(cast(ObservationKind, kind))
    frames = int(setup_params.get("radar_frames", 1) or 1)
    space = stacked_space(space, frames) if frames > 1 else space
    return marked_space(space) if setup_params.get("goal_mark") else space


def image_channels(setup_params: dict[str, Any]) -> int:
    """The image channels a ``radar+goal`` policy of ``setup_params`` reads: its radar images
    (``radar_frames``) and the goal mark's (``goal_mark``)."""
    return int(setup_params.get("radar_frames", 1) or 1) + int(bool(setup_params.get("goal_mark")))


def widened_policy_state(state: dict[str, Any], frames: int) -> dict[str, Any]:
    """A one-image ``radar+goal`` agent state for a policy of ``frames`` image channels (radar
    memory's earlier images, the goal mark, :func:`image_channels`): the convolution's weights
    for the added channels start at zero, so the widened policy is the same function of the
    image now (its actions are those of the original, whatever the added channels hold), and
    the observation space is the widened one."""
    space = space_from_spec(state["observation_space"])
    have = memory_frames(space)
    if have != 1:
        raise ValueError(f"only a one-image policy can be widened, this one reads {have}")
    policy = dict(state["policy"])
    convs = [k for k, v in policy.items() if k.endswith("conv.weight") and v.ndim == 4]
    if len(convs) != 1:
        raise ValueError(f"expected one convolution in the policy, found {convs}")
    weight = policy[convs[0]]
    extra = weight.new_zeros((weight.shape[0], frames - 1, *weight.shape[2:]))
    policy[convs[0]] = torch.cat([weight, extra], dim=1)
    spec = space_to_spec(stacked_space(space, frames))
    return {**state, "policy": policy, "observation_space": spec}


def setup_goal_mark(setup: Any) -> bool:
    """Whether a setup (an ``RLSetup``, or a checkpoint's ``setup_params`` dict) draws the goal
    mark into its policy's image (:mod:`usvsim.task.goal_mark`); False where it has no say."""
    if isinstance(setup, dict):
        return bool(setup.get("goal_mark", False))
    return bool(getattr(setup, "goal_mark", False))


def check_cpu_only_options(setup: Any, device: str) -> None:
    """``UserError`` where ``setup`` (RL or IL) trains on a ``device`` other than cpu with an
    option of the CPU env only: radar memory or the goal mark (NumPy wrappers), unsafe ends (an
    argument of ``OpenWaterVectorEnv``). The message names the options that are on."""
    frames = int(getattr(setup, "radar_frames", 1))
    on = [
        name
        for name, used in (
            (f"radar memory (radar_frames {frames})", frames > 1),
            ("the goal mark (goal_mark)", setup_goal_mark(setup)),
            ("unsafe ends (unsafe_ends)", bool(getattr(setup, "unsafe_ends", False))),
        )
        if used
    ]
    if device != "cpu" and on:
        raise UserError(
            f"{setup.name}: {' and '.join(on)} train on --device cpu only, got --device {device}"
        )


def start_state(state: dict[str, Any], start_params: dict[str, Any], setup: Any) -> dict[str, Any]:
    """The agent state ``state`` of a start file (its setup's ``start_params``) for a run of
    ``setup``: unchanged where it reads the run's image channels, widened
    (:func:`widened_policy_state`) where it reads one image; ``ValueError`` otherwise."""
    channels = image_channels(
        {"radar_frames": getattr(setup, "radar_frames", 1), "goal_mark": setup_goal_mark(setup)}
    )
    have = memory_frames(space_from_spec(state["observation_space"]))
    if channels == have and setup_goal_mark(start_params) == setup_goal_mark(setup):
        return state
    if have != 1:
        raise ValueError(
            f"a policy of {have} image channels cannot start a run of {channels} ({setup.name})"
        )
    return widened_policy_state(state, channels)
