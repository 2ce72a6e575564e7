"""benchmarks/colreg_seed_scores.py: kept records are read back, and a set counts as won only
where a label's lower bound is above every baseline's upper bound."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest

_SPEC = importlib.util.spec_from_file_location(
    "colreg_seed_scores",
    Path(__file__).resolve().parents[3] / "benchmarks" / "colreg_seed_scores.py",
)
assert _SPEC is not None and _SPEC.loader is not None
seeds = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(seeds)


def _flat(name: str, successes: int, compliant: int, n: int = 40) -> dict[str, Any]:
    return {"episode_set": name, "episodes": n, "successes": successes, "collisions": 0,
            "encounters": n, "compliant": compliant}  # fmt: skip


def _record(label: str, rows: list[dict[str, Any]]) -> dict[str, Any]:
    return {"variant": label, "test": {"per_set": rows}}


def test_a_set_is_won_only_outside_every_baselines_interval() -> None:
    runs = [
        _record("il", [_flat("a", 20, 40), _flat("b", 40, 20)]),
        _record("il", [_flat("a", 20, 40), _flat("b", 40, 20)]),
    ]
    baselines = {
        "vo-radar": {"per_set": [_flat("a", 20, 10), _flat("b", 20, 20)]},
        "sb-mpc-radar": {"per_set": [_flat("a", 20, 30), _flat("b", 40, 20)]},
    }
    table = {e["set"]: e for e in seeds.per_set_comparison(runs, baselines)}
    assert table["a"]["rows"]["il"]["compliance"][0] == 1.0  # 80 of 80 pooled over seeds
    assert table["a"]["beats"] == [["il", "compliance"]]  # 80/80 against 10/40 and 30/40
    assert table["b"]["beats"] == []  # success ties with sb-mpc-radar's 40/40
    assert seeds.per_set_comparison(runs, {})[0]["beats"] == []


def test_a_kept_record_is_read_without_checkpoints_only_for_the_same_scoring(
    tmp_path: Path,
) -> None:
    args = seeds.parse(["--runs", f"x={tmp_path}", "--sets", "imazu-01"])
    scoring = {k: getattr(args, k) for k in seeds.SCORING}
    (tmp_path / "summary.json").write_text(json.dumps({"interrupted": False, "seed": 2}))
    kept = {"variant": "all", "seed": 2, "test": {}, "scoring": scoring}
    (tmp_path / "scores.json").write_text(json.dumps(kept))
    record = seeds.seed_record("rl-radar", tmp_path, args)
    assert record["variant"] == "rl-radar" and record["seed"] == 2 and "scoring" not in record
    other = seeds.parse(["--runs", f"x={tmp_path}", "--sets", "imazu-02"])
    with pytest.raises(SystemExit, match=r"no best\.pt or latest\.pt"):
        seeds.seed_record("rl-radar", tmp_path, other)


def test_a_kept_record_of_a_run_since_resumed_is_not_read(tmp_path: Path) -> None:
    """A run folder copied and resumed keeps the old ``scores.json``: its wall-clock is no
    longer the summary's, so the record is stale and the seed is scored again."""
    args = seeds.parse(["--runs", f"x={tmp_path}", "--sets", "imazu-01"])
    scoring = {k: getattr(args, k) for k in seeds.SCORING}
    kept = {"variant": "all", "seed": 2, "test": {}, "train_wall_s": 2055.0, "scoring": scoring}
    (tmp_path / "scores.json").write_text(json.dumps(kept))
    summary = {"interrupted": False, "seed": 2, "wall_time_s": 2055.0}
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    assert seeds.seed_record("rl-radar", tmp_path, args)["seed"] == 2  # the same run: read
    (tmp_path / "summary.json").write_text(json.dumps({**summary, "wall_time_s": 4079.0}))
    with pytest.raises(SystemExit, match=r"no best\.pt or latest\.pt"):
        seeds.seed_record("rl-radar", tmp_path, args)


def test_runs_are_required() -> None:
    with pytest.raises(SystemExit):
        seeds.parse(["--baselines", "vo-radar"])
