"""Demonstrations checked for physical plausibility at the edge: file and line in the message;
IL training skips a bad file with a warning and says how many it used."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from learning.experiments.il_setups import get_il_setup
from learning.experiments.train_il import expert_pairs
from learning.imitation.demonstrations import (
    DEMOS_DIR,
    DemoFormatError,
    load_recording,
    main,
)

SHIPPED = sorted(DEMOS_DIR.glob("demo_*.csv"))


def _edit_gps(src: Path, dst: Path, k: int, column: int, value: str) -> int:
    """Copy ``src`` to ``dst`` with cell ``column`` of the ``k``-th GPS row set; its line."""
    lines = src.read_text().splitlines()
    rows = [i for i, line in enumerate(lines) if line.startswith("gps,")]
    cells = lines[rows[k]].split(",")
    cells[column] = value
    lines[rows[k]] = ",".join(cells)
    dst.write_text("\n".join(lines) + "\n")
    return rows[k] + 1


def _edit_meta(src: Path, dst: Path, **changes: object) -> None:
    lines = src.read_text().splitlines()
    magic, payload = lines[0][2:].split(" ", 1)
    lines[0] = f"# {magic} {json.dumps({**json.loads(payload), **changes})}"
    dst.write_text("\n".join(lines) + "\n")


def test_every_shipped_demonstration_is_plausible() -> None:
    assert len(SHIPPED) == 46
    for path in SHIPPED:
        load_recording(path)


def test_latitude_out_of_range_names_file_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "demo_000.csv"
    line = _edit_gps(SHIPPED[0], bad, 5, 2, "123.0")
    with pytest.raises(DemoFormatError, match=rf"demo_000.csv, line {line}, column lat_deg: 123"):
        load_recording(bad)


def test_a_fix_far_from_the_origin_or_too_fast_is_refused(tmp_path: Path) -> None:
    far = tmp_path / "far.csv"
    line = _edit_gps(SHIPPED[0], far, 5, 2, "63.6")  # ~18 km north of the site
    with pytest.raises(DemoFormatError, match=rf"line {line}: GPS fix \d+ m from the site origin"):
        load_recording(far)
    jump = tmp_path / "jump.csv"
    line = _edit_gps(SHIPPED[0], jump, 5, 2, "63.4395")  # a few hundred metres in ~1 s
    with pytest.raises(DemoFormatError, match=rf"line {line}: GPS fix \d+ m from the previous"):
        load_recording(jump)


@pytest.mark.parametrize(
    ("changes", "words"),
    [
        ({"origin_lat_deg": 999}, "origin_lat_deg must be a number in [-90, 90]"),
        ({"origin_lon_deg": "east"}, "origin_lon_deg must be a number"),
        ({"poles_ne": [[0, "x"]]}, "poles_ne[0] must be [x_N, y_E]"),
        ({"pole_radius_m": -1}, "pole_radius_m must be in (0, 100]"),
    ],
)
def test_implausible_metadata_is_refused(tmp_path: Path, changes: dict, words: str) -> None:
    bad = tmp_path / "demo.csv"
    _edit_meta(SHIPPED[0], bad, **changes)
    with pytest.raises(DemoFormatError, match="line 1: metadata") as info:
        load_recording(bad)
    assert words in str(info.value)


def test_training_skips_bad_files_and_says_how_many_it_used(tmp_path: Path) -> None:
    for src in SHIPPED[:5]:
        shutil.copy(src, tmp_path / src.name)
    _edit_gps(SHIPPED[0], tmp_path / SHIPPED[0].name, 5, 2, "123.0")
    _edit_meta(SHIPPED[1], tmp_path / SHIPPED[1].name, origin_lat_deg=999)
    said: list[str] = []
    data, used, skipped = expert_pairs(
        get_il_setup("il-gaussian-positional"), (tmp_path,), said.append
    )
    assert (used, skipped) == (3, 2)
    assert sum(line.startswith("warning: skipping") for line in said) == 2
    assert "using 3 of 5 demonstrations" in said[-1]
    assert len(data) > 0 and int(data.episode.max()) == 2


def test_a_folder_without_usable_demonstrations_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(DemoFormatError, match="no usable demonstration"):
        expert_pairs(get_il_setup("il-gaussian-positional"), (tmp_path,), lambda _: None)


def test_the_recorder_never_writes_into_the_package_unasked(capsys) -> None:
    before = {p.name: p.stat().st_mtime_ns for p in DEMOS_DIR.iterdir()}
    assert main([]) == 2
    assert "FOLDER is required" in capsys.readouterr().err
    assert {p.name: p.stat().st_mtime_ns for p in DEMOS_DIR.iterdir()} == before
