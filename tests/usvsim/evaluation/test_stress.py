"""The stress suite: every set exercises what it names, reproducible rows, JSON, files."""

from __future__ import annotations

import json
import math
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pytest

from usvsim.cli.bench import run_bench_command
from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.evaluation.bench import BenchArgs
from usvsim.evaluation.episodes import heldout_episodes
from usvsim.evaluation.stress import (
    STRESS_SETS,
    run_stress,
    select_sets,
    stress_episodes,
    stress_json,
)
from usvsim.helm.registry import make_helmsman
from usvsim.task.openwater import OpenWaterScenario, from_pole_episodes
from usvsim.task.waypoints import heldout_courses

N = 40
SETS = {s.name: s for s in STRESS_SETS}


def _eps(name):
    return stress_episodes(SETS[name], N)


def _course(e):
    s, g = e.start_ne, np.asarray(e.goal_ne)
    return math.atan2(g[1] - s[1], g[0] - s[0])


def _lateral(e):  # goal offset from the start → pole line, m (signed)
    s, g = e.start_ne, np.asarray(e.goal_ne)
    u = -s / np.hypot(*s)
    d = g - s
    return d[1] * u[0] - d[0] * u[1]


def _all(values, lo, hi):
    values = np.asarray(list(values), dtype=float)
    return bool(values.size and values.min() >= lo - 1e-9 and values.max() <= hi + 1e-9)


def _current_rel(e):
    return np.abs(ssa(e.disturbance.current_direction_rad - _course(e)))


def _weather(e):
    return e.disturbance.weather


def _wind_rel(e):  # the wind's direction (towards) off the course, rad, in [0, π]
    return np.abs(ssa(_weather(e).wind_dir_rad - _course(e)))


def _waves_off_wind(e):
    return np.abs(ssa(_weather(e).wave_dir_rad - _weather(e).wind_dir_rad))


CHECKS = {
    "study": lambda eps: eps == from_pole_episodes(heldout_episodes(n=N)),
    "start-short": lambda eps: _all((e.start.start_distance_m for e in eps), 30, 50),
    "start-long": lambda eps: (
        _all((e.start.start_distance_m for e in eps), 150, 200)
        and _all((np.hypot(*(np.asarray(e.goal_ne) - e.start_ne)) for e in eps), 320, 320)
    ),
    "heading-offset": lambda eps: (
        max(abs(e.start.heading_offset_rad) for e in eps) > 2.5
        and _all((abs(e.start.heading_offset_rad) for e in eps), 0, math.pi)
    ),
    "goal-off-line": lambda eps: (
        _all((abs(_lateral(e)) for e in eps), 20, 60)
        and min(_lateral(e) for e in eps) < 0 < max(_lateral(e) for e in eps)
    ),
    "goal-anywhere": lambda eps: (
        max(abs(ssa(_course(e) - math.atan2(-e.start_ne[1], -e.start_ne[0]))) for e in eps) > 2.5
    ),
    "current-following": lambda eps: (
        _all((e.disturbance.current_speed_mps for e in eps), 0.3, 0.8)
        and _all(map(_current_rel, eps), 0, math.radians(20))
    ),
    "current-crossing": lambda eps: _all(
        map(_current_rel, eps), math.radians(70), math.radians(110)
    ),
    "current-head": lambda eps: _all(map(_current_rel, eps), math.radians(160), math.pi),
    "gnss-noise-x3": lambda eps: all(e.disturbance.gnss_noise_scale == 3.0 for e in eps),
    "gnss-outliers": lambda eps: all(e.disturbance.gnss_outlier_probability == 0.05 for e in eps),
    "gnss-dropout": lambda eps: (
        _all((e.disturbance.gnss_dropout_duration_s for e in eps), 15, 30)
        and all(e.disturbance.gnss_dropout_start_s < e.time_limit_s for e in eps)
    ),
    "radar-clutter": lambda eps: all(e.radar.clutter_probability == 0.001 for e in eps),
    "radar-noise": lambda eps: all(
        (e.radar.speckle, e.radar.missed_probability, e.radar.noise_amplitude) == (0.5, 0.2, 40.0)
        for e in eps
    ),
    "two-obstacles": lambda eps: (
        all(len(e.obstacles) == 2 for e in eps)
        and _all((math.dist(e.obstacles[0][:2], e.obstacles[1][:2]) for e in eps), 15, 30)
    ),
    "several-obstacles": lambda eps: all(4 <= len(e.obstacles) <= 7 for e in eps),
    "extended-obstacles": lambda eps: (
        _all((o[2] for e in eps for o in e.obstacles), 8, 25)
        # the start is 50-100 m from the islet's edge, + 1 m: as far as the study's from its pole
        and _all((e.start.start_distance_m - e.obstacles[0][2] + 1.0 for e in eps), 50, 100)
    ),
    "moving-vessels": lambda eps: (
        all(not e.obstacles and 1 <= len(e.vessels) <= 3 for e in eps)
        and {v.encounter for e in eps for v in e.vessels} == {"head-on", "crossing", "overtaking"}
    ),
    "speed-slow": lambda eps: _all((e.disturbance.speed_mps for e in eps), 1.5, 2.0),
    "speed-fast": lambda eps: _all((e.disturbance.speed_mps for e in eps), 4.0, 5.0),
    "waypoints": lambda eps: all(
        np.array_equal(a.waypoints_ne, b.waypoints_ne) and np.array_equal(a.poles_ne, b.poles_ne)
        for a, b in zip(eps, heldout_courses(n=N), strict=True)
    ),
    "wind-beam": lambda eps: (
        _all((_weather(e).wind_speed_mps for e in eps), 8, 12)
        and _all(map(_wind_rel, eps), math.radians(80), math.radians(100))
        and all(_weather(e).hs_m == 0 for e in eps)
    ),
    "gusts": lambda eps: (
        _all((_weather(e).wind_speed_mps for e in eps), 6, 10)
        and _all((_weather(e).gust_intensity for e in eps), 0.2, 0.3)
        and max(map(_wind_rel, eps)) > 2.5
    ),
    "sea-state-3": lambda eps: (
        _all((_weather(e).hs_m for e in eps), 0.5, 1.25)
        and _all((_weather(e).wind_speed_mps for e in eps), 5.5, 7.9)
        and _all(map(_waves_off_wind, eps), 0, math.radians(30))
    ),
    "sea-state-4": lambda eps: (
        _all((_weather(e).hs_m for e in eps), 1.25, 2.5)
        and _all((_weather(e).wind_speed_mps for e in eps), 8.0, 10.7)
        and _all(map(_waves_off_wind, eps), 0, math.radians(30))
    ),
    "everything": lambda eps: (
        # the moderate weather (issue 38): wind up to 8 m/s and H_s up to 1 m, calm included
        _all((_weather(e).wind_speed_mps for e in eps), 0.0, 8.0)
        and _all((_weather(e).hs_m for e in eps), 0.0, 1.0)
        and max(_weather(e).wind_speed_mps for e in eps) > 4.0
        and max(_weather(e).hs_m for e in eps) > 0.5
        and any(e.vessels for e in eps)
        and any(o[2] >= 8 for e in eps for o in e.obstacles)
        and any(e.disturbance.current_speed_mps > 0.3 for e in eps)
        and any(math.isfinite(e.disturbance.gnss_dropout_start_s) for e in eps)
        and any(e.radar.clutter_probability > 0 for e in eps)
    ),
}


def test_every_set_has_a_check():
    assert set(CHECKS) == set(SETS)


@pytest.mark.parametrize("name", list(SETS))
def test_set_exercises_what_it_names(name):
    assert CHECKS[name](_eps(name))


@pytest.mark.parametrize(
    "name", [s.name for s in STRESS_SETS if s.scenario is not None and s.name != "everything"]
)
def test_single_perturbation_sets_change_few_parameters(name):
    calm = OpenWaterScenario()
    changed = [
        f.name
        for f in fields(OpenWaterScenario)
        if getattr(SETS[name].scenario, f.name) != getattr(calm, f.name)
    ]
    assert 1 <= len(changed) <= 3, changed


def test_same_seed_gives_identical_rows():
    sets = select_sets(["two-obstacles", "moving-vessels", "radar-clutter"])
    factories = {"los-avoid": lambda: make_helmsman("los-avoid"), "vo": lambda: make_helmsman("vo")}
    a = run_stress(factories, sets, 8, progress=False)
    b = run_stress(factories, sets, 8, progress=False)

    def timeless(rows):
        return [replace(r, wall_s=0.0, colreg_s=0.0).flat() for r in rows]

    assert json.dumps(timeless(a.rows)) == json.dumps(timeless(b.rows))  # NaN-safe equality
    assert len(a.rows) == 6


def test_unknown_set_is_an_error():
    with pytest.raises(UserError, match="unknown stress set 'tow-obstacles'"):
        select_sets(["tow-obstacles"])
    with pytest.raises(UserError, match="--sets needs --suite stress"):
        BenchArgs(sets="everything").check()


def test_stress_command_writes_table_heatmap_and_json(tmp_path: Path, capsys):
    args = BenchArgs(
        suite="stress",
        sets="study,several-obstacles",
        helmsmen="los,vo",
        stress_episodes=6,
        out=str(tmp_path),
        json=True,
    )
    assert run_bench_command(args) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["suite"] == "stress" and payload["episodes_per_set"] == 6
    assert {(r["helmsman"], r["episode_set"]) for r in payload["rows"]} == {
        (h, s) for h in ("los", "vo") for s in ("study", "several-obstacles")
    }
    assert payload["wall_s"] > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "stress-heatmap.png",
        "stress.csv",
        "stress.md",
    ]
    md = (tmp_path / "stress.md").read_text()
    assert "| several-obstacles |" in md and "Run time" in md
    assert json.loads(stress_json(run_stress({}, (), 1, progress=False)))["rows"] == []


def test_stress_figures_do_not_depend_on_the_machines_thread_count(tmp_path: Path, capsys):
    """A learned radar policy's float sums depend on torch's thread count; ``--threads`` pins
    it, so the process's own setting (a machine's core count) changes nothing."""
    import torch

    args = BenchArgs(
        suite="stress", sets="several-obstacles", helmsmen="radar-gaussian-gail-trpo-traffic",
        stress_episodes=4, out=str(tmp_path), json=True, plots=False, threads=2,
    )  # fmt: skip
    before = torch.get_num_threads()
    rows = []
    try:
        for machine_threads in (1, 3):
            torch.set_num_threads(machine_threads)
            assert run_bench_command(args) == 0
            assert torch.get_num_threads() == 2
            payload = json.loads(capsys.readouterr().out)
            rows.append(
                [
                    (r["success_rate"], r["min_pole_distance_median_m"], r["path_length_mean_m"])
                    for r in payload["rows"]
                ]
            )
    finally:
        torch.set_num_threads(before)
    assert rows[0] == rows[1]
