"""usvsim bench's helmsman selection: paths and names alike, duplicates once, a corrupt shipped
model skipped with a warning, results written as one unit and marked when interrupted."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from usvsim.common.errors import UserError
from usvsim.evaluation import bench
from usvsim.evaluation.bench import BenchArgs, run_bench, to_json, write_results
from usvsim.helm import registry
from usvsim.helm.registry import MODELS_DIR, select_helmsmen

MODEL = MODELS_DIR / "positional-gaussian-trpo-study.pt"


def test_names_and_paths_alike_duplicates_once(tmp_path: Path) -> None:
    mine = tmp_path / "my-run" / "best.pt"
    mine.parent.mkdir()
    shutil.copy(MODEL, mine)
    chosen = select_helmsmen(["los", str(mine), "los", "straight", str(mine)])
    assert list(chosen) == ["los", "best", "straight"]
    assert type(chosen["best"]()).__name__ == "PolicyHelmsman"
    other = tmp_path / "other" / "best.pt"
    other.parent.mkdir()
    shutil.copy(MODEL, other)
    with pytest.raises(UserError, match="would share the label 'best'"):
        select_helmsmen([str(mine), str(other)])


def test_duplicated_helmsman_gives_one_row_per_set() -> None:
    result = run_bench(BenchArgs(helmsmen="los,los", heldout=3, likeness=False), progress=False)
    assert [(r.helmsman, r.episode_set) for r in result.rows] == [
        ("los", "validation"),
        ("los", "held-out"),
    ]


def test_a_corrupt_shipped_model_is_skipped_not_fatal(tmp_path, monkeypatch, capsys) -> None:
    (tmp_path / "broken.pt").write_bytes(b"\x00" * 100)
    monkeypatch.setattr(registry, "MODELS_DIR", tmp_path)
    result = run_bench(BenchArgs(heldout=3, likeness=False), progress=False)
    baselines = {"los", "los-avoid", "vo", "sb-mpc", "vo-radar", "sb-mpc-radar"}
    assert {r.helmsman for r in result.rows} == baselines
    perceives = {r.helmsman: r.perceives for r in result.rows}
    assert perceives["vo-radar"] == perceives["sb-mpc-radar"] == "radar tracks"
    assert len(result.skipped) == 1 and result.skipped[0].startswith("broken: ")
    assert "usvsim bench: skipping broken:" in capsys.readouterr().err
    with pytest.raises(UserError, match="--helmsmen broken"):  # named: an error
        run_bench(BenchArgs(helmsmen="broken", heldout=3), progress=False)


def test_interrupted_bench_keeps_the_finished_sets(monkeypatch, tmp_path: Path) -> None:
    calls = []
    real = bench.summarize_set

    def summarize_then_interrupt(*args, **kwargs):
        calls.append(args[1])
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(bench, "summarize_set", summarize_then_interrupt)
    args = BenchArgs(helmsmen="los,los-avoid", heldout=3, likeness=False)
    result = run_bench(args, progress=False)
    assert result.interrupted and [r.episode_set for r in result.rows] == ["validation"]
    files = write_results(result, tmp_path, plots=False)
    assert "(interrupted" in (tmp_path / "bench.md").read_text().splitlines()[0]
    assert '"interrupted": true' in to_json(result, [str(f) for f in files])


def test_results_replace_the_older_set_as_one_unit(tmp_path: Path) -> None:
    stale = tmp_path / "paths-nobody-validation.png"  # a plot of an older, bigger run
    stale.write_bytes(b"old")
    (tmp_path / ".bench.md.abc.tmp").write_text("left by a killed writer")
    (tmp_path / ".staging-bench").mkdir()
    (tmp_path / "notes.txt").write_text("the user's")
    result = run_bench(BenchArgs(helmsmen="los", heldout=3, likeness=False), progress=False)
    write_results(result, tmp_path, plots=True)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [
        "bench.csv",
        "bench.md",
        "notes.txt",
        "paths-los-held-out.png",
        "paths-los-validation.png",
    ]
