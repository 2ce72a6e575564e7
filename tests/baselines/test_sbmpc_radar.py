"""sb-mpc-radar: sb-mpc fed by the radar tracker (the perception of vo-radar)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from baselines.sbmpc import SBMPCHelmsman
from baselines.sbmpc_radar import SBMPCRadarHelmsman
from usvsim.common.angles import ssa
from usvsim.evaluation.colreg import evaluate_colreg
from usvsim.evaluation.colreg_rollout import EncounterRun, run_encounters
from usvsim.evaluation.imazu import imazu_episodes
from usvsim.task.openwater import RadarQuality

# the stress suite's radar-noise set (usvsim.evaluation.stress): speckle 50 %, noise 40,
# 20 % missed returns, plus radar-clutter's 0.1 % false pixels
NOISY = RadarQuality(clutter_probability=0.001, speckle=0.5, missed_probability=0.2,
                     noise_amplitude=40.0)  # fmt: skip


@pytest.fixture(scope="module")
def head_on() -> list:
    """Imazu problem 1 (head-on), 10 perturbed validation episodes, clean radar."""
    episodes = list(imazu_episodes(1, 10, "validation"))
    assert all(e.radar.clean for e in episodes)
    return episodes


def _side_and_cpa(run: EncounterRun) -> tuple[np.ndarray, np.ndarray]:
    """Per episode: the side the (single) target is passed on at the closest approach (+1
    starboard, −1 port, relative to the own course over ground) and that range (m)."""
    tr = run.tracks
    d = tr.target_north_east_m[:, 0] - tr.own_north_east_m
    dist = np.where(tr.valid, np.hypot(d[..., 0], d[..., 1]), np.inf)
    i = np.argmin(dist, axis=1)
    e = np.arange(i.size)
    bearing = ssa(np.arctan2(d[e, i, 1], d[e, i, 0]) - tr.own_course_rad[e, i])
    return np.sign(bearing), dist[e, i]


def _compliant(run: EncounterRun) -> int:
    result = evaluate_colreg(run.tracks)
    return int(np.asarray(result.passed)[result.scored].sum())


def test_reads_only_the_radar_and_declares_it() -> None:
    helm = SBMPCRadarHelmsman()
    assert (helm.observation, helm.action) == ("radar+nav", "gaussian")
    assert helm.config == SBMPCHelmsman().config  # one SB-MPC, the same parameters


def test_clean_radar_head_on_passes_like_sb_mpc(head_on: list) -> None:
    """On a clean radar the tracks stand in for the truth: in every head-on episode
    sb-mpc-radar passes the target on the same side as sb-mpc (port to port, rule 14) at a
    closest approach within 6 m of sb-mpc's (measured: 38.8-44.6 m against 39.9-43.1 m, at most
    4.6 m apart; the radar sees the target from 200 m, the truth from the start)."""
    truth = run_encounters(SBMPCHelmsman(), head_on)
    radar = run_encounters(SBMPCRadarHelmsman(), head_on)
    side_t, cpa_t = _side_and_cpa(truth)
    side_r, cpa_r = _side_and_cpa(radar)
    assert (side_t == -1).all() and (side_r == -1).all()
    assert np.abs(cpa_r - cpa_t).max() < 6.0, (cpa_t, cpa_r)
    assert all(r.success for r in radar.records)
    # measured compliance: sb-mpc 10/10, sb-mpc-radar 8/10 (two late starboard turns)
    assert _compliant(radar) >= 7 and _compliant(truth) >= 9


def test_noisy_radar_changes_the_manoeuvre_but_keeps_the_boat_safe(head_on: list) -> None:
    """With speckle, noise, missed returns and clutter the tracks lag and jitter: the boat
    still reaches every goal without a collision (measured 10/10), but its manoeuvres differ
    from the clean-radar ones and fewer head-on meetings are kept to the rules (measured 1/10
    against 8/10 compliant; one passed starboard to starboard)."""
    clean = run_encounters(SBMPCRadarHelmsman(), head_on)
    noisy = run_encounters(SBMPCRadarHelmsman(), [replace(e, radar=NOISY) for e in head_on])
    assert sum(r.success for r in noisy.records) >= 9
    assert not any(r.collision for r in noisy.records)
    _, cpa_clean = _side_and_cpa(clean)
    _, cpa_noisy = _side_and_cpa(noisy)
    assert np.abs(cpa_noisy - cpa_clean).max() > 5.0
    assert _compliant(noisy) < _compliant(clean)


def test_same_radar_seed_same_run_another_seed_another(head_on: list) -> None:
    episodes = [replace(e, radar=NOISY) for e in head_on[:4]]
    a = run_encounters(SBMPCRadarHelmsman(), episodes).tracks
    b = run_encounters(SBMPCRadarHelmsman(), episodes).tracks
    np.testing.assert_array_equal(a.own_north_east_m, b.own_north_east_m)
    reseeded = [replace(e, radar_seed=e.radar_seed + 1) for e in episodes]
    c = run_encounters(SBMPCRadarHelmsman(), reseeded).tracks
    assert not np.array_equal(a.own_north_east_m, c.own_north_east_m)


def test_registry_and_table_labels() -> None:
    from usvsim.evaluation.colreg_suite import traffic_fitness
    from usvsim.evaluation.model_cards import default_helmsmen
    from usvsim.evaluation.stress import run_stress, select_sets, stress_markdown
    from usvsim.helm.registry import make_helmsman, select_helmsmen

    assert isinstance(make_helmsman("sb-mpc-radar"), SBMPCRadarHelmsman)
    default = default_helmsmen()
    assert default.index("sb-mpc-radar") == default.index("vo-radar") + 1
    fit = traffic_fitness("sb-mpc-radar", "radar+nav", {})
    assert (fit.perceives, fit.trained_for, fit.meets_traffic) == ("radar tracks", "baseline", True)
    result = run_stress(
        select_helmsmen(["sb-mpc", "sb-mpc-radar"]), select_sets(["study"]), 2, False
    )
    assert "| set | sb-mpc [true scene] | sb-mpc-radar [radar tracks] |" in stress_markdown(result)
