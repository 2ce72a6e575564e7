"""Starting and loading policies with radar memory (:mod:`usvsim.task.radar_memory`).

A policy with radar memory reads K radar images as K channels; its checkpoint says K in its
setup's ``radar_frames``. :func:`policy_observation_space` is the space such a policy reads (the
checkpoint reader checks the stored weights against it); :func:`widened_policy_state` turns a
one-image policy into the first policy of a memory run with the same actions.
"""

from __future__ import annotations

from typing import Any, cast

import torch
from gymnasium import spaces

from learning.algorithms.networks import space_from_spec, space_to_spec
from usvsim.task.observations import ObservationKind, observation_space
from usvsim.task.radar_memory import memory_frames, stacked_space

__all__ = ["policy_observation_space", "widened_policy_state"]


def policy_observation_space(kind: str, setup_params: dict[str, Any]) -> spaces.Space:
    """The single-boat observation space a policy of observation ``kind`` reads: the kind's,
    with the setup's radar memory (``radar_frames`` in ``setup_params``; absent: 1) stacked."""
    space = observation_space(cast(ObservationKind, kind))
    frames = int(setup_params.get("radar_frames", 1) or 1)
    return stacked_space(space, frames) if frames > 1 else space


def widened_policy_state(state: dict[str, Any], frames: int) -> dict[str, Any]:
    """A one-image ``radar+goal`` agent state for a policy with radar memory of ``frames``
    images: the convolution's weights for the earlier images start at zero, so the widened
    policy is the same function of the image now (its actions are those of the original,
    whatever the earlier images), and the observation space is the stacked one."""
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
