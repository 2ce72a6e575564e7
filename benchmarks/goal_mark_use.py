"""How much a goal-mark policy reads its mark (``usvsim.task.goal_mark``): the change of its
heading command when the mark channel is blanked (``docs/notes/2026-12-traffic.md``, "A goal mark
in the radar image").

``N`` open-water boats (``usvsim/OpenWater-v0``'s family, radar+goal, seeded) take uniformly
random actions for ``T`` decisions; at every ``--every``-th decision the policy's deterministic
heading change (deg) is computed twice, with the goal mark drawn and with its channel set to 0,
and the absolute differences are summarised (mean, 90th percentile, max). Beside them the norm
of the convolution's weights on each input channel (the radar image's and the mark's). A
policy widened from a one-image file and not yet trained reads 0. Printed as JSON::

    python benchmarks/goal_mark_use.py --policies A.pt,B.pt
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from learning.algorithms.networks import CNNTrunk
from learning.experiments.checkpoint import CheckpointError, load_helmsman
from usvsim.task.batch import heading_change_rad
from usvsim.task.goal_mark import with_goal_mark
from usvsim.task.openwater_env import OpenWaterVectorEnv
from usvsim.task.scenario import Scenario


def decision_observations(n_boats: int, decisions: int, every: int, seed: int) -> list[Any]:
    """Every ``every``-th radar+goal observation of ``n_boats`` open-water boats taking uniform
    random actions for ``decisions`` decisions (``seed`` for the env and the actions)."""
    env = OpenWaterVectorEnv(n_boats, observation="radar+goal")
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    kept: list[Any] = []
    for t in range(decisions):
        obs, *_ = env.step(rng.uniform(-1.0, 1.0, (n_boats, 1)))
        if t % every == 0:
            assert isinstance(obs, dict)
            kept.append({k: np.array(v, copy=True) for k, v in obs.items()})
    return kept


def mark_use(path: str | Path, observations: list[Any]) -> dict[str, Any]:
    """The summary (module docstring) of the goal-mark policy at ``path`` on ``observations``."""
    helmsman = load_helmsman(path)
    if not helmsman.goal_mark:
        raise CheckpointError(f"{path}: not a goal-mark policy (setup goal_mark false)")
    agent, limit = helmsman.agent, Scenario().max_heading_change_rad
    diffs = []
    for obs in observations:
        n = obs["goal"].shape[0]
        marked = with_goal_mark(obs)
        blank = {**marked, "radar": marked["radar"].copy()}
        blank["radar"][:, -1] = 0
        turn = [np.degrees(heading_change_rad(helmsman.action, agent.act(o, deterministic=True),
                                              n, limit)) for o in (marked, blank)]  # fmt: skip
        diffs.append(np.abs(turn[0] - turn[1]))
    d = np.concatenate(diffs)
    trunk = agent.policy.trunk
    assert isinstance(trunk, CNNTrunk)
    weight = trunk.conv.weight.detach()
    norms = [round(float(weight[:, c].norm()), 4) for c in range(weight.shape[1])]
    return {
        "policy": str(path),
        "decisions": int(d.size),
        "mean_deg": round(float(d.mean()), 3),
        "p90_deg": round(float(np.percentile(d, 90)), 3),
        "max_deg": round(float(d.max()), 2),
        "conv_weight_norm_per_channel": norms,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--policies", required=True, help="comma-separated checkpoint files")
    parser.add_argument("--boats", type=int, default=256)
    parser.add_argument("--decisions", type=int, default=30)
    parser.add_argument("--every", type=int, default=3)
    parser.add_argument("--seed", type=int, default=5)
    args = parser.parse_args(argv)
    if min(args.boats, args.decisions, args.every) < 1:
        parser.error("--boats, --decisions and --every must be >= 1")
    observations = decision_observations(args.boats, args.decisions, args.every, args.seed)
    try:
        rows = [mark_use(p, observations) for p in args.policies.split(",")]
    except CheckpointError as err:
        parser.exit(2, f"goal_mark_use.py: error: {err}\n")
    print(json.dumps({"boats": args.boats, "decisions": args.decisions, "every": args.every,
                      "seed": args.seed, "policies": rows}, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
