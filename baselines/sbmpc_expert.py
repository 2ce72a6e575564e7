"""A COLREG-compliant human-like expert: ``sb-mpc``'s judgement with the family expert's eyes
and hand.

The family expert (:mod:`baselines.family_expert`) steers by ``vo``'s course, which keeps clear
of traffic but only weakly keeps the rules of the road. For demonstrations in COLREG encounters
(issue 41, "demonstrations from a compliant expert") this expert takes its course from the
project's SB-MPC (:mod:`baselines.sbmpc`; Johansen, Perez & Cristofaro 2016, with the departures
chosen on the Imazu validation split), and keeps everything human of the family expert
unchanged (:func:`baselines.family_expert.run_family_expert`):

=======================  =====================================================================
what                     model
=======================  =====================================================================
what the helmsman sees   the TRUE scene as it was ``reaction_delay_s`` ago (0.4-1.0 s, drawn per
                         run), bearings with 1.5° (1σ) noise (:class:`baselines.expert.
                         ExpertParams`)
caution                  ``caution_m`` (0-8 m, drawn per run) added to every obstacle's radius
                         as SB-MPC judges it: its D_safe and D_close are measured from a hull
                         that much wider, so it alters earlier and passes wider
decision                 SB-MPC's cheapest course offset χ_ca (:func:`baselines.sbmpc.
                         sbmpc_offsets`) from the perceived ``scene`` observation every
                         :attr:`SBMPCJudgement.decide_every_ticks` ticks (2 s: ``sb-mpc``'s own
                         decision period in the bench), held in between; the course to steer
                         each 0.2 s tick is the perceived goal bearing plus that offset. The
                         first decision waits until the helmsman has seen the boat move (its
                         velocity over ground is judged from the last tick's motion; before
                         that it steers for the goal): decided at rest, SB-MPC predicted the
                         own ship standing still and held a port turn into head-on meetings
                         for 2 s (the expert without its human imperfections on 64 training
                         episodes: 10 of 32 head-on encounters failed, 9 of them by that
                         turn; waiting: 1 of 31; the ``sb-mpc`` helmsman, fed the filter's
                         velocity: 1 of 32)
hand                     the family expert's: the heading to steer is ψ + ssa(θ* − β) plus an
                         Ornstein-Uhlenbeck wobble (2°, 4 s), swung at most 11°/s
=======================  =====================================================================

The expert sees the truth (as ``sb-mpc``, not ``sb-mpc-radar``): a person on the bridge looks at
the water, and what a learner is to copy is the seamanship, not a tracker's errors.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from baselines.family_expert import FamilyExpertParams, FamilyExpertRun, run_family_expert
from baselines.sbmpc import SBMPCConfig, sbmpc_offsets
from usvsim.common.angles import ssa
from usvsim.task.observations import SCENE_FEATURES
from usvsim.task.openwater import OpenWaterEpisode

__all__ = ["SBMPCJudgement", "run_sbmpc_expert"]

FloatArray = NDArray[np.float64]


@dataclass
class SBMPCJudgement:
    """SB-MPC's course choice for :func:`baselines.family_expert.run_family_expert` (module
    table): a new course offset every ``decide_every_ticks`` ticks, the caution on the radii."""

    config: SBMPCConfig = field(default_factory=SBMPCConfig)
    # ticks (0.2 s each) between decisions: 10 = 2 s, the task's decision period at which the
    # ``sb-mpc`` helmsman decides in the bench (its validation-split tuning was made at it)
    decide_every_ticks: int = 10

    def __post_init__(self) -> None:
        if self.decide_every_ticks < 1:
            raise ValueError(
                f"SBMPCJudgement.decide_every_ticks must be >= 1, got {self.decide_every_ticks}"
            )

    # m/s, a perceived speed over ground below this is "not seen moving yet" (vo's threshold for
    # a velocity, baselines.velocity_obstacle.VOConfig.moving_speed_mps)
    min_speed_mps: float = 0.3

    def reset(self, n_boats: int) -> None:
        self.offset_rad = np.full(n_boats, np.nan)  # χ_ca held since the last decision (rad)

    def course(self, observation: FloatArray, caution_m: FloatArray, tick: int) -> FloatArray:
        """Course over ground (N,) rad relative to the heading: the perceived goal bearing plus
        the held offset, decided anew every ``decide_every_ticks`` ticks (a boat's first
        decision as soon as it is seen moving; until then the goal's bearing)."""
        obs = np.asarray(observation, dtype=np.float64)
        moving = np.hypot(obs[:, 2], obs[:, 3]) > self.min_speed_mps
        # every boat on one 2 s grid (one batched call per decision), a boat's first decision
        # as soon as it is seen moving (the first few ticks only)
        due = np.isnan(self.offset_rad) | (tick % self.decide_every_ticks == 0)
        rows = np.flatnonzero(due & moving)
        if rows.size:
            seen = obs[rows].copy()
            slots = seen[:, 4:].reshape(rows.size, -1, SCENE_FEATURES)
            slots[..., 2] += caution_m[rows, None] * slots[..., 5]  # wider hulls, valid slots
            self.offset_rad[rows], _ = sbmpc_offsets(self.config, seen, self.offset_rad[rows])
        return np.asarray(ssa(obs[:, 1] + np.nan_to_num(self.offset_rad)))


def run_sbmpc_expert(
    episodes: Sequence[OpenWaterEpisode],
    *,
    seed: int,
    params: FamilyExpertParams | None = None,
    config: SBMPCConfig | None = None,
) -> list[FamilyExpertRun]:
    """Run the SB-MPC expert on every episode in one batch (module docstring); traits, noise and
    wobble from ``seed`` exactly as :func:`baselines.family_expert.run_family_expert` draws
    them (the same seed gives the same traits as the family expert's run)."""
    judgement = SBMPCJudgement(config or SBMPCConfig())
    return run_family_expert(episodes, seed=seed, params=params, judgement=judgement)
