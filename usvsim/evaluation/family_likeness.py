"""Expert-likeness on the open-water family: how much a helmsman moves like the family expert.

The family's counterpart of :mod:`usvsim.evaluation.likeness`. The family expert
(:mod:`baselines.family_expert`: the ``vo`` judgement with a human hand) drives each episode of
a set ``n_samples`` times with different traits; a helmsman's record on the same episode is
compared with those paths by the same three metrics:

=========================  =====================================================================
metric                     definition (lower is more expert-like unless stated)
=========================  =====================================================================
``path_distance_m``        symmetric mean closest-point distance to the nearest expert path on
                           that episode, averaged over episodes (m)
``side_agreement``         share of expert samples that pass the episode's *key obstacle* on the
                           helmsman's side, averaged over episodes; HIGHER is more alike. The key
                           obstacle is the disc (static or moving, where it is at each instant)
                           that the first expert sample passes closest
``action_distance_deg``    1-Wasserstein distance between the pooled 2 s heading changes of the
                           helmsman and of the expert (deg)
=========================  =====================================================================

:data:`FAMILY_HELD_OUT_SEED` draws the held-out set: family episodes that neither training nor
checkpoint selection (:func:`learning.experiments.validation.family_validation_episodes`) nor the
demonstrations ever saw.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import wasserstein_distance

from baselines.family_expert import FamilyExpertParams, run_family_expert
from usvsim.common.splits import check_test_draw
from usvsim.evaluation.likeness import Likeness, chamfer_m, heading_changes, pass_side
from usvsim.evaluation.openwater import OpenWaterRecord
from usvsim.task.openwater import OpenWaterEpisode, vessel_motion
from usvsim.task.openwater_env import OPEN_WATER_FAMILY, draw_family

__all__ = [
    "FAMILY_HELD_OUT_SEED",
    "FamilyReference",
    "disc_track",
    "family_held_out_episodes",
    "family_likeness",
    "family_reference",
]

FloatArray = NDArray[np.float64]
FAMILY_HELD_OUT_SEED = zlib.crc32(b"family-held-out")  # as the stress sets' seeds
FAMILY_REFERENCE_SEED = 20261203  # seeds the expert samples of a reference
STEP_S = 0.1  # s, the plant step of the paths compared


def family_held_out_episodes(n: int = 100) -> tuple[OpenWaterEpisode, ...]:
    """The held-out family set: ``n`` episodes of the training family from their own seed (a
    test split, refused inside :func:`usvsim.common.splits.selection_mode`)."""
    check_test_draw("family held-out")
    return draw_family(OPEN_WATER_FAMILY, FAMILY_HELD_OUT_SEED, n)


def disc_track(episode: OpenWaterEpisode, j: int, t_s: NDArray[np.floating]) -> FloatArray:
    """Centre (K, 2) m of disc ``j`` (statics first, then vessels) at episode times ``t_s``."""
    n_static = len(episode.obstacles)
    if j < n_static:
        return np.broadcast_to(np.asarray(episode.obstacles[j][:2], dtype=float), (t_s.size, 2))
    v = episode.vessels[j - n_static]
    pos, _ = vessel_motion(
        np.array([v.x0_n, v.y0_e]), np.array(v.course_rad), np.array(v.speed_mps),
        np.array(v.turn_rate_radps), np.asarray(t_s, dtype=float)[:, None],
    )  # fmt: skip
    return pos.reshape(-1, 2)


def _key_disc(episode: OpenWaterEpisode, path: FloatArray) -> int:
    """The disc that ``path`` (K, 3), sampled every 0.1 s from t = 0, passes closest (edge)."""
    t: FloatArray = np.arange(path.shape[0], dtype=np.float64) * STEP_S
    radii = [o[2] for o in episode.obstacles] + [v.radius_m for v in episode.vessels]
    edge = [
        np.min(np.hypot(*(path[:, :2] - disc_track(episode, j, t)).T)) - r
        for j, r in enumerate(radii)
    ]
    return int(np.argmin(edge)) if edge else -1


def _side(episode: OpenWaterEpisode, j: int, path: FloatArray) -> float:
    """Pass side of disc ``j`` (:func:`usvsim.evaluation.likeness.pass_side`, the disc where it
    is at each instant); 0 for an episode without discs."""
    if j < 0:
        return 0.0
    t: FloatArray = np.arange(path.shape[0], dtype=np.float64) * STEP_S
    return pass_side(path, disc_track(episode, j, t))


@dataclass(frozen=True)
class FamilyReference:
    """Per episode: the expert's sample paths (K, 3) [x_N, y_E, ψ] every 0.1 s, the key disc
    and the samples' pass sides; the pooled 2 s heading changes of every sample."""

    episodes: tuple[OpenWaterEpisode, ...]
    paths: tuple[tuple[FloatArray, ...], ...]
    key_disc: tuple[int, ...]
    sides: tuple[FloatArray, ...]
    heading_changes_rad: FloatArray


def family_reference(
    episodes: Sequence[OpenWaterEpisode] | None = None,
    *,
    n_samples: int = 4,
    seed: int = FAMILY_REFERENCE_SEED,
    params: FamilyExpertParams | None = None,
) -> FamilyReference:
    """The family expert ``n_samples`` times on every episode (default the held-out set), in
    one batch."""
    episodes = tuple(episodes if episodes is not None else family_held_out_episodes())
    runs = run_family_expert(
        [e for e in episodes for _ in range(n_samples)], seed=seed, params=params
    )
    paths, keys, sides, changes = [], [], [], []
    for i, e in enumerate(episodes):
        mine = [r.trajectory[:, 1:4] for r in runs[i * n_samples : (i + 1) * n_samples]]
        key = _key_disc(e, mine[0])
        paths.append(tuple(mine))
        keys.append(key)
        sides.append(np.array([_side(e, key, p) for p in mine]))
        changes += [heading_changes(p) for p in mine]
    return FamilyReference(
        episodes, tuple(paths), tuple(keys), tuple(sides), np.concatenate(changes)
    )


def family_likeness(records: Sequence[OpenWaterRecord], reference: FamilyReference) -> Likeness:
    """Compare ``records`` (one per reference episode, same order) with the family expert."""
    if len(records) != len(reference.episodes):
        raise ValueError(f"need {len(reference.episodes)} records, got {len(records)}")
    dist, agree, changes = [], [], []
    for rec, e, paths, key, sides in zip(
        records, reference.episodes, reference.paths, reference.key_disc, reference.sides,
        strict=True,
    ):  # fmt: skip
        path = rec.trajectory
        dist.append(min(chamfer_m(path[:, :2], p[:, :2]) for p in paths))
        agree.append(float(np.mean(sides == _side(e, key, path))))
        changes.append(heading_changes(path))
    w = wasserstein_distance(
        np.degrees(np.concatenate(changes)), np.degrees(reference.heading_changes_rad)
    )
    return Likeness(float(np.mean(dist)), float(np.mean(agree)), float(w), len(records))
