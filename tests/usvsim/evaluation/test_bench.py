"""usvsim bench and the helmsman registry: JSON output, CLI conventions, atomic results."""

from __future__ import annotations

import argparse
import json
import sys
import types
from pathlib import Path

import pytest

from usvsim.cli.args import add_dataclass_arguments as _add_dataclass_arguments
from usvsim.cli.args import field_comments as _field_comments
from usvsim.cli.bench import run_bench_command as run
from usvsim.common import fileio
from usvsim.common.errors import UserError
from usvsim.evaluation import bench
from usvsim.evaluation.bench import BenchArgs, run_bench, write_results
from usvsim.evaluation.model_cards import default_helmsmen
from usvsim.helm.protocol import RandomHelmsman, StraightAheadHelmsman
from usvsim.helm.registry import available_helmsmen, make_helmsman, select_helmsmen


def test_registry_lists_the_baselines(tmp_path: Path) -> None:
    helmsmen = available_helmsmen(tmp_path)
    assert list(helmsmen) == ["los", "los-avoid", "vo", "sb-mpc", "vo-radar", "sb-mpc-radar"]
    h = helmsmen["los-avoid"]()
    assert (h.observation, h.action) == ("positional", "gaussian")  # type: ignore[attr-defined]
    vo = helmsmen["vo"]()
    assert (vo.observation, vo.action) == ("scene", "gaussian")  # type: ignore[attr-defined]
    vo_radar = helmsmen["vo-radar"]()
    assert vo_radar.observation == "radar+nav"  # type: ignore[attr-defined]
    sbmpc_radar = helmsmen["sb-mpc-radar"]()
    assert sbmpc_radar.observation == "radar+nav"  # type: ignore[attr-defined]


def test_make_helmsman_knows_every_kind_of_name(tmp_path: Path) -> None:
    assert isinstance(make_helmsman("straight", "categorical"), StraightAheadHelmsman)
    assert isinstance(make_helmsman("random"), RandomHelmsman)
    assert type(make_helmsman("los-avoid")).__name__ == "AvoidHelmsman"
    with pytest.raises(ValueError, match=r"unknown helmsman 'nope'; choose straight, random, los"):
        make_helmsman("nope")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a model")
    with pytest.raises(ValueError, match=r"bad\.pt"):
        make_helmsman(str(bad))


def test_registry_loads_models_with_the_checkpoint_module(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "trpo-positional.pt").write_bytes(b"weights")
    loaded: list[Path] = []
    fake = types.ModuleType("learning.experiments.checkpoint")

    def load_helmsman(path: Path) -> str:
        loaded.append(path)
        return "helmsman"

    fake.load_helmsman = load_helmsman  # type: ignore[attr-defined]
    fake.CheckpointError = ValueError  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "learning.experiments.checkpoint", fake)
    helmsmen = available_helmsmen(tmp_path)
    baselines = ["los", "los-avoid", "vo", "sb-mpc", "vo-radar", "sb-mpc-radar"]
    assert list(helmsmen) == [*baselines, "trpo-positional"]
    assert helmsmen["trpo-positional"]() == "helmsman" and loaded == [
        tmp_path / "trpo-positional.pt"
    ]


def test_bench_args_follow_the_cli_conventions() -> None:
    comments = _field_comments(BenchArgs)
    assert set(comments) == {
        "scenario",
        "helmsmen",
        "heldout",
        "out",
        "json",
        "plots",
        "likeness",
        "suite",
        "sets",
        "stress_episodes",
        "split",
        "colreg_episodes",
        "reactive_targets",
        "trafficgen",
        "sweep",
        "threads",
    }
    assert all(comments.values())
    parser = argparse.ArgumentParser()
    _add_dataclass_arguments(parser, BenchArgs)
    args = BenchArgs(
        **vars(parser.parse_args(["--scenario", "waypoints", "--json", "--heldout", "7"]))
    )
    assert args == BenchArgs(scenario="waypoints", json=True, heldout=7)
    assert BenchArgs(**vars(parser.parse_args([]))) == BenchArgs()


def test_literal_fields_accept_only_their_values(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser()
    _add_dataclass_arguments(parser, BenchArgs)
    with pytest.raises(SystemExit) as exit_info:
        parser.parse_args(["--scenario", "pools"])
    assert exit_info.value.code == 2
    assert "invalid choice: 'pools' (choose from" in capsys.readouterr().err
    assert bench.SCENARIOS == ("pole", "waypoints")


def test_bench_json_parses_and_has_every_default_helmsman(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run(BenchArgs(json=True, heldout=20, out=str(tmp_path), plots=False)) == 0
    payload = json.loads(capsys.readouterr().out)  # stdout holds the JSON and nothing else
    rows = payload["rows"]
    default = set(select_helmsmen(default_helmsmen()))  # baselines + recommended models
    assert {r["helmsman"] for r in rows} == default
    assert {(r["helmsman"], r["episode_set"]) for r in rows} == {
        (h, s) for h in default for s in ("validation", "held-out")
    }
    assert payload["episode_sets"] == {"validation": 15, "held-out": 20}
    avoid = next(
        r for r in rows if r["helmsman"] == "los-avoid" and r["episode_set"] == "validation"
    )
    assert avoid["successes"] == 15 and avoid["success_ci95_low"] == pytest.approx(0.7961, abs=1e-4)
    los = next(r for r in rows if r["helmsman"] == "los" and r["episode_set"] == "validation")
    assert los["successes"] == 0 and los["time_to_goal_mean_s"] is None  # NaN → null
    assert sorted(Path(f).name for f in payload["files"]) == ["bench.csv", "bench.md"]


def test_bench_writes_table_and_a_path_plot_per_helmsman_and_set(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = BenchArgs(scenario="waypoints", heldout=3, out=str(tmp_path), helmsmen="los,los-avoid")
    assert run(args) == 0
    printed = capsys.readouterr().out
    assert "los-avoid" in printed and "success [95 % CI]" in printed
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(
        ["bench-waypoints.md", "bench-waypoints.csv"]
        + [
            f"paths-waypoints-{h}-{s}.png"
            for h in ("los", "los-avoid")
            for s in ("validation", "held-out")
        ]
    )
    md = (tmp_path / "bench-waypoints.md").read_text()
    assert md.count("| los-avoid |") == 2 and md.count("| los |") == 2


def test_interrupted_write_leaves_the_old_results_and_no_temporary_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    old = run_bench(BenchArgs(helmsmen="los", heldout=5), progress=False)
    write_results(old, tmp_path, plots=False)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    new = run_bench(BenchArgs(helmsmen="los,los-avoid", heldout=5), progress=False)

    def interrupted(fd: int) -> None:  # the new text is half on disk when the user hits Ctrl-C
        raise KeyboardInterrupt

    monkeypatch.setattr(fileio.os, "fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_results(new, tmp_path, plots=False)
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert after == before  # old files intact, no temporary files left beside them
    monkeypatch.undo()
    write_results(new, tmp_path, plots=False)
    assert "los-avoid" in (tmp_path / "bench.md").read_text()


def test_unknown_helmsman_or_scenario_is_an_error() -> None:
    with pytest.raises(UserError, match="unknown helmsman 'nobody'; choose straight"):
        run_bench(BenchArgs(helmsmen="nobody"), progress=False)
    with pytest.raises(UserError, match="--scenario"):
        run_bench(BenchArgs(scenario="docking"), progress=False)
    assert bench.SCENARIOS == ("pole", "waypoints")
