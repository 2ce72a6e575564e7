"""COLREG columns of the stress suite's traffic sets (usvsim.evaluation.stress_colreg)."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest

from usvsim.evaluation.bench import to_csv
from usvsim.evaluation.colreg import evaluate_colreg, summarize_colreg
from usvsim.evaluation.colreg_rollout import encounter_tracks
from usvsim.evaluation.stress import (
    evaluate_set,
    run_stress,
    select_sets,
    stress_episodes,
    stress_json,
    stress_markdown,
)
from usvsim.evaluation.stress_colreg import StressRow, colreg_overhead, has_traffic, stress_row
from usvsim.helm.registry import make_helmsman

N = 30


@pytest.fixture(scope="module")
def result():
    sets = select_sets(["two-obstacles", "moving-vessels"])
    factories = {h: (lambda h=h: make_helmsman(h)) for h in ("straight", "vo")}
    return run_stress(factories, sets, N, progress=False)


def _row(result, helmsman, set_name):
    return next(r for r in result.rows if (r.helmsman, r.episode_set) == (helmsman, set_name))


def test_only_sets_with_vessels_have_traffic():
    names = [s.name for s in select_sets([]) if has_traffic(s)]
    assert names == ["moving-vessels", "everything"]


def test_traffic_set_rows_carry_compliance_with_its_wilson_interval(result):
    for h in ("straight", "vo"):
        r = _row(result, h, "moving-vessels")
        assert r.colreg_encounters >= N  # 1-3 vessels per episode, most on a collision course
        assert 0 <= r.colreg_compliant <= r.colreg_encounters
        assert r.colreg_compliance_rate == pytest.approx(r.colreg_compliant / r.colreg_encounters)
        assert r.colreg_compliance_ci95_low <= r.colreg_compliance_rate
        assert r.colreg_compliance_rate <= r.colreg_compliance_ci95_high
        assert 0.0 < r.colreg_s < r.wall_s


def test_sets_without_traffic_have_empty_columns(result):
    r = _row(result, "vo", "two-obstacles")
    assert r.colreg_encounters == 0 and r.colreg_s == 0.0
    assert math.isnan(r.colreg_compliance_rate) and math.isnan(r.colreg_mean_score)


def test_columns_are_the_scorer_s_figures_on_the_recorded_tracks():
    (stress_set,) = select_sets(["moving-vessels"])
    episodes = stress_episodes(stress_set, 12)
    records = evaluate_set(make_helmsman("vo"), stress_set, episodes)
    base = StressRow("vo", "moving-vessels", *[None] * 2, *[0.0] * 7)  # only the columns matter
    row = stress_row(base, stress_set, records)
    summary = summarize_colreg(evaluate_colreg(encounter_tracks(records)))
    assert row.colreg_encounters == summary.compliance.n
    assert row.colreg_compliant == summary.compliance.successes
    assert row.colreg_mean_score == pytest.approx(summary.mean_score)
    assert stress_row(base, stress_set, records, colreg=False).colreg_encounters == 0


def test_a_helmsman_that_never_gives_way_scores_far_below_vo(result):
    # measured: straight 7 % of 56 encounters, vo 59 % (30 episodes of moving-vessels)
    straight = _row(result, "straight", "moving-vessels")
    vo = _row(result, "vo", "moving-vessels")
    assert straight.colreg_compliance_rate < 0.2
    assert vo.colreg_compliance_ci95_low > straight.colreg_compliance_ci95_high


def test_json_csv_and_markdown_show_the_columns(result):
    payload = json.loads(stress_json(result))
    rows = {(r["helmsman"], r["episode_set"]): r for r in payload["rows"]}
    assert rows[("vo", "moving-vessels")]["colreg_encounters"] > 0
    assert rows[("vo", "two-obstacles")]["colreg_compliance_rate"] is None
    assert 0.0 < payload["colreg_overhead"] < 0.2
    header = to_csv(result.rows).splitlines()[0].split(",")
    assert "colreg_compliance_ci95_low" in header and "colreg_encounters" in header
    md = stress_markdown(result)
    assert "COLREG compliance on the sets with traffic" in md
    assert md.count("| moving-vessels |") == 2 and md.count("| two-obstacles |") == 1


def test_overhead_is_scoring_time_over_the_scored_runs():
    rows = [
        replace(_empty_row(), wall_s=11.0, colreg_s=1.0),
        replace(_empty_row(), wall_s=5.5, colreg_s=0.5),
        replace(_empty_row(), wall_s=100.0),  # a set without traffic does not count
    ]
    assert colreg_overhead(rows) == pytest.approx(1.5 / 15.0)
    assert math.isnan(colreg_overhead([_empty_row()]))


def _empty_row():
    return StressRow("h", "s", None, 0, *[0.0] * 6)
