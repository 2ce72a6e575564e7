"""``usvsim bench --sweep DIR``: the sweep's across-seed columns on the shipped models' held-out
rows, read from its ``report.json`` (a small fake one here, in the format of
:func:`learning.experiments.sweep_report.write_report`); one line for a folder that is no sweep."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from usvsim.cli.main import main
from usvsim.common.errors import UserError
from usvsim.evaluation.bench_sweep import SWEEP_HEADER, load_sweep

MODEL = "rl-categorical-positional"  # a setup of the sweep
SHIPPED = "positional-categorical-trpo-study"  # the shipped model of that setup (card "setup")


def _arm(setup: str, overrides: dict[str, Any], seeds: list[int], iqm: Any, ci: list[float]) -> Any:
    return {
        "arm": setup,
        "setup": setup,
        "overrides": overrides,
        "seeds": seeds,
        "crashed_seeds": [4] if len(seeds) == 4 else [],
        "not_run_seeds": [],
        "heldout_iqm": iqm,
        "heldout_iqm_ci95": ci,
    }


@pytest.fixture
def sweep_dir(tmp_path: Path) -> Path:
    root = tmp_path / "sweep"
    root.mkdir()
    report = {
        "spec": {"name": "positional-seeds0-4", "heldout": 200},
        "arms": [
            _arm(MODEL, {}, [0, 1, 2, 3], 0.9875, [0.96, 1.0]),  # seed 4 crashed
            _arm(MODEL, {"max_kl": 0.02}, [0, 1, 2, 3, 4], 0.5, [0.4, 0.6]),  # not shipped
            _arm("il-gaussian-positional", {}, [], None, []),  # every seed crashed
        ],
    }
    (root / "report.json").write_text(json.dumps(report))
    return root


def test_load_sweep_reads_the_arms_without_overrides(sweep_dir: Path) -> None:
    sweep = load_sweep(sweep_dir)
    assert sweep.name == "positional-seeds0-4" and sweep.heldout_episodes == 200
    assert set(sweep.arms) == {MODEL, "il-gaussian-positional"}
    assert sweep.arms[MODEL].cells() == ("4 (1 crashed)", "98.8 % [96.0, 100.0]")
    assert sweep.arms["il-gaussian-positional"].cells() == ("0", "–")


@pytest.mark.parametrize(
    ("make", "why"),
    [
        (lambda d: d / "nope", "no such folder"),
        (lambda d: d, "no report.json\\)"),
        (lambda d: (d / "trials.json").write_text("[]") and d, "run usvsim sweep --report-only"),
        (lambda d: (d / "report.json").write_text("{") and d, "report.json unreadable"),
        (lambda d: (d / "report.json").write_text('{"arms": []}') and d, "unreadable: KeyError"),
    ],
)
def test_a_folder_that_is_no_sweep_is_refused_in_one_line(
    tmp_path: Path, make: Any, why: str
) -> None:
    folder = make(tmp_path)
    with pytest.raises(UserError, match=why) as err:
        load_sweep(folder)
    assert str(err.value).startswith(f"--sweep {folder}: not a sweep folder")
    assert "\n" not in str(err.value)


def test_bench_refuses_a_non_sweep_before_it_runs(tmp_path: Path, capsys: Any) -> None:
    out = tmp_path / "bench"
    assert main(["bench", "--sweep", str(tmp_path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"usvsim bench: --sweep {tmp_path}: not a sweep folder (no report.json); "
                   "give a usvsim sweep --out"]  # fmt: skip
    assert not (out / "bench.md").exists()  # nothing evaluated


def test_bench_shows_the_sweep_beside_the_shipped_model(
    sweep_dir: Path, tmp_path: Path, capsys: Any
) -> None:
    argv = ["bench", "--helmsmen", f"straight,{SHIPPED}", "--heldout", "5", "--no-likeness"]
    argv += ["--no-plots", "--out", str(tmp_path / "bench"), "--sweep", str(sweep_dir)]
    assert main(argv) == 0
    lines = capsys.readouterr().out.splitlines()
    header = next(line for line in lines if line.startswith("helmsman"))
    assert re.search(rf"{SWEEP_HEADER[0]} +{re.escape(SWEEP_HEADER[1])}$", header), header
    splits = ("validation", "held-out")  # a row: helmsman, what it perceives (words), split, ...
    rows = {(line.split()[0], next(w for w in line.split() if w in splits)): line
            for line in lines if set(line.split()) & set(splits)}  # fmt: skip
    assert rows[(SHIPPED, "held-out")].endswith("4 (1 crashed)  98.8 % [96.0, 100.0]")
    for key in ((SHIPPED, "validation"), ("straight", "validation"), ("straight", "held-out")):
        assert "crashed" not in rows[key] and "98.8" not in rows[key], key
    assert f"shown for {SHIPPED}" in lines[-2]

    assert main([*argv, "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["sweep"]["heldout_episodes"] == 200
    assert {a["setup"]: a["heldout_iqm"] for a in payload["sweep"]["arms"]} == {
        MODEL: 0.9875,
        "il-gaussian-positional": None,
    }
    assert len(payload["rows"]) == 4  # the bench's own rows unchanged


def test_sweep_needs_the_study_suite(sweep_dir: Path) -> None:
    from usvsim.evaluation.bench import BenchArgs

    with pytest.raises(UserError, match="--sweep goes with the pole scenario"):
        BenchArgs(sweep=str(sweep_dir), scenario="waypoints").check()
