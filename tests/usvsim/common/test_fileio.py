"""usvsim.common.fileio: writability checks, staged result sets, JSON without NaN."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from usvsim.common.errors import UserError
from usvsim.common.fileio import (
    check_writable_dir,
    check_writable_file,
    json_safe,
    remove_stale_temporaries,
    staged_dir,
)


def test_writable_dir_is_created_and_a_file_is_refused(tmp_path: Path) -> None:
    assert check_writable_dir(tmp_path / "a" / "b").is_dir()
    (tmp_path / "f").write_text("x")
    with pytest.raises(UserError, match=r"--out .*f: is a file, not a folder"):
        check_writable_dir(tmp_path / "f")
    with pytest.raises(UserError, match="cannot create the folder"):
        check_writable_dir(tmp_path / "f" / "sub")
    with pytest.raises(UserError, match=r"--json .*: is a folder, not a file"):
        check_writable_file(tmp_path, "--json")
    assert list(tmp_path.glob("**/.write-test.*")) == []


def test_staged_dir_moves_all_or_nothing(tmp_path: Path) -> None:
    (tmp_path / "r.csv").write_text("old")
    (tmp_path / "p-1.png").write_text("old plot")
    with pytest.raises(RuntimeError), staged_dir(tmp_path, "r", replaces=["p-*.png"]) as s:
        (s / "r.csv").write_text("new")
        raise RuntimeError("failed half way")
    assert (tmp_path / "r.csv").read_text() == "old"
    assert (tmp_path / "p-1.png").exists()
    with staged_dir(tmp_path, "r", replaces=["p-*.png"]) as s:
        (s / "r.csv").write_text("new")
        (s / "p-2.png").write_text("new plot")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p-2.png", "r.csv"]
    assert (tmp_path / "r.csv").read_text() == "new"


def test_stale_temporaries_are_removed(tmp_path: Path) -> None:
    (tmp_path / ".x.csv.123.tmp").write_text("half")
    (tmp_path / ".staging-bench").mkdir()
    (tmp_path / "keep.tmp").write_text("not ours: no leading dot")
    removed = remove_stale_temporaries(tmp_path)
    assert len(removed) == 2
    assert [p.name for p in tmp_path.iterdir()] == ["keep.tmp"]


def test_json_safe_replaces_every_non_finite_float() -> None:
    value = {"a": math.nan, "b": [1.0, math.inf, {"c": -math.inf}], "d": (2, "x")}
    assert json.dumps(json_safe(value), allow_nan=False) == (
        '{"a": null, "b": [1.0, null, {"c": null}], "d": [2, "x"]}'
    )
