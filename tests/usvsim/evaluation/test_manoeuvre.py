"""Manoeuvring trials: the issue-12 bars on usv105 at 3 m/s, and the trial definitions."""

from __future__ import annotations

import dataclasses
import math

import pytest

from usvsim.common.errors import UserError
from usvsim.evaluation.manoeuvre import (
    helm_command,
    run_trials,
    stopping_trial,
    trials_summary,
    trials_table,
    turning_circle,
    zigzag,
)
from usvsim.vessel.vessels import CYBERSHIP2, LOE_DEFAULT, USV105

L = USV105.length_m


@pytest.fixture(scope="module")
def usv105_trials():
    return run_trials(USV105, 3.0)


def test_turning_circle_at_max_helm_is_a_boat(usv105_trials):
    t = usv105_trials.turning
    assert 1.5 <= t.tactical_diameter_m / L <= 5.0  # 2.78 L
    assert t.steady_radius_m / L >= 1.0  # 1.11 L
    assert 5.0 <= t.drift_angle_deg <= 30.0  # 22° bow-in
    assert t.min_surge_mps > 0.0  # 1.76 m/s: never goes backwards
    assert 0.4 <= t.speed_ratio <= 0.95  # 0.63
    assert t.advance_m / L <= 4.5  # IMO; 2.61 L


def test_turning_radius_in_lengths_barely_changes_between_2_and_5_m_s():
    slow, fast = turning_circle(USV105, (2.0, 5.0))
    ratio = max(slow.steady_radius_m, fast.steady_radius_m) / min(
        slow.steady_radius_m, fast.steady_radius_m
    )
    assert ratio < 2.0  # 1.07 L at 2 m/s, 1.15 L at 5 m/s: ratio 1.07


def test_zigzag_10_10_overshoots(usv105_trials):
    z = usv105_trials.zigzag10
    assert z.first_overshoot_deg < 10.0  # 5.6°
    assert z.second_overshoot_deg < 25.0  # 8.6°
    assert z.initial_turning_m / L <= 2.5  # IMO initial turning; 1.28 L
    assert usv105_trials.zigzag20.first_overshoot_deg < 25.0  # 8.9°


def test_zigzag_executes_when_the_heading_reaches_the_switch_angle():
    z = zigzag(USV105, 3.0, 10.0)
    k = round(z.time_to_second_execute_s / 0.1)
    assert z.heading_deg[k] >= 10.0 > z.heading_deg[k - 1]
    assert z.helm_deg_t[k - 1] == 10.0 and z.helm_deg_t[k] == -10.0


def test_stopping_with_and_without_astern():
    with_bucket = stopping_trial(USV105, 3.0)
    assert with_bucket.astern and with_bucket.surge_mps[-1] <= 0.0
    assert with_bucket.track_reach_m / L <= 15.0  # 0.41 L
    no_bucket = stopping_trial(
        dataclasses.replace(USV105, actuation=dataclasses.replace(USV105.actuation, a1_min=0.0)),
        3.0,
    )
    assert not no_bucket.astern
    assert no_bucket.track_reach_m > with_bucket.track_reach_m


def test_the_old_default_hull_fails_the_realism_bars():
    # the reason for usv105: the Loe hull pirouettes (hull audit: 0.06 L, β -104°, backwards)
    t = turning_circle(LOE_DEFAULT, (3.0,))[0]
    assert t.steady_radius_m / LOE_DEFAULT.length_m < 0.1
    assert t.min_surge_mps < 0.0


def test_helm_of_a_stern_force_actuator_turns_to_starboard():
    a2 = helm_command(CYBERSHIP2.actuation, 10.0)
    assert a2 == pytest.approx(-CYBERSHIP2.actuation.a2_max / 3)  # force aft: push to port
    assert helm_command(USV105.actuation, 10.0) == pytest.approx(math.radians(10.0))


def test_table_has_the_imo_column_and_summary_names_the_figures(usv105_trials):
    table = trials_table([usv105_trials])
    assert "IMO MSC.137(76)" in table.splitlines()[0]
    assert "| tactical diameter (L) | 2.78 | ≤ 5 |" in table
    assert "tactical diameter 2.78 L" in trials_summary(usv105_trials)


def test_manoeuvre_command_writes_table_and_plots(tmp_path, capsys):
    from usvsim.cli.main import main

    assert main(["manoeuvre", "--vessel", "usv105", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "manoeuvre.md").read_text().startswith("| trial | usv105 3 m/s |")
    assert (tmp_path / "manoeuvre_usv105.png").stat().st_size > 10_000
    assert "tactical diameter" in capsys.readouterr().out


def test_manoeuvre_command_rejects_an_unknown_vessel():
    from usvsim.cli.plant import ManoeuvreArgs

    with pytest.raises(
        UserError, match="--vessel must be one of all, default, cybership2, loe-default"
    ):
        ManoeuvreArgs(vessel="titanic").check()
