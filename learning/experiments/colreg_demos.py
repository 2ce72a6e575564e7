"""Demonstrations from a COLREG-compliant expert, recorded as ``usvsim-demo/2`` files (issue 41).

The SB-MPC expert (:mod:`baselines.sbmpc_expert`: ``sb-mpc``'s judgement with the family
expert's reaction delay, perception noise, caution, wobble and hand) drives
:data:`COLREG_DEMO_RUNS` encounter episodes of the COLREG members of the open-water family
(:func:`colreg_demo_family`: Imazu-like and trafficgen-like traffic), drawn from a seed namespace
of their own (:data:`COLREG_DEMO_SEED`), never an episode of the COLREG suite's Imazu or
trafficgen sets in either split (tested). Each run is logged by the same recorder as the family
demonstrations (:func:`learning.imitation.family_demos.record_runs`), so the files load with the
same loader, pass the same quality filter and turn into (observation, action) pairs by the same
preprocessing; they ship gzipped in ``usvsim/demos/colreg``.

:func:`score_runs` scores the expert's runs with the project's COLREG scorer
(:func:`usvsim.evaluation.colreg.evaluate_colreg`, rules 13-17 per encounter; the target vessels
as they were drawn, holding course and speed) and the task's success. Only the runs that
succeeded and passed every scored encounter are shipped (:func:`record_colreg_demonstrations`,
``compliant_only``): an expert's lapse is not a behaviour to imitate. File ``demo_NNN`` is
episode NNN of the draw, so the gaps in the numbering are the runs left out.

``python -m learning.experiments.colreg_demos FOLDER`` writes them and prints the expert's figures
on every episode drawn (the shipped set is ``usvsim/demos/colreg``; the command and its figures
are in that folder's README).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from baselines.family_expert import FamilyExpertParams, FamilyExpertRun
from baselines.sbmpc import SBMPCConfig
from baselines.sbmpc_expert import run_sbmpc_expert
from learning.imitation.demonstrations import (
    RecorderParams,
    Recording,
    demo_folder,
    write_demo_set,
)
from learning.imitation.family_demos import record_runs
from usvsim.task.colreg_family import COLREG_FAMILY
from usvsim.task.openwater import OpenWaterEpisode, OpenWaterScenario
from usvsim.task.openwater_env import ScenarioMixture, draw_family

__all__ = [
    "COLREG_DEMOS_DIR",
    "COLREG_DEMO_RUNS",
    "COLREG_DEMO_SEED",
    "ColregDemoSet",
    "RunScore",
    "colreg_demo_episodes",
    "colreg_demo_family",
    "record_colreg_demonstrations",
    "score_runs",
]

# seeds the runs (episodes, expert, sensors); the episodes' own seed, spawned from it, is
# checked against every COLREG suite seed (tests/learning/experiments/test_colreg_demos.py)
COLREG_DEMO_SEED = 20261241
COLREG_DEMO_RUNS = 400  # runs drawn and driven; the compliant ones are kept (README figures)
COLREG_DEMOS_DIR = Path(str(resources.files("usvsim"))) / "demos" / "colreg"


def colreg_demo_family() -> ScenarioMixture:
    """The encounters the expert is recorded in: :data:`usvsim.task.colreg_family.COLREG_FAMILY`
    (Imazu-like and trafficgen-like traffic, the open-water family's disturbances)."""
    return COLREG_FAMILY


def colreg_demo_episodes(
    n_runs: int = COLREG_DEMO_RUNS,
    *,
    seed: int = COLREG_DEMO_SEED,
    family: ScenarioMixture | OpenWaterScenario | None = None,
) -> tuple[int, tuple[OpenWaterEpisode, ...]]:
    """The episode seed spawned from ``seed`` and the ``n_runs`` episodes drawn with it
    (:func:`usvsim.task.openwater_env.draw_family`, episode k from ``default_rng([s, k])``)."""
    episode_seed = int(np.random.SeedSequence(seed).spawn(3)[0].generate_state(1)[0])
    fam = colreg_demo_family() if family is None else family
    return episode_seed, draw_family(fam, episode_seed, n_runs)


@dataclass(frozen=True)
class RunScore:
    """Success and COLREG compliance of a set of runs: ``success`` and ``collision`` (E,) bool;
    ``summary`` the scorer's :class:`usvsim.evaluation.colreg.ColregSummary`; ``passed`` (E,)
    bool, every scored encounter of a run passed (True without one)."""

    success: NDArray[np.bool_]
    collision: NDArray[np.bool_]
    passed: NDArray[np.bool_]
    summary: Any

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready figures: success and collision rates, and the scorer's summary."""
        return {
            "runs": int(self.success.size),
            "success_rate": float(self.success.mean()) if self.success.size else math.nan,
            "collisions": int(self.collision.sum()),
            **self.summary.to_dict(),
        }


@dataclass(frozen=True)
class _Track:
    """What :func:`usvsim.evaluation.colreg_rollout.encounter_tracks` reads of a record."""

    episode: OpenWaterEpisode
    trajectory: NDArray[np.float64]  # (K, 3) true [x_N, y_E, ψ] every 0.1 s


def score_runs(runs: Sequence[FamilyExpertRun], sample_s: float = 1.0) -> RunScore:
    """Score expert runs with the COLREG scorer (module docstring) and the task's success."""
    from usvsim.evaluation.colreg import evaluate_colreg, summarize_colreg
    from usvsim.evaluation.colreg_rollout import encounter_tracks

    records = [_Track(r.episode, r.trajectory[:, 1:4]) for r in runs]
    result = evaluate_colreg(encounter_tracks(records, sample_s))
    return RunScore(
        success=np.array([r.success for r in runs], dtype=bool),
        collision=np.array([r.collision for r in runs], dtype=bool),
        passed=np.asarray(result.episode_passed, dtype=bool),
        summary=summarize_colreg(result),
    )


@dataclass(frozen=True)
class ColregDemoSet:
    """A recording session: every run of the expert (``runs``, one per episode drawn), their
    score (:func:`score_runs`), and the ``recordings`` kept (``kept`` (E,) bool; each keeps its
    run's index as ``run``, so file ``demo_NNN`` is episode NNN of the draw)."""

    recordings: list[Recording]
    runs: list[FamilyExpertRun]
    score: RunScore
    kept: NDArray[np.bool_]


def record_colreg_demonstrations(
    n_runs: int = COLREG_DEMO_RUNS,
    *,
    seed: int = COLREG_DEMO_SEED,
    family: ScenarioMixture | OpenWaterScenario | None = None,
    compliant_only: bool = True,
    expert: FamilyExpertParams | None = None,
    sbmpc: SBMPCConfig | None = None,
    recorder: RecorderParams | None = None,
) -> ColregDemoSet:
    """Drive ``n_runs`` encounter episodes of ``family`` (None: :func:`colreg_demo_family`)
    with the SB-MPC expert and log them (module docstring).

    ``compliant_only``: keep only the runs that reached the goal safely (the task's success)
    and passed every encounter the COLREG scorer found (:func:`score_runs`; a run without one
    is kept when it succeeded): the demonstrations show seamanship, not the expert's lapses.
    The scorer reads the true tracks, which the expert's log never holds, so this is a choice of
    which runs to ship, made before the files exist (the loader's quality filter still judges
    each file by its recorded data).

    Deterministic in ``seed``: the episodes, the expert's traits and the sensor noise each come
    from their own stream spawned from it (as the family demonstrations); every run is logged,
    so the kept files are the same whichever runs are dropped.
    """
    _, expert_seq, sensor_seq = np.random.SeedSequence(seed).spawn(3)
    _, episodes = colreg_demo_episodes(n_runs, seed=seed, family=family)
    runs = run_sbmpc_expert(
        episodes, seed=int(expert_seq.generate_state(1)[0]), params=expert, config=sbmpc
    )
    rng = np.random.default_rng(sensor_seq)
    recordings = record_runs(runs, rng, recorder or RecorderParams())
    score = score_runs(runs)
    kept = score.success & score.passed if compliant_only else np.ones(len(runs), dtype=bool)
    return ColregDemoSet([r for r, k in zip(recordings, kept, strict=True) if k], runs, score, kept)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m learning.experiments.colreg_demos FOLDER``: record the runs into FOLDER.

    Exit status 2 with a one-line message when FOLDER is missing or cannot be written; the
    files are written as one set (a kill leaves the previous set, never a mix of two). Prints
    the expert's success and COLREG compliance on the recorded episodes.
    """
    folder = demo_folder(
        argv,
        "learning.experiments.colreg_demos",
        f"records the {COLREG_DEMO_RUNS} SB-MPC expert runs into FOLDER/demo_NNN.csv.gz",
    )
    if folder is None:
        return 2
    demo = record_colreg_demonstrations()
    write_demo_set(demo.recordings, folder, compress=True)
    figures = demo.score.to_dict()
    print(
        f"expert on all {figures['runs']} episodes: success {figures['success_rate']:.3f}, "
        f"collisions {figures['collisions']}, COLREG compliance "
        f"{figures['compliance_rate']:.3f} of {figures['encounters']} encounters; "
        f"{int(demo.kept.sum())} runs kept (success and every encounter passed)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
