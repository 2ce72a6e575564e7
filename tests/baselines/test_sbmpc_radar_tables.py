"""sb-mpc-radar's published rows: merged into the committed data by benchmarks/stress_merge.py
and benchmarks/colreg_table.py --merge, which add a later run's helmsmen without running the
others again and refuse a run whose shared helmsmen disagree with the file."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
ORDER = ["los", "vo", "sb-mpc", "vo-radar", "sb-mpc-radar"]


def _script(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _row(helmsman: str, episode_set: str, successes: int) -> dict:
    return {"helmsman": helmsman, "episode_set": episode_set, "successes": successes, "wall_s": 1.0}


def _run(helmsmen: list[str], rows: list[dict]) -> dict:
    return {"suite": "stress", "split": "test", "sets": ["a", "b"], "episodes_per_set": 100,
            "helmsmen": helmsmen, "rows": rows, "wall_s": 60.0}  # fmt: skip


def test_stress_merge_adds_rows_after_the_helmsman_before_it() -> None:
    merge = _script("stress_merge").merge
    base = _run(["vo", "vo-radar", "model"],
                [_row(h, s, 90) for s in "ab" for h in ("vo", "vo-radar", "model")])  # fmt: skip
    new = _run(
        ["vo", "sb-mpc-radar"], [_row(h, s, 90) for s in "ab" for h in ("vo", "sb-mpc-radar")]
    )
    new["rows"][0]["wall_s"] = 9.0  # timing may differ, counts may not
    assert merge(base, new, ORDER) == ["sb-mpc-radar"]
    assert base["helmsmen"] == ["vo", "vo-radar", "sb-mpc-radar", "model"]
    assert [(r["episode_set"], r["helmsman"]) for r in base["rows"]][:4] == [
        ("a", "vo"), ("a", "vo-radar"), ("a", "sb-mpc-radar"), ("a", "model"),
    ]  # fmt: skip
    assert base["merged"] == [
        {"helmsmen": ["sb-mpc-radar"], "run_helmsmen": ["vo", "sb-mpc-radar"], "wall_s": 60.0}
    ]
    other = _run(["vo", "sb-mpc"], [_row("vo", "a", 89), _row("vo", "b", 90)])
    with pytest.raises(SystemExit, match="vo on a differs"):
        merge(base, other, ORDER)


def test_stress_merge_replace_sets_swaps_one_sets_rows_for_every_helmsman() -> None:
    replace_sets = _script("stress_merge").replace_sets
    base = _run(["vo", "old-name"], [_row(h, s, 90) for s in "ab" for h in ("vo", "old-name")])
    new = _run(["vo", "new-name"], [_row("vo", "b", 70), _row("new-name", "b", 60)])
    replace_sets(base, new, ["b"], {"old-name": "new-name"})
    assert [(r["episode_set"], r["helmsman"], r["successes"]) for r in base["rows"]] == [
        ("a", "vo", 90), ("a", "old-name", 90), ("b", "vo", 70), ("b", "old-name", 60),
    ]  # fmt: skip
    assert base["replaced"] == [{"sets": ["b"], "wall_s": 60.0}]
    with pytest.raises(SystemExit, match="no row for old-name on b"):
        replace_sets(base, new, ["b"], {})
    with pytest.raises(SystemExit, match="not sets of the file"):
        replace_sets(base, new, ["c"], {})


def test_stress_merge_replace_helmsmen_swaps_one_helmsmans_rows_on_every_set() -> None:
    replace_helmsmen = _script("stress_merge").replace_helmsmen
    base = _run(["vo", "model"], [_row(h, s, 90) for s in "ab" for h in ("vo", "model")])
    new = _run(["model"], [_row("model", "a", 70), _row("model", "b", 60)])
    replace_helmsmen(base, new, ["model"])
    assert [(r["episode_set"], r["helmsman"], r["successes"]) for r in base["rows"]] == [
        ("a", "vo", 90), ("a", "model", 70), ("b", "vo", 90), ("b", "model", 60),
    ]  # fmt: skip
    assert base["replaced"] == [{"helmsmen": ["model"], "wall_s": 60.0}]
    with pytest.raises(SystemExit, match="no row for vo on a"):
        replace_helmsmen(base, new, ["vo"])
    with pytest.raises(SystemExit, match="not helmsmen of the file"):
        replace_helmsmen(base, new, ["other"])
    with pytest.raises(SystemExit, match="differ in split"):
        replace_helmsmen(base, {**new, "split": "validation"}, ["model"])


def test_stress_merge_replace_helmsmen_takes_the_study_bench_json_without_a_helmsmen_list() -> None:
    replace_helmsmen = _script("stress_merge").replace_helmsmen
    rows = [_row(h, s, 10) for s in ("validation", "held-out") for h in ("vo", "model")]
    base = {"scenario": "pole", "rows": rows}
    new = {"scenario": "pole", "rows": [_row("model", "validation", 12)], "wall_s": 3.0}
    with pytest.raises(SystemExit, match="no row for model on held-out"):
        replace_helmsmen(base, new, ["model"])
    new["rows"].append(_row("model", "held-out", 150))
    replace_helmsmen(base, new, ["model"])
    assert [(r["episode_set"], r["helmsman"], r["successes"]) for r in base["rows"]] == [
        ("validation", "vo", 10), ("validation", "model", 12),
        ("held-out", "vo", 10), ("held-out", "model", 150),
    ]  # fmt: skip
    assert base["replaced"] == [{"helmsmen": ["model"], "wall_s": 3.0}]


def test_colreg_table_merge_adds_a_row_and_a_column_and_refuses_a_changed_row() -> None:
    merge_block = _script("colreg_table").merge_block
    old = "head\n\n| helmsman | x |\n|---|---|\n| `vo` | 1 |\n| `vo-radar` | 2 |\n| `m` | 3 |\n"
    new = "other head\n\n| helmsman | x |\n|---|---|\n| `vo` | 1 |\n| `sb-mpc-radar` | 4 |\n"
    merged = merge_block(old, new, "{} merged", ORDER)
    assert merged == (
        "head\n\n| helmsman | x |\n|---|---|\n| `vo` | 1 |\n| `vo-radar` | 2 |\n"
        "| `sb-mpc-radar` | 4 |\n| `m` | 3 |\n\n`sb-mpc-radar` merged\n"
    )
    assert merge_block(merged, new, "{} merged", ORDER) == merged  # nothing new: unchanged
    cols_old = "| problem | `vo` | `sb-mpc` |\n|---|---|---|\n| p1 | 1 | 2 |\n"
    cols_new = "| problem | `sb-mpc` | `sb-mpc-radar` |\n|---|---|---|\n| p1 | 2 | 5 |\n"
    assert merge_block(cols_old, cols_new, "{}", ORDER, columns=True).splitlines()[:3] == [
        "| problem | `vo` | `sb-mpc` | `sb-mpc-radar` |",
        "|---|---|---|---|",
        "| p1 | 1 | 2 | 5 |",
    ]
    with pytest.raises(SystemExit, match="vo: the new run's row differs"):
        merge_block(old, new.replace("| `vo` | 1 |", "| `vo` | 7 |"), "{}", ORDER)
    changed = "| helmsman | x |\n|---|---|\n| `m` | 9 |\n"
    assert merge_block(old, changed, "{} replaced", ORDER, replace=True) == (
        "head\n\n| helmsman | x |\n|---|---|\n| `vo` | 1 |\n| `vo-radar` | 2 |\n| `m` | 9 |\n"
        "\n`m` replaced\n"
    )


def test_colreg_table_replace_keeps_one_note_per_replaced_row() -> None:
    merge_block = _script("colreg_table").merge_block
    note = "{} replaced (`benchmarks/colreg_table.py --replace`; run %d)."
    old = "| helmsman | x |\n|---|---|\n| `m` | 3 |\n| `n` | 4 |\n"
    once = merge_block(old, "| helmsman | x |\n|---|---|\n| `m` | 5 |\n", note % 1, ORDER,
                       replace=True)  # fmt: skip
    twice = merge_block(once, "| helmsman | x |\n|---|---|\n| `n` | 6 |\n", note % 2, ORDER,
                        replace=True)  # fmt: skip
    thrice = merge_block(twice, "| helmsman | x |\n|---|---|\n| `m` | 7 |\n", note % 3, ORDER,
                         replace=True)  # fmt: skip
    notes = [ln for ln in thrice.splitlines() if "replaced" in ln]
    assert notes == [
        "`m` replaced (`benchmarks/colreg_table.py --replace`; run 3).",
        "`n` replaced (`benchmarks/colreg_table.py --replace`; run 2).",
    ]
    assert "| `m` | 7 |" in thrice and "| `n` | 6 |" in thrice and "\n\n\n" not in thrice


def test_committed_data_and_page_hold_the_same_sb_mpc_radar_rows() -> None:
    stress = json.loads((ROOT / "docs" / "data" / "stress.json").read_text())
    helmsmen = stress["helmsmen"]
    assert helmsmen.index("sb-mpc-radar") == helmsmen.index("vo-radar") + 1
    rows = [r for r in stress["rows"] if r["helmsman"] == "sb-mpc-radar"]
    assert [r["episode_set"] for r in rows] == stress["sets"] and len(rows) == 22
    assert all(r["episodes"] == 100 and r["perceives"] == "radar tracks" for r in rows)
    page = (ROOT / "docs" / "guide" / "colreg-suite.md").read_text()
    table = _script("colreg_table").stress_table(stress)
    row = next(ln for ln in table.splitlines() if ln.startswith("| `sb-mpc-radar` |"))
    assert row in page


def test_reship_docs_sets_one_models_column_and_row_and_a_whole_table() -> None:
    docs = _script("reship_docs")
    text = (
        "intro\n\n| set | vo-radar | m | n |\n|---|---|---|---|\n| a | 100 | 90 | 80 |\n"
        "| b | 99 | 70 | 60 |\n\nafter\n\n| helmsman | x |\n|---|---|\n| m | old |\n| n | keep |\n"
    )
    text = docs.set_column(text, "| set | vo-radar |", "m", {"a": "91", "c": "5"})
    assert "| a | 100 | 91 | 80 |" in text and "| b | 99 | 70 | 60 |" in text
    assert docs.set_column(text, "| set | vo-radar |", "absent", {"a": "1"}) == text
    text = docs.set_row(text, "| helmsman | x |", "| m | new |")
    assert "| m | new |\n| n | keep |" in text
    text = docs.set_table(text, "| helmsman | x |", "| helmsman | y |\n|---|---|\n| z | 1 |\n")
    assert text.endswith("after\n\n| helmsman | y |\n|---|---|\n| z | 1 |\n")
    with pytest.raises(SystemExit, match="no table"):
        docs.set_row(text, "| nothing |", "| m | 1 |")
