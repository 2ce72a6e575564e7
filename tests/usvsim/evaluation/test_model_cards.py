"""Model cards: every shipped file has one that agrees with it, ``usvsim models`` (table and
JSON), one-line errors for a missing or disagreeing card, the recommended marks follow the rule
on validation figures only, and the cards' stress figures reproduce."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from usvsim.cli.main import main
from usvsim.common.errors import UserError
from usvsim.evaluation import model_cards
from usvsim.evaluation.model_cards import (
    CARD_FIELDS,
    USES,
    ModelCard,
    cards_markdown,
    check_cards,
    load_cards,
    recommend,
    recommendation_mismatches,
    stress_summary,
    with_recommendations,
    with_stress_figures,
)
from usvsim.helm import registry
from usvsim.helm.registry import MODELS_DIR

SHIPPED = sorted(p.stem for p in MODELS_DIR.glob("*.pt"))
SMALL = "positional-gaussian-trpo-study"  # a small file for the bad-input tests
SMALL_SETUP = "rl-gaussian-positional"  # its setup, the name it was published under


def test_every_shipped_file_has_a_card_that_agrees_with_it() -> None:
    cards = check_cards()
    assert sorted(cards) == SHIPPED and len(SHIPPED) >= 20
    for name, card in cards.items():
        assert card.name == name and card.use in USES and card.family in ("RL", "IL")
        assert card.runs and all(r.command.startswith("usvsim train") for r in card.runs)
        assert card.test["study_heldout"]["episodes"] == 200


def test_models_command_prints_a_table_and_the_cards_as_json(capsys) -> None:
    assert main(["models"]) == 0
    table = capsys.readouterr().out
    assert all(f"\n{name} " in table for name in SHIPPED)
    assert main(["models", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert sorted(payload["models"]) == SHIPPED
    assert all(list(card) == list(CARD_FIELDS) for card in payload["models"].values())
    assert "validation" in payload["recommendation_rule"]


def _one_model_dir(tmp_path: Path, monkeypatch) -> Path:
    shutil.copy(MODELS_DIR / f"{SMALL}.pt", tmp_path / f"{SMALL}.pt")
    entry = json.loads((MODELS_DIR / "models.json").read_text())["models"][SMALL]
    (tmp_path / "models.json").write_text(json.dumps({"models": {SMALL: entry}}))
    monkeypatch.setattr(registry, "MODELS_DIR", tmp_path)
    return tmp_path


def _edit_card(folder: Path, **changes: object) -> None:
    data = json.loads((folder / "models.json").read_text())
    data["models"][SMALL]["card"].update(changes)
    (folder / "models.json").write_text(json.dumps(data))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"observation": "scene"}, "field 'observation' is 'scene', the file says 'positional'"),
        ({"action": "categorical"}, "field 'action' is 'categorical', the file says 'gaussian'"),
        ({"setup": "rl-gaussian-radar"}, "field 'setup' is 'rl-gaussian-radar'"),
        ({"best_iteration": 7}, "field 'best_iteration' is 7, the file says "),  # its iteration
        ({"use": "anywhere"}, "field 'use' is 'anywhere'; allowed: study-positional"),
        ({"recommended": ["open-water-scene"]}, "field 'recommended' names 'open-water-scene'"),
    ],
)
def test_a_card_that_disagrees_with_its_file_is_one_line_exit_2(
    tmp_path: Path, monkeypatch, capsys, changes: dict[str, object], message: str
) -> None:
    folder = _one_model_dir(tmp_path, monkeypatch)
    assert main(["models"]) == 0
    capsys.readouterr()
    _edit_card(folder, **changes)
    assert main(["models"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"usvsim models: model card {SMALL}: ") and message in err
    assert len(err.splitlines()) == 1


def test_a_missing_card_or_file_is_named(tmp_path: Path, monkeypatch) -> None:
    folder = _one_model_dir(tmp_path, monkeypatch)
    data = json.loads((folder / "models.json").read_text())
    card = data["models"][SMALL].pop("card")
    (folder / "models.json").write_text(json.dumps(data))
    with pytest.raises(UserError, match=f"model {SMALL}: no card .* \\(field 'card'\\)"):
        check_cards()
    data["models"][SMALL]["card"] = card
    data["models"]["ghost"] = {"card": {**card, "former_names": []}}
    (folder / "models.json").write_text(json.dumps(data))
    with pytest.raises(UserError, match=r"model card ghost: no file .*ghost\.pt"):
        check_cards()
    data["models"][SMALL]["card"] = {k: v for k, v in card.items() if k != "runs"}
    (folder / "models.json").write_text(json.dumps(data))
    with pytest.raises(UserError, match=f"model card {SMALL}: missing field 'runs'"):
        load_cards()


def _card(name: str, use: str, family: str, val: dict[str, float], test: float) -> ModelCard:
    stress_val = {"success_pct": val, "mean_success_pct": sum(val.values()) / len(val)}
    stress_test = {"success_pct": dict.fromkeys(val, test)}
    return ModelCard(
        name=name, former_names=(), observation="scene", action="gaussian", algorithm="trpo",
        method="RL", family=family, task="open-water", use=use, setup=name, seed=0,
        code_commit="unknown", date="2026-12-04", best_iteration=1, runs=(),
        validation={"stress": stress_val}, test={"stress": stress_test},
    )  # fmt: skip


def test_recommendation_reads_validation_only_one_per_use_and_family() -> None:
    ow = "open-water-scene"
    cards = {
        "a": _card("a", ow, "RL", {"x": 90.0, "y": 100.0}, test=100.0),
        "b": _card("b", ow, "RL", {"x": 96.0, "y": 96.0}, test=10.0),
        "c": _card("c", ow, "IL", {"x": 80.0, "y": 80.0}, test=100.0),
        "d": _card("d", "study-positional", "RL", {"study": 100.0, "x": 50.0}, test=0.0),
        "e": _card("e", "study-positional", "RL", {"study": 100.0, "x": 60.0}, test=0.0),
    }
    assert recommend(cards) == {
        (ow, "IL"): "c",
        (ow, "RL"): "b",  # higher validation mean, however poor its test figures
        ("study-positional", "RL"): "e",  # tie on the study set, broken by all sets
    }
    flipped = {k: replace(c, test={"stress": {"success_pct": {"x": 100.0 - 1.0}}})
               for k, c in cards.items()}  # fmt: skip
    assert recommend(flipped) == recommend(cards)  # test figures play no part
    marked = with_recommendations(cards)
    assert [n for n, c in marked.items() if c.recommended] == ["b", "c", "e"]
    assert recommendation_mismatches(marked) == []
    assert recommendation_mismatches(cards) == ["b", "c", "e"]


def test_where_a_use_has_a_model_over_seeds_only_such_models_compete() -> None:
    ow = "open-water-radar"
    cards = {
        "one-seed": _card("one-seed", ow, "RL", {"x": 99.0}, test=99.0),
        "seeded": _card("seeded", ow, "RL", {"x": 90.0}, test=90.0),
        "il": _card("il", ow, "IL", {"x": 80.0}, test=80.0),
    }
    assert recommend(cards, seeded=set()) == {(ow, "IL"): "il", (ow, "RL"): "one-seed"}
    assert recommend(cards, seeded={"seeded"}) == {(ow, "IL"): "il", (ow, "RL"): "seeded"}
    assert recommend(cards, seeded={"il"}) == recommend(cards, seeded={"il", "absent"})


def test_traffic_use_ranks_by_colreg_validation_success_times_compliance() -> None:
    """traffic-radar ranks on the COLREG suite's validation split, not on the stress suite;
    a traffic card without COLREG validation figures does not compete."""
    tr = "traffic-radar"

    def traffic(name: str, stress: float, success: float, compliance: float | None) -> ModelCard:
        card = _card(name, tr, "RL", {"x": stress}, test=stress)
        colreg = {} if compliance is None else {"colreg": {
            "episodes": 125, "success_pct": success, "compliance_pct": compliance,
            "encounters": 250, "collisions": 0}}  # fmt: skip
        return replace(card, validation={**card.validation, **colreg})

    cards = {
        "safe": traffic("safe", 99.0, 84.0, 92.0),  # 77.3: the best stress figures
        "keeps-rules": traffic("keeps-rules", 90.0, 96.0, 88.0),  # 84.5
        "no-colreg": traffic("no-colreg", 100.0, 0.0, None),
    }
    assert recommend(cards, seeded=set()) == {(tr, "RL"): "keeps-rules"}
    tie = {**cards, "tie": traffic("tie", 95.0, 88.0, 96.0)}  # 84.5 too, better stress
    assert recommend(tie, seeded=set()) == {(tr, "RL"): "tie"}
    assert model_cards.colreg_summary(
        {"episodes": 125, "success_rate": 0.84, "compliance_rate": 0.9219, "encounters": 269,
         "collisions": 3}
    ) == {"episodes": 125, "success_pct": 84.0, "compliance_pct": 92.2, "encounters": 269,
          "collisions": 3}  # fmt: skip


def test_shipped_marks_follow_the_rule_at_most_one_per_use_and_family() -> None:
    cards = load_cards()
    assert recommendation_mismatches(cards) == []
    marks = [(c.use, c.family) for c in cards.values() for _ in c.recommended]
    assert len(marks) == len(set(marks))
    for card in cards.values():
        if card.recommended:  # a mark rests on validation figures; test ones computed after
            assert card.validation["stress"]["split"] == "validation"
            assert card.test["stress"]["split"] == "test"
    assert {c.use for c in cards.values() if c.recommended} == set(USES)


def test_stress_figures_go_to_the_split_they_came_from() -> None:
    cards = {SMALL: load_cards()[SMALL]}
    row = {"helmsman": SMALL, "episode_set": "study", "success_rate": 0.97, "collisions": 1}
    stress = {"split": "validation", "episodes_per_set": 100, "rows": [row]}
    filled = with_stress_figures(cards, stress)[SMALL]
    assert filled.validation["stress"]["success_pct"] == {"study": 97.0}
    assert filled.test == cards[SMALL].test
    tested = with_stress_figures(cards, {**stress, "split": "test"})[SMALL]
    assert tested.test["stress"]["sets_at_95_pct"] == 1
    assert stress_summary(stress, "nobody") == {}


def test_card_stress_figures_reproduce() -> None:
    """The card's validation-split figure of a positional model on two sets, run again."""
    from usvsim.evaluation.stress import run_stress, select_sets
    from usvsim.helm.registry import make_helmsman

    card = load_cards()[SMALL]
    recorded = card.validation.get("stress", {}).get("success_pct", {})
    if not recorded:
        pytest.skip("no stress figures on this card")
    sets = select_sets(["study", "two-obstacles"])
    n = card.validation["stress"]["episodes_per_set"]
    result = run_stress({SMALL: lambda: make_helmsman(SMALL)}, sets, n, False, split="validation")
    again = stress_summary(_rows(result), SMALL)
    assert {s: again["success_pct"][s] for s in ("study", "two-obstacles")} == {
        s: recorded[s] for s in ("study", "two-obstacles")
    }


def _rows(result) -> dict[str, Any]:  # type: ignore[no-untyped-def]
    from usvsim.evaluation.stress import stress_json

    return json.loads(stress_json(result))


def test_markdown_page_has_every_model_and_the_rule() -> None:
    page = cards_markdown(load_cards())
    assert page.startswith("# Shipped models")
    assert all(f"## `{name}`" in page for name in SHIPPED)
    assert model_cards.RECOMMENDATION_RULE in page


def test_default_helmsmen_are_the_baselines_and_the_recommended_models(
    tmp_path: Path, monkeypatch
) -> None:
    from usvsim.evaluation.model_cards import default_helmsmen
    from usvsim.helm.registry import available_helmsmen, select_helmsmen

    folder = _one_model_dir(tmp_path, monkeypatch)
    shutil.copy(
        MODELS_DIR / "positional-gaussian-gail-study.pt",
        folder / "positional-gaussian-gail-study.pt",
    )
    _edit_card(folder, recommended=[])
    assert default_helmsmen() == []  # no model recommended: every available one
    _edit_card(folder, recommended=["study-positional"])
    names = default_helmsmen()
    assert SMALL in names and "positional-gaussian-gail-study" not in names
    assert {"los", "los-avoid", "vo"} <= set(names)
    assert list(select_helmsmen(["all"])) == list(available_helmsmen())
    assert "positional-gaussian-gail-study" in select_helmsmen(["all"])


def test_names_say_what_a_model_is_and_need_no_quoting() -> None:
    """observation-action-algorithm-task (``usvsim models``): lower-case words and hyphens only,
    so a name survives ``--helmsmen a,b``, a file name, a URL and a docs heading anchor."""
    import re

    for name, card in load_cards().items():
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", name), name
        observation, action = name.split("-")[:2]
        assert observation == card.observation.split("+")[0] and action == card.action
        assert ("-study" in name) == (card.task == "study") and card.former_names == (card.setup,)


def test_every_model_is_also_named_by_its_former_name(tmp_path: Path, capsys) -> None:
    """``usvsim bench --helmsmen rl-gaussian-positional`` (a published name) loads the file that
    is now ``positional-gaussian-trpo-study``, labels the row by the name given and prints
    nothing; an index without cards gives no aliases."""
    aliases = registry.model_aliases()
    cards = load_cards()
    assert aliases == {f: name for name, c in cards.items() for f in c.former_names}
    assert len(aliases) == len(cards) >= 20
    chosen = registry.select_helmsmen([SMALL_SETUP])
    assert list(chosen) == [SMALL_SETUP]
    by_alias, by_file = chosen[SMALL_SETUP](), registry.make_helmsman(SMALL)
    assert type(by_alias) is type(registry.make_helmsman(SMALL_SETUP)) is type(by_file)
    assert capsys.readouterr() == ("", "")  # an old name is no warning
    assert (
        registry.model_path(SMALL_SETUP) == registry.model_path(SMALL) == MODELS_DIR / f"{SMALL}.pt"
    )
    assert registry.model_path("no-such") == MODELS_DIR / "no-such.pt"
    assert registry.checkpoint_facts(MODELS_DIR / f"{SMALL}.pt")["setup"] == SMALL_SETUP
    shutil.copy(MODELS_DIR / f"{SMALL}.pt", tmp_path / f"{SMALL}.pt")
    assert registry.model_aliases(tmp_path) == {}  # no models.json there
    (tmp_path / "models.json").write_text("{")
    with pytest.raises(UserError, match="unreadable model index"):
        registry.model_aliases(tmp_path)


def test_a_former_name_that_is_a_models_name_is_refused(tmp_path: Path, monkeypatch) -> None:
    folder = _one_model_dir(tmp_path, monkeypatch)
    _edit_card(folder, former_names=[SMALL])
    with pytest.raises(UserError, match=f"model card {SMALL}: field 'former_names' holds"):
        check_cards()
