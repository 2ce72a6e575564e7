"""Manoeuvring trials in wind and waves (issue 38): calm weather changes nothing, beam wind moves
the turning circle downwind, waves leave the zig-zags finite, same seed same trial, bad options
are one line."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from usvsim.common.errors import UserError
from usvsim.evaluation.manoeuvre import (
    TrialWeather,
    run_trials,
    trials_table,
    turning_circle,
    zigzag,
)
from usvsim.vessel.vessels import USV105


def test_calm_weather_gives_todays_trials_exactly() -> None:
    calm, today = run_trials(USV105, 3.0, TrialWeather()), run_trials(USV105, 3.0)
    assert calm.weather is None and calm.nozzle_filtered is None
    for field in ("turning", "zigzag10", "zigzag20", "stopping"):
        a, b = getattr(calm, field), getattr(today, field)
        for f in dataclasses.fields(a):
            x, y = getattr(a, f.name), getattr(b, f.name)
            if isinstance(x, np.ndarray):
                assert np.array_equal(x, y)
            elif not (isinstance(x, float) and math.isnan(x) and math.isnan(y)):
                assert x == y, f.name


def test_beam_wind_moves_the_turning_circle_downwind() -> None:
    """10 m/s from the east (starboard beam of the approach): the circle's centre drifts west at
    0.20 m/s (measured), towards 294°; asserted: 0.1-0.5 m/s, within 45° of downwind (270°)."""
    circle = turning_circle(USV105, (3.0,), weather=TrialWeather(10.0, 90.0, 0))[0]
    assert 0.1 <= circle.drift_mps <= 0.5
    assert abs(circle.drift_towards_deg - 270.0) <= 45.0
    calm = turning_circle(USV105, (3.0,))[0]
    assert math.isnan(calm.drift_mps)


def test_zigzags_in_sea_state_4_are_finite_and_repeatable() -> None:
    weather = TrialWeather(0.0, 90.0, 4, seed=2)
    first, again = (zigzag(USV105, 3.0, 10.0, weather=weather) for _ in range(2))
    assert np.array_equal(first.heading_deg, again.heading_deg)
    assert 0.0 < first.first_overshoot_deg < 15.0
    assert 0.0 < first.second_overshoot_deg < 25.0
    other = zigzag(USV105, 3.0, 10.0, weather=dataclasses.replace(weather, seed=3))
    assert not np.array_equal(first.heading_deg, other.heading_deg)


def test_table_reports_drift_and_nozzle_activity_in_waves() -> None:
    report = run_trials(USV105, 3.0, TrialWeather(10.0, 90.0, 3))
    table = trials_table([report])
    assert "wind 10 m/s from 90°, sea state 3" in table.splitlines()[0]
    assert "circle drift (m/s)" in table
    assert report.nozzle_unfiltered is not None and report.nozzle_filtered is not None
    assert report.nozzle_filtered.rms_deg < report.nozzle_unfiltered.rms_deg
    assert "nozzle RMS, with wave filter (deg)" in table


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--vessel", "default", "--sea-state", "9"], "sea-state"),
        (["--vessel", "default", "--wind", "-1"], "wind"),
        (["--vessel", "default", "--wind", "50"], "wind"),
        (["--vessel", "default", "--wind-dir", "360"], "wind-dir"),
        (["--wind", "10"], "need one --vessel"),
    ],
)
def test_bad_weather_options_exit_2_with_one_line(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str], tmp_path: object
) -> None:
    from usvsim.cli.main import main

    try:
        code = main(["manoeuvre", *argv, "--out", str(tmp_path)])
    except SystemExit as exit_info:  # argparse's own checks exit instead of returning
        code = exit_info.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_args_check_rejects_weather_for_all_vessels() -> None:
    from usvsim.cli.plant import ManoeuvreArgs

    with pytest.raises(UserError, match="need one --vessel"):
        ManoeuvreArgs(wind=10.0).check()


def test_demo_shows_the_wave_filter_design_and_effect(
    tmp_path: object, capsys: pytest.CaptureFixture[str]
) -> None:
    from usvsim.cli.main import main

    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "wave filter: Kalman observer" in out and "steady-state gains" in out
    assert "sea state 4, heading kept" in out
