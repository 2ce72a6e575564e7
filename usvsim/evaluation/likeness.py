"""Expert-likeness: how much a helmsman moves like the expert on the same starts.

The reason to imitate is to get a policy that steers like the person it learned from; success
rate alone cannot show that. For each episode of a set (by default the 15 validation episodes),
the expert model (:mod:`baselines.expert`, the careful expert: no lapses) drives the same start
``n_samples`` times with different draws of its traits, and the helmsman's episode record is
compared with those paths:

=========================  =====================================================================
metric                     definition (lower is more expert-like unless stated)
=========================  =====================================================================
``path_distance_m``        symmetric mean closest-point distance between the helmsman's true
                           path and the nearest of the expert's paths on that start,
                           ½ (mean_p d(p, E) + mean_e d(e, P)), averaged over episodes (m);
                           symmetric, so a path cut short by a collision is far from the
                           expert's remaining path
``side_agreement``         share of expert samples that pass the pole on the helmsman's side
                           (starboard/port), averaged over episodes; HIGHER is more alike
``action_distance_deg``    1-Wasserstein distance between the distributions of 2 s heading
                           changes ψ(t + 2 s) − ψ(t) (the demonstrations' action definition,
                           true headings) of the helmsman and of the expert, pooled (deg)
=========================  =====================================================================

:func:`helmsman_likeness` is the call for ``usvsim bench`` (one helmsman, one episode set);
:func:`expert_reference` builds the expert side once and can be shared between helmsmen.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.stats import wasserstein_distance

from baselines.expert import ExpertParams, run_expert
from usvsim.common.angles import ssa
from usvsim.evaluation.episodes import EpisodeRecord, evaluate, validation_episodes
from usvsim.helm.protocol import Helmsman
from usvsim.task.batch import ActionKind
from usvsim.task.observations import ObservationKind
from usvsim.task.scenario import EpisodeSpec, Scenario

__all__ = [
    "ExpertReference",
    "Likeness",
    "chamfer_m",
    "expert_reference",
    "heading_changes",
    "helmsman_likeness",
    "likeness",
    "pass_side",
]

FloatArray = NDArray[np.float64]
REFERENCE_SEED = 20190035  # seeds the expert samples of the reference


@dataclass(frozen=True)
class Likeness:
    """Expert-likeness of one helmsman on one episode set (module table)."""

    path_distance_m: float
    side_agreement: float
    action_distance_deg: float
    n_episodes: int


@dataclass(frozen=True)
class ExpertReference:
    """Per episode: the expert's sample paths (list of (K, 3) [x_N, y_E, ψ]) and pass sides."""

    specs: tuple[EpisodeSpec, ...]
    paths: tuple[tuple[FloatArray, ...], ...]
    sides: tuple[FloatArray, ...]
    heading_changes_rad: FloatArray  # pooled 2 s heading changes of every sample


def pass_side(path: FloatArray, pole_ne: FloatArray) -> float:
    """+1 when the pole is passed on the boat's port side (it went round to starboard), -1 when
    on the starboard side, from the closest approach of ``path`` (K, 3) [x_N, y_E, ψ]."""
    d = path[:, :2] - pole_ne
    k = int(np.argmin(np.hypot(d[:, 0], d[:, 1])))
    to_pole = -d[k]
    cross = math.cos(path[k, 2]) * to_pole[1] - math.sin(path[k, 2]) * to_pole[0]
    return -1.0 if cross > 0 else 1.0


def heading_changes(path: FloatArray, steps_per_decision: int = 20) -> FloatArray:
    """ψ(t + 2 s) − ψ(t) (wrapped) along a path sampled every 0.1 s, from its start."""
    psi = path[::steps_per_decision, 2]
    return np.asarray(ssa(np.diff(psi)))


def expert_reference(
    specs: Sequence[EpisodeSpec] | None = None,
    *,
    n_samples: int = 8,
    seed: int = REFERENCE_SEED,
    scenario: Scenario | None = None,
    params: ExpertParams | None = None,
) -> ExpertReference:
    """The careful expert (``p_late_turn = 0``) ``n_samples`` times on every spec, one batch."""
    specs = tuple(specs if specs is not None else validation_episodes(scenario))
    params = dataclasses.replace(params or ExpertParams(), p_late_turn=0.0)
    runs = run_expert(
        [s for s in specs for _ in range(n_samples)], seed=seed, scenario=scenario, params=params
    )
    paths, sides, changes = [], [], []
    for i in range(len(specs)):
        mine = runs[i * n_samples : (i + 1) * n_samples]
        paths.append(tuple(r.trajectory[:, 1:4] for r in mine))
        sides.append(np.array([pass_side(r.trajectory[:, 1:4], r.pole_ne) for r in mine]))
        changes += [heading_changes(r.trajectory[:, 1:4]) for r in mine]
    return ExpertReference(specs, tuple(paths), tuple(sides), np.concatenate(changes))


def chamfer_m(a: FloatArray, b: FloatArray) -> float:
    """½ (mean_a d(a, B) + mean_b d(b, A)) for point sets (n, 2), (m, 2)."""
    da, _ = cKDTree(b).query(a)
    db, _ = cKDTree(a).query(b)
    return 0.5 * (float(np.mean(da)) + float(np.mean(db)))


def likeness(records: Sequence[EpisodeRecord], reference: ExpertReference) -> Likeness:
    """Compare ``records`` (one per reference episode, same order) with the expert."""
    if len(records) != len(reference.specs):
        raise ValueError(f"need {len(reference.specs)} records, got {len(records)}")
    dist, agree, changes = [], [], []
    for rec, paths, sides in zip(records, reference.paths, reference.sides, strict=True):
        path = rec.trajectory
        dist.append(min(chamfer_m(path[:, :2], e[:, :2]) for e in paths))
        agree.append(float(np.mean(sides == pass_side(path, rec.pole_ne))))
        changes.append(heading_changes(path))
    w = wasserstein_distance(
        np.degrees(np.concatenate(changes)), np.degrees(reference.heading_changes_rad)
    )
    return Likeness(float(np.mean(dist)), float(np.mean(agree)), float(w), len(records))


def helmsman_likeness(
    helmsman: Helmsman,
    *,
    observation: ObservationKind = "positional",
    action: ActionKind = "gaussian",
    reference: ExpertReference | None = None,
    **batch_kwargs: Any,
) -> Likeness:
    """Run ``helmsman`` on the reference's episodes (default: the validation set) and score it."""
    reference = reference or expert_reference()
    records = evaluate(
        helmsman, reference.specs, observation=observation, action=action, **batch_kwargs
    )
    return likeness(records, reference)
