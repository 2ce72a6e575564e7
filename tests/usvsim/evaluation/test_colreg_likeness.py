"""Expert-likeness in traffic: the metrics on hand-made tracks, and one fast run end to end.

usvsim.evaluation.colreg_likeness (path distance, lock-step distance, pass side, side agreement)
and usvsim.evaluation.colreg_likeness_bench (the expert and helmsmen on the same COLREG episodes).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from usvsim.evaluation.colreg import EncounterTracks, evaluate_colreg
from usvsim.evaluation.colreg_likeness import (
    held_positions,
    lockstep_distance_m,
    mean_interval,
    pass_sides,
    path_distance_m,
    side_agreement,
)
from usvsim.evaluation.likeness import chamfer_m
from usvsim.task.colreg_geometry import EncounterType

SCRIPT = Path(__file__).resolve().parents[3] / "benchmarks" / "colreg_likeness.py"
U = 3.0  # m/s, own and target speed of the hand-made encounters
T = 201  # samples, 1 s apart


def _script() -> Any:
    """benchmarks/colreg_likeness.py as a module."""
    spec = importlib.util.spec_from_file_location("colreg_likeness_script", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _tracks(own: np.ndarray, targets: np.ndarray, dt: float = 1.0) -> EncounterTracks:
    """EncounterTracks of own positions (E, T, 2) and target positions (E, K, T, 2), courses and
    speeds from their differences (one-sided at the ends)."""

    def course_speed(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = np.gradient(p, dt, axis=-2)
        return np.arctan2(v[..., 1], v[..., 0]), np.hypot(v[..., 0], v[..., 1])

    oc, os_ = course_speed(own)
    tc, ts = course_speed(targets)
    e, t = own.shape[:2]
    return EncounterTracks(dt, own, oc, os_, targets, tc, ts, np.ones((e, t), dtype=bool))


def _head_on(swerve_east_m: float) -> EncounterTracks:
    """Own ship north at U from (−300, 0) with a smooth swerve to east ``swerve_east_m`` around
    the meeting (t = 100 s); target south at U from (300, 0): a head-on meeting."""
    t = np.arange(T, dtype=float)
    east = swerve_east_m * np.exp(-(((t - 100.0) / 25.0) ** 2))
    own = np.stack([-300.0 + U * t, east], axis=-1)[None]
    target = np.stack([300.0 - U * t, np.zeros(T)], axis=-1)[None, None]
    return _tracks(own, target)


def test_the_same_path_is_at_distance_zero_and_agrees_everywhere() -> None:
    tr = _head_on(60.0)
    ok = tr.valid
    assert path_distance_m(tr.own_north_east_m, ok, tr.own_north_east_m, ok).tolist() == [0.0]
    mean, peak = lockstep_distance_m(tr.own_north_east_m, ok, tr.own_north_east_m, ok)
    assert mean.tolist() == [0.0] and peak.tolist() == [0.0]
    kind = evaluate_colreg(tr).encounter
    assert kind.tolist() == [[int(EncounterType.HEAD_ON)]]
    agreement = side_agreement(pass_sides(tr), pass_sides(tr), kind)
    assert agreement.overall is not None
    assert (agreement.overall.successes, agreement.overall.n) == (1, 1)
    assert agreement.by_type == {"head_on": (1, 1)}


def test_a_mirrored_path_passes_on_the_other_side() -> None:
    starboard, port = _head_on(60.0), _head_on(-60.0)  # swerve east: target left to port
    assert pass_sides(starboard).tolist() == [[-1]]  # target on our port side at the CPA
    assert pass_sides(port).tolist() == [[1]]
    agreement = side_agreement(pass_sides(port), pass_sides(starboard), [[EncounterType.HEAD_ON]])
    assert agreement.overall is not None
    assert (agreement.overall.successes, agreement.overall.n) == (0, 1)
    # the lock-step distance peaks at the meeting: 2 × 60 m apart
    _, peak = lockstep_distance_m(
        port.own_north_east_m, port.valid, starboard.own_north_east_m, starboard.valid
    )
    assert peak[0] == pytest.approx(120.0)


def test_parallel_lines_are_their_offset_apart_on_any_sampling() -> None:
    a = np.stack([np.linspace(0.0, 100.0, 11), np.zeros(11)], axis=-1)[None]  # 10 m samples
    b = np.stack([np.linspace(0.0, 100.0, 7), np.full(7, 4.0)], axis=-1)[None]  # staggered
    d = path_distance_m(a, np.ones((1, 11), bool), b, np.ones((1, 7), bool))
    assert d[0] == pytest.approx(4.0, abs=1e-12)  # to the polyline, not its vertices
    assert chamfer_m(a[0], b[0]) > 4.5  # the vertex-to-vertex distance is not


def test_path_distance_equals_the_study_likeness_chamfer_on_dense_paths() -> None:
    """The same samples: to the polyline (here) is never farther than to its vertices
    (likeness.chamfer_m), and on paths sampled every ~0.3 m the two differ by < 1 cm."""
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 1.0, 1001)
    paths = []
    for _ in range(3):  # smooth random curves ~300 m long
        c = rng.normal(0.0, 40.0, (2, 4))
        x = 300.0 * s + c[0] @ np.sin(np.outer(np.arange(1, 5), np.pi * s))
        paths.append(np.stack([x, c[1] @ np.sin(np.outer(np.arange(1, 5), np.pi * s))], -1))
    a, b = np.stack(paths[:2]), np.stack(paths[1:])
    ok = np.ones(a.shape[:2], bool)
    d = path_distance_m(a, ok, b, ok)
    ref = np.array([chamfer_m(a[i], b[i]) for i in range(2)])
    assert np.all(d <= ref) and np.all(ref - d < 0.01) and np.all(ref > 10.0)


def test_a_path_cut_short_is_held_at_its_end() -> None:
    line = np.stack([np.arange(10.0), np.zeros(10)], axis=-1)[None]
    cut = np.arange(10) < 4  # stopped at x = 3 m
    held = held_positions(line, cut[None], 12)
    assert held[0, :, 0].tolist() == [0.0, 1.0, 2.0, 3.0] + [3.0] * 8
    mean, peak = lockstep_distance_m(line, cut[None], line, np.ones((1, 10), bool))
    assert peak[0] == 6.0 and mean[0] == pytest.approx(sum(range(1, 7)) / 10)
    d = path_distance_m(line, cut[None], line, np.ones((1, 10), bool))
    assert d[0] == pytest.approx(0.5 * (0.0 + sum(range(1, 7)) / 10))


def test_empty_slots_and_episodes_without_an_encounter_are_left_out() -> None:
    tr = _head_on(60.0)
    far = tr.target_north_east_m + np.array([0.0, 5000.0])  # a second target never near
    two = EncounterTracks(
        tr.dt_s, tr.own_north_east_m, tr.own_course_rad, tr.own_speed_mps,
        np.concatenate([tr.target_north_east_m, far], axis=1),
        np.repeat(tr.target_course_rad, 2, axis=1), np.repeat(tr.target_speed_mps, 2, axis=1),
        tr.valid, np.array([[True, False]]),
    )  # fmt: skip
    sides = pass_sides(two)
    assert sides.tolist() == [[-1, 0]]
    agreement = side_agreement(sides, sides, evaluate_colreg(two).encounter)
    assert agreement.overall is not None and agreement.overall.n == 1
    none = side_agreement(sides, sides, np.zeros((1, 2), int))
    assert none.overall is None and none.by_type == {}


def test_the_mean_interval_is_seeded_and_holds_the_mean() -> None:
    v = np.random.default_rng(1).exponential(20.0, 50)
    a, b = mean_interval(v), mean_interval(v)
    assert a == b and a.ci95[0] < a.mean < a.ci95[1] and a.n == 50
    assert mean_interval(np.array([np.nan, 3.0])).n == 1
    assert mean_interval(np.array([np.nan])).n == 0


def test_end_to_end_sb_mpc_matches_itself_and_vo_does_not(tmp_path: Path) -> None:
    """The tool on 2 Imazu episodes (a head-on, a crossing), vo and sb-mpc as stand-ins for IL
    and RL: sb-mpc against the sb-mpc expert is exactly at distance 0 and agrees everywhere; the
    JSON and the table are written and agree with each other."""
    script = _script()
    code = script.main(
        ["--helmsmen", "vo,sb-mpc", "--sets", "imazu-01,imazu-02", "--episodes", "1",
         "--out", str(tmp_path)]
    )  # fmt: skip
    assert code == 0
    payload = json.loads((tmp_path / "likeness.json").read_text())
    rows = {r["helmsman"]: r for r in payload["rows"]}
    assert payload["expert"] == "sb-mpc" and payload["sets"] == ["imazu-01", "imazu-02"]
    assert len(payload["load_1min"]) == 2 and payload["wall_s"] > 0.0  # the load it ran at
    sb, vo = rows["sb-mpc"], rows["vo"]
    assert sb["path_distance_m"]["mean"] == 0.0 and sb["sync_max_m"]["mean"] == 0.0
    assert sb["side_agreement"]["rate"] == 1.0 and sb["side_agreement"]["encounters"] >= 2
    assert sb["compliance_rate"] == payload["expert_row"]["compliance_rate"]
    assert vo["path_distance_m"]["mean"] > 1.0 and vo["sync_mean_m"]["mean"] > 1.0
    assert (
        vo["episodes"] == 2
        and vo["side_agreement"]["encounters"] == sb["side_agreement"]["encounters"]
    )
    table = (tmp_path / "likeness.md").read_text()
    assert "| sb-mpc (expert) |" in table and "| vo |" in table


def test_bad_input_is_one_line_and_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    script = _script()
    assert script.main(["--sets", "imazu-99"]) == 2
    assert script.main(["--seeds", "IL=only-one.pt"]) == 2
    assert script.main(["--helmsmen", "no-such-helmsman"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("colreg_likeness: ") for line in err)
    assert "imazu-99" in err[0] and "two or more" in err[1] and "no-such-helmsman" in err[2]


def test_seed_groups_take_the_iqm_with_rliable() -> None:
    pytest.importorskip("rliable")
    from usvsim.evaluation.colreg_likeness import Estimate, SideAgreement
    from usvsim.evaluation.colreg_likeness_bench import LikenessRow, group_figures
    from usvsim.evaluation.colreg_suite import ColregRow
    from usvsim.evaluation.stats import proportion

    def row(k: int, dist: float) -> LikenessRow:
        suite = ColregRow("x", "s", proportion(k, 10), 0, proportion(k, 10), 0.5)
        e = Estimate(dist, (dist, dist), 10)
        return LikenessRow(f"IL#{k}", "IL", suite, e, e, e, SideAgreement(proportion(k, 10), {}))

    g = group_figures("IL", [row(7, 10.0), row(8, 20.0), row(9, 60.0)], reps=200)
    dist = g.iqm["path_distance_m"]
    assert dist is not None and dist.mean == pytest.approx(30.0)  # 3 seeds: the mean
    assert dist.ci95[0] >= 10.0 and dist.ci95[1] <= 60.0
    side = g.iqm["side_agreement"]
    assert side is not None and side.mean == pytest.approx(0.8)
    assert g.per_seed["success_rate"] == (0.7, 0.8, 0.9)
