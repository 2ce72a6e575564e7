"""The SB-MPC expert's COLREG demonstrations (issue 41): files the existing loader reads, the
same bytes from the same seed, the compliant runs kept, and no COLREG suite episode among them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from learning.experiments.colreg_demos import (
    COLREG_DEMO_SEED,
    COLREG_DEMOS_DIR,
    colreg_demo_episodes,
    record_colreg_demonstrations,
)
from learning.imitation.demonstrations import (
    load_recording,
    load_recordings,
    quality_check,
    recording_to_text,
    save_recordings,
)
from learning.imitation.preprocess import check_observations, expert_data
from usvsim.evaluation.colreg_suite import COLREG_SETS, colreg_episodes

SHIPPED = sorted(COLREG_DEMOS_DIR.glob("demo_*.csv.gz"))


@pytest.fixture(scope="module")
def demo():
    return record_colreg_demonstrations(6, seed=3, compliant_only=False)


def test_the_files_round_trip_through_the_existing_loader(demo, tmp_path: Path) -> None:
    paths = save_recordings(demo.recordings, tmp_path, compress=True)
    report = load_recordings(tmp_path)
    assert not report.errors and len(report.recordings) == 6
    for rec, back in zip(demo.recordings, report.recordings, strict=True):
        assert back.meta == rec.meta
        assert back.meta["format"] == "usvsim-demo/2"
        np.testing.assert_allclose(back.gps_latlon_deg, rec.gps_latlon_deg, atol=1e-8)
        np.testing.assert_allclose(back.compass_rad, rec.compass_rad, atol=1e-3)
    assert paths[0].name == "demo_000.csv.gz"
    kept = [r for r in report.recordings if not quality_check(r)]
    assert kept
    data = expert_data(kept, "scene", "gaussian")
    check_observations(data, "scene")
    # the scene the loader reads is the episode's: its vessels where they were drawn
    scene = report.recordings[2].scene
    assert scene is not None
    vessels = demo.runs[2].episode.vessels
    assert scene.vessels.shape == (len(vessels), 6)
    assert scene.vessels[0, 0] == pytest.approx(vessels[0].x0_n)


def test_same_seed_same_bytes(demo, tmp_path: Path) -> None:
    again = record_colreg_demonstrations(6, seed=3, compliant_only=False)
    a = save_recordings(demo.recordings, tmp_path / "a", compress=True)
    b = save_recordings(again.recordings, tmp_path / "b", compress=True)
    assert [p.read_bytes() for p in a] == [p.read_bytes() for p in b]
    other = record_colreg_demonstrations(2, seed=4, compliant_only=False)
    c = save_recordings(other.recordings, tmp_path / "c", compress=True)
    assert a[0].read_bytes() != c[0].read_bytes()


def test_only_compliant_successful_runs_are_kept(demo) -> None:
    kept = record_colreg_demonstrations(6, seed=3)
    ok = demo.score.success & demo.score.passed
    assert np.array_equal(kept.kept, ok)
    # a kept file keeps its run's index (episode k of the draw), and its bytes are those of
    # the unfiltered set's file k (every run is logged, whichever are dropped)
    assert [r.meta["run"] for r in kept.recordings] == list(np.flatnonzero(ok))
    for r in kept.recordings:
        assert recording_to_text(r) == recording_to_text(demo.recordings[r.meta["run"]])


def _suite_targets(n: int) -> set[tuple[float, ...]]:
    """Every vessel (x0, y0, course, speed), rounded to 1 mm / 1 µrad, of the first ``n``
    episodes of every COLREG suite set in both splits."""
    keys: set[tuple[float, ...]] = set()
    for cset in COLREG_SETS:
        for split in ("validation", "test"):
            for ep in colreg_episodes(cset, n, split):
                keys.update(
                    (round(v.x0_n, 3), round(v.y0_e, 3), round(v.course_rad, 6),
                     round(v.speed_mps, 6))
                    for v in ep.vessels
                )  # fmt: skip
    return keys


def test_no_recorded_episode_is_a_colreg_suite_episode() -> None:
    """The demonstrations' episode seed is none of the suite's (Imazu and trafficgen sets, both
    splits, CRC-32 of ``<set>/<split>``), nor the family validation sets'; and no vessel of a
    shipped file is a vessel of the suite's first 100 episodes of any set in either split."""
    from learning.experiments.validation import (
        CROWDED_VALIDATION_SEED,
        FAMILY_VALIDATION_SEED,
        RADAR_VALIDATION_SEED,
    )

    episode_seed, _ = colreg_demo_episodes(1, seed=COLREG_DEMO_SEED)
    suite = {s.seed(split) for s in COLREG_SETS for split in ("validation", "test")}
    assert len(suite) == 2 * len(COLREG_SETS)
    others = {FAMILY_VALIDATION_SEED, CROWDED_VALIDATION_SEED, RADAR_VALIDATION_SEED}
    assert episode_seed not in suite | others
    targets = _suite_targets(100)
    assert len(targets) > 10_000
    shipped = 0
    for path in SHIPPED:
        meta = json.loads(_first_line(path))
        for v in meta["scene"]["vessels"]:
            key = (round(v[0], 3), round(v[1], 3), round(v[2], 6), round(v[3], 6))
            assert key not in targets, f"{path.name}: a COLREG suite vessel {key}"
            shipped += 1
    assert shipped > len(SHIPPED)  # every file holds at least one vessel, most more


def _first_line(path: Path) -> str:
    import gzip

    with gzip.open(path, "rt", encoding="utf-8") as handle:
        line = handle.readline()
    return line.split(" ", 2)[2]


def test_the_shipped_set_loads_and_most_of_it_passes_the_quality_filter() -> None:
    assert len(SHIPPED) == 250  # of the 400 runs drawn (README: success and compliance)
    recs = [load_recording(p) for p in SHIPPED[:20]]
    assert all(r.scene is not None for r in recs)
    assert sum(not quality_check(r) for r in recs) >= 15  # 201 of the 250 pass (16 of these 20)
