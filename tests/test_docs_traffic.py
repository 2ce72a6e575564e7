"""docs/hooks/gen_traffic.py: the "Training in traffic" page's generated tables follow the code."""

from __future__ import annotations

import importlib.util
from dataclasses import fields
from pathlib import Path

_SPEC = importlib.util.spec_from_file_location(
    "gen_traffic", Path(__file__).resolve().parents[1] / "docs" / "hooks" / "gen_traffic.py"
)
assert _SPEC is not None and _SPEC.loader is not None
gen_traffic = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(gen_traffic)


def test_the_weights_table_has_every_field_with_its_default_and_comment() -> None:
    from usvsim.task.colreg_reward import COLREG_TERMS, ColregRewardWeights

    table = gen_traffic.reward_weights_markdown()
    w = ColregRewardWeights()
    names = [f.name for f in fields(w) if f.name != "params"]
    assert set(COLREG_TERMS) <= set(names)
    for name in names:
        row = next(line for line in table.splitlines() if line.startswith(f"| `{name}`"))
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert float(cells[1]) == getattr(w, name) and cells[2]  # default, unit/source comment
    assert len(table.splitlines()) == 2 + len(names)


def test_the_setups_table_lists_every_colreg_setup() -> None:
    from learning.experiments.il_setups import IL_SETUPS
    from learning.experiments.setups import SETUPS

    table = gen_traffic.traffic_setups_markdown()
    expected = [n for n in (*SETUPS, *IL_SETUPS) if "colreg" in n]
    assert len(expected) >= 7
    for name in expected:
        assert f"| `{name}` |" in table
    assert len(table.splitlines()) == 2 + len(expected)


def test_the_likeness_table_renders_the_committed_json() -> None:
    table = gen_traffic.likeness_table()
    assert gen_traffic.LIKENESS_JSON.is_file()
    assert "| sb-mpc (expert) |" in table and not table.startswith("#")
