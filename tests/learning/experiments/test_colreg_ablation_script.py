"""benchmarks/colreg_reward_ablation.py's runs across sessions: ``--train-only`` trains each
variant and seed once, goes on from ``latest.pt`` where a run was cut off, and scores nothing."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import pytest

_SPEC = importlib.util.spec_from_file_location(
    "colreg_reward_ablation",
    Path(__file__).resolve().parents[3] / "benchmarks" / "colreg_reward_ablation.py",
)
assert _SPEC is not None and _SPEC.loader is not None
ablation = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(ablation)


def test_train_only_resumes_cut_runs_and_skips_finished_ones(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[dict[str, Any]] = []

    def fake_train(setup: Any, out: Path, **kw: Any) -> None:
        calls.append({"setup": setup, "out": Path(out), **kw})

    monkeypatch.setattr(ablation, "train_rl", fake_train)
    monkeypatch.setattr(ablation, "score", lambda *a: pytest.fail("--train-only scores nothing"))
    done, cut = tmp_path / "all" / "seed0", tmp_path / "all" / "seed1"
    done.mkdir(parents=True)
    (done / "summary.json").write_text(json.dumps({"interrupted": False, "wall_time_s": 9.0}))
    cut.mkdir(parents=True)
    (cut / "latest.pt").write_bytes(b"")
    (cut / "summary.json").write_text(json.dumps({"interrupted": True, "wall_time_s": 3.0}))
    argv = "--train-only --variants all,none --seeds 0,1 --iterations 7 --device torch-cpu"
    ablation.main([*argv.split(), "--out", str(tmp_path)])
    trained = {(c["out"].parent.name, c["out"].name): c for c in calls}
    assert sorted(trained) == [("all", "seed1"), ("none", "seed0"), ("none", "seed1")]
    assert trained["all", "seed1"]["resume"] is True
    assert trained["none", "seed0"]["resume"] is False
    assert all(c["iterations"] == 7 and c["device"] == "torch-cpu" for c in calls)
    assert trained["none", "seed1"]["setup"].colreg_reward == ""
    assert trained["all", "seed1"]["setup"].colreg_reward == "all"
    assert not (tmp_path / "ablation.json").exists()


def test_train_only_and_score_only_together_are_refused() -> None:
    with pytest.raises(SystemExit, match="choose one"):
        ablation.parse(["--train-only", "--score-only"])


def _run(variant: str, seed: int, success: list[float], compliance: list[float | None]) -> dict:
    rates = zip(success, compliance, strict=True)
    per_set = [{"success_rate": s, "compliance_rate": c} for s, c in rates]
    return {"variant": variant, "seed": seed, "colreg_reward": "all", "chosen": "best.pt",
            "train_wall_s": 1.0, "test": {"success_rate": 0.9, "success_ci95": [0.8, 1.0],
                                          "compliance_rate": 0.5, "compliance_ci95": [0.4, 0.6],
                                          "collisions": seed, "per_set": per_set}}  # fmt: skip


def test_across_seeds_gives_each_variant_its_iqm_and_interval() -> None:
    """Three seeds of `all`: the IQM over seeds of the per-set rates (with 3 seeds the mean),
    compliance only over the sets every seed met an encounter in; one seed: no row."""
    runs = [
        _run("all", 0, [1.0, 0.8], [0.5, None]),
        _run("all", 1, [0.9, 0.7], [0.7, 0.2]),
        _run("all", 2, [0.8, 0.6], [0.6, 0.9]),
        _run("none", 0, [0.5, 0.5], [0.1, 0.1]),
    ]
    rows = ablation.across_seeds(runs)
    assert [r["variant"] for r in rows] == ["all"]
    row = rows[0]
    assert row["seeds"] == [0, 1, 2] and row["collisions"] == 3
    assert row["success_rate"] == pytest.approx(0.8)  # mean of the six per-set rates
    assert row["compliance_rate"] == pytest.approx(0.6)  # the first set only
    low, high = row["success_rate_ci95"]
    assert 0.6 <= low <= 0.8 <= high <= 1.0
    args = ablation.parse(["--out", "/tmp/unused"])
    table = ablation.markdown(runs, args)
    assert "| all | 0,1,2 | 80 % [" in table and "| none | 0 |" in table


def test_a_finished_runs_scores_are_kept_and_read_back_without_its_checkpoints(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run = tmp_path / "all" / "seed0"
    run.mkdir(parents=True)
    (run / "summary.json").write_text(json.dumps({"interrupted": False, "wall_time_s": 9.0}))
    for name in ("best.pt", "latest.pt"):
        (run / name).write_bytes(b"")
    scored: list[tuple[str, str]] = []

    def fake_score(path: Path, args: Any, split: str, n: int) -> dict[str, Any]:
        scored.append((path.name, split))
        rate = 0.9 if path.name == "latest.pt" else 0.5
        return {"success_rate": rate, "compliance_rate": 0.5, "per_set": []}

    monkeypatch.setattr(ablation, "score", fake_score)
    args = ablation.parse(["--score-only", "--out", str(tmp_path)])
    first = ablation.run_one("all", 0, args)
    assert first["chosen"] == "latest.pt" and first["train_wall_s"] == 9.0
    assert sorted(scored) == [("best.pt", "validation"), ("latest.pt", "test"),
                              ("latest.pt", "validation")]  # fmt: skip
    for name in ("best.pt", "latest.pt"):
        (run / name).unlink()  # a later session: only the small files were kept
    assert ablation.run_one("all", 0, args) == first and len(scored) == 3
    other = ablation.parse(["--score-only", "--test-episodes", "20", "--out", str(tmp_path)])
    with pytest.raises(SystemExit, match=r"no best\.pt or latest\.pt"):
        ablation.run_one("all", 0, other)  # other scoring: the kept record does not serve
