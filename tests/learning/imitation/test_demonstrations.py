"""Recorder, on-disk format usvsim-demo/1, loader errors and the quality filter."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from learning.imitation.demonstrations import (
    DEMOS_DIR,
    DemoFormatError,
    load_recording,
    load_recordings,
    quality_check,
    record_demonstrations,
    recording_to_text,
    save_recordings,
)


@pytest.fixture(scope="module")
def recordings():  # type: ignore[no-untyped-def]
    return record_demonstrations(4, seed=11)


def test_streams_have_their_own_rates_and_are_not_aligned(recordings) -> None:  # type: ignore[no-untyped-def]
    r = recordings[0]
    assert np.median(np.diff(r.gps_t_s)) == pytest.approx(1.0, abs=0.03)
    assert np.median(np.diff(r.compass_t_s)) == pytest.approx(0.2, abs=0.03)
    assert np.median(np.diff(r.radar_t_s)) == pytest.approx(2.5, abs=0.05)
    assert not np.isin(r.gps_t_s, r.compass_t_s).any()


def test_save_load_round_trip(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    paths = save_recordings(recordings, tmp_path)
    back = load_recording(paths[1])
    r = recordings[1]
    assert back.meta == r.meta
    np.testing.assert_allclose(back.gps_t_s, r.gps_t_s, atol=5e-5)
    np.testing.assert_allclose(back.gps_latlon_deg, r.gps_latlon_deg, atol=5e-9)
    np.testing.assert_allclose(back.compass_rad, r.compass_rad, atol=1e-4)
    np.testing.assert_allclose(back.radar_range_m, r.radar_range_m, atol=5e-3)


def _write_broken(tmp_path: Path, recordings, edit) -> Path:  # type: ignore[no-untyped-def]
    lines = recording_to_text(recordings[0]).splitlines()
    path = tmp_path / "demo_900.csv"
    path.write_text("\n".join(edit(lines)) + "\n")
    return path


def test_missing_column_is_named(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    def drop_heading(lines: list[str]) -> list[str]:
        return [lines[0]] + [
            ",".join(c for i, c in enumerate(x.split(",")) if i != 4) for x in lines[1:]
        ]

    with pytest.raises(DemoFormatError, match=r"line 2: missing column\(s\) heading_deg"):
        load_recording(_write_broken(tmp_path, recordings, drop_heading))


def test_non_monotonic_time_is_located(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    def swap(lines: list[str]) -> list[str]:
        gps = [i for i, x in enumerate(lines) if x.startswith("gps,")]
        a, b = gps[3], gps[4]
        lines[a], lines[b] = lines[b], lines[a]
        return lines

    with pytest.raises(DemoFormatError, match=r"column t_s: gps time .* time must increase"):
        load_recording(_write_broken(tmp_path, recordings, swap))


def test_nan_is_located(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    def nan(lines: list[str]) -> list[str]:
        k = next(i for i, x in enumerate(lines) if x.startswith("gps,"))
        cells = lines[k].split(",")
        cells[2] = "nan"
        lines[k] = ",".join(cells)
        return lines

    path = _write_broken(tmp_path, recordings, nan)
    k = next(i for i, x in enumerate(path.read_text().splitlines()) if x.startswith("gps,"))
    with pytest.raises(DemoFormatError, match=rf"line {k + 1}, column lat_deg: nan is not finite"):
        load_recording(path)


def test_bad_metadata_and_format(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(DemoFormatError, match="format 'usvsim-demo/9'"):
        load_recording(
            _write_broken(tmp_path, recordings, lambda ls: [ls[0].replace("/1", "/9", 1), *ls[1:]])
        )
    with pytest.raises(DemoFormatError, match="not valid JSON"):
        load_recording(_write_broken(tmp_path, recordings, lambda ls: [ls[0][:-3], *ls[1:]]))


def test_a_bad_file_does_not_stop_the_batch(recordings, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    save_recordings(recordings, tmp_path)
    (tmp_path / "demo_002.csv").write_text("garbage\n")
    report = load_recordings(tmp_path)
    assert len(report.recordings) == 3
    assert list(report.errors) == [str(tmp_path / "demo_002.csv")]
    assert "line 1" in report.errors[str(tmp_path / "demo_002.csv")]


def test_quality_filter_reasons(recordings) -> None:  # type: ignore[no-untyped-def]
    r = recordings[0]
    keep = (r.gps_t_s < 20.0) | (r.gps_t_s > 26.0)
    gap = type(r)(
        r.meta,
        r.gps_t_s[keep],
        r.gps_latlon_deg[keep],
        r.compass_t_s,
        r.compass_rad,
        r.radar_t_s,
        r.radar_range_m,
        r.radar_bearing_rad,
    )
    reasons = quality_check(gap)
    assert any(x.startswith("GPS gap of") for x in reasons)
    spun = type(r)(
        r.meta,
        r.gps_t_s,
        r.gps_latlon_deg,
        r.compass_t_s,
        r.compass_rad + np.where(r.compass_t_s > 30, math.radians(40), 0.0),
        r.radar_t_s,
        r.radar_range_m,
        r.radar_bearing_rad,
    )
    assert any("within 2 s" in x for x in quality_check(spun))


def test_shipped_demonstrations_46_recorded_39_kept() -> None:
    report = load_recordings(DEMOS_DIR)
    assert report.errors == {}
    assert len(report.recordings) == 46
    kept = [r for r in report.recordings if not quality_check(r)]
    assert len(kept) == 39
    # every lapse of the expert (a late turn) is among the rejected runs
    assert all(quality_check(r) for r in report.recordings if r.meta["expert"]["late_turn"])
