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
