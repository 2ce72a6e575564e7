"""A policy's first episodes on a torch env: validation on the device (issue 40).

The twin of :func:`usvsim.evaluation.openwater.evaluate_open_water` for a torch env whose table
holds the episodes (boat i's first episode is row i: ``per_boat=1``): the deterministic policy
(the distribution's mode, Box actions clipped to the bounds, as
:meth:`learning.algorithms.actor_critic.ActorCriticAgent.act`) on the normalised observations,
every boat until its first episode ends, and what each first episode came to. With
``noise="replay"`` in float64 on ``torch-cpu`` the outcomes are the CPU evaluation's (tested
on the family validation set); on a GPU a validation set runs where CasADi is missing (the
episodes packed elsewhere: :func:`usvsim.task.torch_openwater_episodes.pack_episodes`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from numpy.typing import NDArray

from learning.algorithms.device_rollout import DeviceNormalizer

__all__ = ["OUTCOMES", "first_episode_outcomes", "outcome_counts"]

#: What :func:`first_episode_outcomes` returns per boat (the CPU records' fields).
OUTCOMES = ("is_success", "reached_goal", "collision", "min_distance_m")
_CHECK_EVERY = 8  # decisions between reading "has every boat finished?" back to the host


@torch.no_grad()
def first_episode_outcomes(
    policy: torch.nn.Module,
    normalise: DeviceNormalizer,
    env: Any,
    obs: Any,
    action_bounds: tuple[float, float] | None,
    max_decisions: int,
) -> dict[str, NDArray[Any]]:
    """Step ``env`` (just reset; ``obs`` its first observation) with ``policy``'s deterministic
    actions until every boat's first episode has ended (at most ``max_decisions``); returns
    :data:`OUTCOMES` (N,) as NumPy arrays, each at the boat's first episode's end.

    Raises ``RuntimeError`` where a boat's first episode has not ended by ``max_decisions``."""
    n, device = env.num_envs, torch.device(env.device)
    active = torch.ones(n, dtype=torch.bool, device=device)
    out = {key: torch.zeros(n, dtype=torch.float64, device=device) for key in OUTCOMES}
    policy.eval()
    for k in range(max_decisions):
        actions = policy(normalise(obs)).mode()
        if action_bounds is not None:
            actions = actions.clamp(*action_bounds)
        obs, _, terminated, truncated, info = env.step(actions)
        ended = active & (terminated | truncated)
        for key in OUTCOMES:
            out[key] = torch.where(ended, info[key].to(torch.float64), out[key])
        active &= ~ended
        if (k + 1) % _CHECK_EVERY == 0 and not bool(active.any()):
            break
    if bool(active.any()):
        raise RuntimeError(
            f"{int(active.sum())} boats had not finished in {max_decisions} decisions"
        )
    result = {key: value.cpu().numpy() for key, value in out.items()}
    for key in ("is_success", "reached_goal", "collision"):
        result[key] = result[key].astype(bool)
    return result


def outcome_counts(outcomes: dict[str, NDArray[Any]]) -> dict[str, float]:
    """Successes, episodes, collisions and the closest approach of a set's outcomes (the keys of
    :func:`learning.experiments.validation.family_summary`, unprefixed)."""
    return {
        "successes": int(outcomes["is_success"].sum()),
        "n_episodes": int(outcomes["is_success"].size),
        "collisions": int(outcomes["collision"].sum()),
        "min_distance_m": float(np.min(outcomes["min_distance_m"])),
    }
