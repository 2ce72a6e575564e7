"""vo-radar: vo fed by the radar tracker."""

from __future__ import annotations

import numpy as np

from baselines.vo_radar import VORadarHelmsman, targets_to_scene
from usvsim.evaluation.stress import STRESS_SETS, evaluate_set, stress_episodes
from usvsim.nav.tracker import TrackTargets
from usvsim.task.openwater_batch import OpenWaterBatch

SETS = {s.name: s for s in STRESS_SETS}


def test_perfect_tracks_give_vo_the_true_scene() -> None:
    """The conversion is exact: the true discs as tracks (certain, velocities significant where
    they move) make the same scene observation as the simulator's own."""
    episodes = list(stress_episodes(SETS["moving-vessels"], 6)) + list(
        stress_episodes(SETS["several-obstacles"], 6)
    )
    n = len(episodes)
    sim = OpenWaterBatch(n, observation="radar+nav")
    obs = sim.reset(None, episodes)
    for _ in range(3):
        obs = sim.step(np.zeros((n, 1), dtype=np.float32)).observation
    truth = sim.observe("scene")
    centres, radii, velocity, ok = sim.scene_at(np.full(n, 6.0))
    cov = np.broadcast_to(np.eye(4) * 1e-6, (*ok.shape, 4, 4))
    targets = TrackTargets(ok, centres, velocity, radii, cov, np.zeros(ok.shape, dtype=np.int64))
    scene = targets_to_scene(targets, obs["nav"], obs["goal"], 9.21)
    # float32 nav and goal: agreement to float32 rounding of positions ~1e3 m
    np.testing.assert_allclose(scene, truth, rtol=0, atol=2e-3)


def test_vo_radar_reads_only_the_radar_and_avoids_like_vo() -> None:
    helm = VORadarHelmsman()
    assert (helm.observation, helm.action) == ("radar+nav", "gaussian")
    records = evaluate_set(
        helm, SETS["several-obstacles"], stress_episodes(SETS["several-obstacles"], 20)
    )
    # vo: 20/20 on these episodes; measured vo-radar 20/20 (29/30 on 30)
    assert sum(r.success for r in records) >= 18
    assert not any(r.collision for r in records)


def test_stress_table_labels_each_column_by_what_it_perceives() -> None:
    from usvsim.evaluation.stress import run_stress, select_sets, stress_markdown
    from usvsim.helm.registry import select_helmsmen

    result = run_stress(select_helmsmen(["vo", "vo-radar"]), select_sets(["study"]), 2, False)
    assert "| set | vo [true scene] | vo-radar [radar tracks] |" in stress_markdown(result)
