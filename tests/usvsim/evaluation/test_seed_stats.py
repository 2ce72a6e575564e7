"""Across-seed figures of a recommended setup (:mod:`usvsim.evaluation.seed_stats`): the IQM of
3 seeds is their mean, rliable's interval contains it, the rule picks the median validation seed
from validation figures only, the committed file agrees with its own per-seed figures, and the
columns appear only for shipped models whose setup has seed figures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from usvsim.cli.main import main
from usvsim.common.errors import UserError
from usvsim.evaluation.model_cards import cards_json, cards_table, load_cards
from usvsim.evaluation.seed_stats import (
    SEEDS_DIR,
    SeedTable,
    iqm,
    load_seed_tables,
    pick_seed,
    seed_table,
    seed_tables_for,
    with_seed_columns,
)

pytest.importorskip("rliable")

SETS = ["study", "two-obstacles", "gusts"]  # gusts: a weather set, not one of the 22 originals
TEST = {  # seed -> success per set (test split)
    0: [1.0, 0.90, 0.50],
    1: [0.98, 0.80, 0.60],
    2: [0.96, 0.97, 0.70],
}
VALIDATION = {0: [1.0, 0.95, 0.9], 1: [0.9, 0.9, 1.0], 2: [1.0, 1.0, 1.0]}  # means .95 .93 1.0
RENAME = {"s0": 0, "s1": 1, "s2": 2}


def _payload(split: str, rates: dict[int, list[float]], seeds: list[int]) -> dict[str, Any]:
    rows = [
        {"helmsman": f"s{seed}", "episode_set": name, "success_rate": rates[seed][j]}
        for seed in seeds
        for j, name in enumerate(SETS)
    ]
    rows.append({"helmsman": "vo", "episode_set": "study", "success_rate": 0.1})  # ignored
    return {"split": split, "sets": SETS, "episodes_per_set": 100, "rows": rows}


def _table(**kwargs: Any) -> SeedTable:
    val = [_payload("validation", VALIDATION, [0, 1]), _payload("validation", VALIDATION, [2])]
    test = [_payload("test", TEST, [0, 1]), _payload("test", TEST, [2])]
    return seed_table("setup-x", val, test, RENAME, reps=500, **kwargs)


def test_iqm_of_three_is_their_mean_and_of_four_cuts_one_each_end() -> None:
    assert iqm([0.8, 0.9, 1.0]) == pytest.approx(0.9, abs=1e-12)
    assert iqm([0.0, 0.5, 0.7, 1.0]) == pytest.approx(0.6, abs=1e-12)


def test_per_set_iqm_is_the_mean_of_three_seeds_inside_its_interval() -> None:
    table = _table()
    assert table.seeds == (0, 1, 2)
    assert [f.name for f in table.sets] == SETS
    for j, f in enumerate(table.sets):
        values = [TEST[s][j] for s in (0, 1, 2)]
        assert f.per_seed == pytest.approx(values)
        assert f.iqm == pytest.approx(np.mean(values), abs=1e-12)
        eps = 1e-9  # the bootstrap's means of equal values round
        assert min(values) - eps <= f.ci95[0] <= f.iqm <= f.ci95[1] <= max(values) + eps
        assert f.ci95[0] < f.ci95[1]  # the seeds differ on every set here


def test_original_sets_leave_the_weather_sets_out() -> None:
    table = _table()
    means = [np.mean(TEST[s][:2]) for s in (0, 1, 2)]  # study and two-obstacles only
    assert table.original.per_seed == pytest.approx(means)
    assert table.original.iqm == pytest.approx(np.mean(means))
    assert table.original.ci95[0] <= table.original.iqm <= table.original.ci95[1]


def test_rule_picks_the_median_validation_seed() -> None:
    assert _table().picked_seed == 0  # means 0.95, 0.933, 1.0: the median is seed 0's
    # on the two original sets only: 0.975, 0.9, 1.0 -> still seed 0; the weather set decides
    assert _table(rule_sets="original").validation_means[1] == pytest.approx(0.9)
    assert pick_seed({0: {"a": 0.9}, 1: {"a": 1.0}, 2: {"a": 0.8}}, ["a"]) == 0
    assert pick_seed({3: {"a": 0.5}, 1: {"a": 0.7}, 2: {"a": 0.9}, 0: {"a": 0.6}}, ["a"]) == 0
    assert pick_seed({0: {"a": 0.5}, 1: {"a": 0.5}, 2: {"a": 0.5}}, ["a"]) == 1  # ties by seed


def test_the_rule_reads_validation_only() -> None:
    test = [_payload("test", TEST, [0, 1, 2])]
    with pytest.raises(UserError, match="--validation JSON holds the test split"):
        seed_table("setup-x", test, test, RENAME, reps=50)
    with pytest.raises(UserError, match=r"no test rows for s2 \(seed 2\)"):
        seed_table("setup-x", [_payload("validation", VALIDATION, [0, 1, 2])],
                   [_payload("test", TEST, [0, 1])], RENAME, reps=50)  # fmt: skip


def test_bootstrap_is_seeded_and_leaves_numpys_generator_alone() -> None:
    state = np.random.get_state()[1].copy()  # noqa: NPY002
    a, b = _table(), _table()
    assert np.array_equal(state, np.random.get_state()[1])  # noqa: NPY002
    assert [f.ci95 for f in a.sets] == [f.ci95 for f in b.sets]


def test_table_survives_its_json(tmp_path: Path) -> None:
    table = _table(command="python benchmarks/seed_table.py ...")
    assert SeedTable.from_json(json.loads(json.dumps(table.to_json()))) == table
    (tmp_path / "bad.json").write_text('{"setup": "x"}')
    with pytest.raises(UserError, match=r"bad\.json: not a seed table"):
        load_seed_tables(tmp_path)
    assert load_seed_tables(tmp_path / "none") == {}


@pytest.mark.parametrize(
    ("setup", "picked", "start_short"),
    [
        ("il-categorical-scene-ow", 0, (0.82, 1.0, 0.83)),
        ("il-gaussian-radar-ow", 2, (0.56, 0.56, 0.51)),
        ("rl-categorical-scene-ow-ft", 1, (1.0, 1.0, 0.92)),
        ("rl-gaussian-scene-ow-ft", 2, (0.76, 0.95, 1.0)),
        ("rl-gaussian-radar-ow-cont", 0, (0.95, 0.44, 0.74)),
        ("rl-categorical-radar-ow-cont", 1, (1.0, 0.98, 0.87)),
    ],
)
def test_committed_file_agrees_with_its_per_seed_figures(
    setup: str, picked: int, start_short: tuple[float, ...]
) -> None:
    """``usvsim/models/seeds/<setup>.json`` (docs/notes/2026-12-seeds.md)."""
    table = load_seed_tables()[setup]
    assert table.seeds == (0, 1, 2) and table.split == "test" and len(table.sets) == 26
    for f in [*table.sets, table.original]:
        assert f.iqm == pytest.approx(np.mean(f.per_seed), abs=1e-9)
        assert min(f.per_seed) - 1e-9 <= f.ci95[0] <= f.iqm <= f.ci95[1] <= max(f.per_seed) + 1e-9
    means = table.validation_means
    assert table.picked_seed == sorted(means, key=lambda s: (means[s], s))[1] == picked
    assert table.figure("start-short").per_seed == start_short
    assert table.command.startswith("python benchmarks/seed_table.py --setup")


def test_columns_only_for_shipped_models_of_a_setup_with_seeds() -> None:
    shipped = next(n for n, c in load_cards().items() if c.setup == "il-categorical-scene-ow")
    tables = seed_tables_for([shipped, "vo", "rl-gaussian-scene-ow", "best"])  # no seeds there
    assert list(tables) == [shipped]

    class Row:
        def __init__(self, helmsman: str, episode_set: str) -> None:
            self.helmsman, self.episode_set = helmsman, episode_set

    rows = [Row(shipped, "start-short"), Row("vo", "start-short")]
    table = "helmsman  set\n--------  ---\na  b\nc  d"
    lines = with_seed_columns(table, rows, tables, "test").splitlines()
    assert lines[0].endswith("IQM over 3 seeds [95 % CI]")
    assert lines[2].endswith("88.3 % [82.0, 100.0]")
    assert lines[3] == "c  d"  # nothing for vo: no zeros
    assert "seed rule picks seed 0" in lines[4]
    assert with_seed_columns(table, rows, tables, "validation") == table


def test_usvsim_models_shows_the_iqm_beside_the_shipped_figure() -> None:
    cards, seeds = load_cards(), load_seed_tables()
    shipped = {c.setup: n for n, c in cards.items() if c.setup in seeds}
    assert (
        set(shipped)
        == set(seeds)
        == {
            "il-categorical-scene-ow",
            "il-gaussian-radar-ow",
            "rl-categorical-scene-ow-ft",
            "rl-gaussian-scene-ow-ft",
            "rl-gaussian-radar-ow-cont",
            "rl-categorical-radar-ow-cont",
            "rl-gaussian-positional",
            "il-categorical-positional",
            "rl-categorical-radar",
            "il-gaussian-radar",
            "il-gaussian-radar-ow-colreg",
            "rl-gaussian-radar-colreg-ilft-safe-ow-aim2-unsafe-ends",
        }
    )
    # issue 37: every recommended model's setup was trained over >= 3 seeds
    recommended = {c.setup for c in cards.values() if c.recommended}
    assert len(recommended) == 10 and recommended <= set(seeds)
    lines = cards_table(cards, seeds).splitlines()
    assert "stress test: IQM over N seeds [95 % CI]" in lines[0]
    with_iqm = [line for line in lines if "(3 seeds)" in line]
    assert sorted(line.split()[0] for line in with_iqm) == sorted(shipped.values())
    for setup, name in shipped.items():
        o = seeds[setup].original
        figure = f"{100 * o.iqm:.1f} % [{100 * o.ci95[0]:.1f}, {100 * o.ci95[1]:.1f}] (3 seeds)"
        assert figure in next(line for line in with_iqm if line.startswith(name + " "))
    assert (
        "98.0 % [97.5, 98.8] (3 seeds)"
        in lines[[ln.split()[0] for ln in lines].index(shipped["il-categorical-scene-ow"])]
    )
    payload = json.loads(cards_json(cards, seeds))
    assert sorted(payload["across_seeds"]) == sorted(shipped.values())
    assert payload["across_seeds"][shipped["il-categorical-scene-ow"]]["picked_seed"] == 0
    assert payload["across_seeds"][shipped["il-gaussian-radar-ow"]]["picked_seed"] == 2
    assert payload["across_seeds"][shipped["rl-categorical-scene-ow-ft"]]["picked_seed"] == 1
    assert payload["across_seeds"][shipped["rl-gaussian-scene-ow-ft"]]["picked_seed"] == 2
    assert payload["across_seeds"][shipped["rl-gaussian-radar-ow-cont"]]["picked_seed"] == 0
    assert payload["across_seeds"][shipped["rl-categorical-radar-ow-cont"]]["picked_seed"] == 1


def test_bench_stress_json_carries_the_seed_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shipped = next(n for n, c in load_cards().items() if c.setup == "il-categorical-scene-ow")
    argv = ["bench", "--suite", "stress", "--sets", "start-short", "--helmsmen", f"{shipped},los"]
    argv += ["--stress-episodes", "2", "--no-plots", "--out", str(tmp_path)]
    assert main([*argv, "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert list(payload["seeds"]) == [shipped]
    assert payload["seeds"][shipped]["setup"] == "il-categorical-scene-ow"
    assert main(argv) == 0
    text = capsys.readouterr().out
    row = next(line for line in text.splitlines() if line.startswith(shipped))
    assert row.rstrip().endswith("88.3 % [82.0, 100.0]")
    los = next(line for line in text.splitlines() if line.startswith("los "))
    assert "88.3 %" not in los  # nothing for a helmsman without seed figures


def test_seed_files_are_package_data() -> None:
    import tomllib

    root = Path(__file__).resolve().parents[3]
    data = tomllib.loads((root / "pyproject.toml").read_text())
    patterns = data["tool"]["setuptools"]["package-data"]["usvsim"]
    assert "models/seeds/*.json" in patterns
    assert SEEDS_DIR == root / "usvsim" / "models" / "seeds"


def _script() -> Any:
    import importlib.util

    path = Path(__file__).resolve().parents[3] / "benchmarks" / "seed_table.py"
    spec = importlib.util.spec_from_file_location("seed_table", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_seed_table_script_writes_the_file_with_its_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    files = {}
    for split, rates in (("validation", VALIDATION), ("test", TEST)):
        files[split] = tmp_path / f"{split}.json"
        files[split].write_text(json.dumps(_payload(split, rates, [0, 1, 2])))
    out = tmp_path / "seeds" / "setup-x.json"
    argv = ["--setup", "setup-x", "--validation", str(files["validation"]), "--test",
            str(files["test"]), "--rename", "s0=0,s1=1,s2=2", "--out", str(out)]  # fmt: skip
    assert _script().main(argv) == 0
    table = load_seed_tables(out.parent)["setup-x"]
    assert table.picked_seed == 0 and table.seeds == (0, 1, 2)
    assert table.command.startswith("python benchmarks/seed_table.py --setup setup-x")
    assert "rule picks seed 0" in capsys.readouterr().out
    bad = [*argv[:-4], "--rename", "s0:0", "--out", str(out)]
    assert _script().main(bad) == 2
    assert "--rename 's0:0': write LABEL=SEED" in capsys.readouterr().err
