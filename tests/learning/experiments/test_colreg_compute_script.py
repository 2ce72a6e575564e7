"""benchmarks/colreg_compute.py: the training wall-clock of every finished run, per setup and
in total."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

_SPEC = importlib.util.spec_from_file_location(
    "colreg_compute", Path(__file__).resolve().parents[3] / "benchmarks" / "colreg_compute.py"
)
assert _SPEC is not None and _SPEC.loader is not None
compute = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(compute)


def test_it_sums_each_runs_wall_clock_per_setup(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for name, setup, wall in (("a/seed0", "x", 1800.0), ("a/seed1", "x", 900.0), ("b", "y", 3600)):
        (tmp_path / name).mkdir(parents=True)
        (tmp_path / name / "summary.json").write_text(
            json.dumps({"setup": setup, "wall_time_s": wall})
        )
    (tmp_path / "scores-only").mkdir()
    (tmp_path / "scores-only" / "summary.json").write_text("{}")  # no wall-clock: not a run
    assert compute.main([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| `x` | 2 | 2,700 | 0.8 |" in out and "| `y` | 1 | 3,600 | 1.0 |" in out
    assert "| total | 3 | 6,300 | 1.8 |" in out


def test_no_run_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as exc:
        compute.main([str(tmp_path)])
    assert exc.value.code == 2


def test_a_run_resumed_in_a_copy_counts_once_at_its_whole_length(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = "iteration,wall_time_s\n1,10.0\n"
    for name, wall in (("seed0", 1000.0), ("seed0-300", 1800.0), ("seed1", 900.0)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "summary.json").write_text(
            json.dumps({"setup": "x", "seed": int(name[4]), "wall_time_s": wall})
        )
        (tmp_path / name / "log.csv").write_text(log)
    assert [r[2] for r in compute.runs([tmp_path])] == [1800.0, 900.0]
