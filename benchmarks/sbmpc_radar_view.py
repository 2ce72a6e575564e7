"""Why ``sb-mpc-radar`` keeps fewer COLREG rules than ``sb-mpc``: the radar's view or its tracks?

``sb-mpc`` is run on the true ``scene`` observation cut to what the radar can see (obstacle
centres within ``--range-m`` and ``--half-fov-deg`` of the bow; the rest marked absent), beside
``sb-mpc`` and ``sb-mpc-radar``, on Imazu's 22 problems, **validation** split (a diagnosis, not
a reported figure). If the cut truth loses what ``sb-mpc-radar`` loses, the view explains it
and the tracker's errors do not. Run from the repository root::

    nice python benchmarks/sbmpc_radar_view.py            # 8 episodes per problem

Prints one Markdown row per helmsman: success, compliant / scored encounters, and the
encounters that crossed ahead of a vessel they had to give way to.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.sbmpc import SBMPCHelmsman
from baselines.sbmpc_radar import SBMPCRadarHelmsman
from usvsim.evaluation.colreg import evaluate_colreg
from usvsim.evaluation.colreg_rollout import run_encounters
from usvsim.evaluation.colreg_suite import colreg_episodes, select_colreg_sets
from usvsim.task.observations import SCENE_FEATURES
from usvsim.task.radar import RadarConfig


@dataclass
class CutSBMPC:
    """``sb-mpc`` on the true scene without the obstacles outside a range and a sector."""

    range_m: float
    half_fov_rad: float
    observation: str = field(default="scene", init=False)
    action: str = field(default="gaussian", init=False)

    def __post_init__(self) -> None:
        self.inner = SBMPCHelmsman()

    def reset(self, n_boats: int) -> None:
        self.inner.reset(n_boats)

    def act(self, observation: NDArray[np.generic]) -> NDArray[np.float32]:
        obs = np.array(observation, dtype=np.float32, copy=True)
        slots = obs[:, 4:].reshape(obs.shape[0], -1, SCENE_FEATURES)
        unseen = (slots[..., 0] > self.range_m) | (np.abs(slots[..., 1]) > self.half_fov_rad)
        slots[unseen] = 0.0  # an empty slot: valid = 0
        obs[:, 4:] = slots.reshape(obs.shape[0], -1)
        return self.inner.act(obs)


def row(name: str, helmsman: Any, episodes: list[Any]) -> str:
    run = run_encounters(helmsman, episodes)
    result = evaluate_colreg(run.tracks)
    scored = result.scored
    passed = np.asarray(result.passed)[scored]
    ahead = np.nan_to_num(np.asarray(result.penalties["crossing_ahead"])) > 0  # (E, K)
    crossed = int(ahead[scored].sum())
    ok = sum(r.success for r in run.records)
    return (
        f"| {name} | {ok}/{len(episodes)} | {int(passed.sum())}/{passed.size} "
        f"({100 * passed.mean():.1f} %) | {crossed} |"
    )


def main(argv: list[str]) -> int:
    radar = RadarConfig()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=8, help="per Imazu problem")
    parser.add_argument("--range-m", type=float, default=radar.max_range_m)
    parser.add_argument("--half-fov-deg", type=float, default=math.degrees(radar.half_fov_rad))
    args = parser.parse_args(argv)
    sets = select_colreg_sets([f"imazu-{p:02d}" for p in range(1, 23)])
    episodes = [e for s in sets for e in colreg_episodes(s, args.episodes, "validation")]
    fov = math.radians(args.half_fov_deg)
    helmsmen = {
        "sb-mpc": SBMPCHelmsman(),
        "sb-mpc-radar": SBMPCRadarHelmsman(),
        f"sb-mpc, truth within {args.range_m:.0f} m and ±{args.half_fov_deg:.0f}°": CutSBMPC(
            args.range_m, fov
        ),
        f"sb-mpc, truth within {args.range_m:.0f} m": CutSBMPC(args.range_m, math.inf),
        f"sb-mpc, truth within ±{args.half_fov_deg:.0f}°": CutSBMPC(math.inf, fov),
    }
    print(f"Imazu 1-22, validation split, {args.episodes} episodes per problem\n")
    print("| helmsman | success | compliant encounters | crossed ahead (give-way) |")
    print("|---|---|---|---|")
    for name, helmsman in helmsmen.items():
        print(row(name, helmsman, episodes), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
