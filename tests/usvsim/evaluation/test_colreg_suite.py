"""``usvsim bench --suite colreg``: sets, rows, and a scorer that tells rule breakers apart."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from baselines.los import heading_change_to_action
from usvsim.common.angles import ssa
from usvsim.common.errors import UserError
from usvsim.evaluation.colreg_suite import (
    COLREG_SETS,
    colreg_episodes,
    colreg_set_names,
    select_colreg_sets,
)
from usvsim.task.observations import SCENE_FEATURES

DEG = math.pi / 180


def test_twenty_two_imazu_sets_and_trafficgen() -> None:
    names = colreg_set_names()
    assert names[:22] == tuple(f"imazu-{p:02d}" for p in range(1, 23))
    assert names[22:] == ("trafficgen-1ts", "trafficgen-2ts", "trafficgen-3ts")
    assert [len(s.trafficgen_files) for s in COLREG_SETS[22:]] == [5, 15, 35]  # DNV's 55
    assert not any(s.reactive_targets for s in COLREG_SETS)  # Imazu's problems are defined so
    with pytest.raises(UserError, match="unknown colreg set 'imazu-23'"):
        select_colreg_sets(["imazu-23"])


def test_episodes_are_seeded_per_set_and_split() -> None:
    tg = select_colreg_sets(["trafficgen-1ts"])[0]
    a, b = colreg_episodes(tg, 6), colreg_episodes(tg, 6)
    assert a == b
    assert colreg_episodes(tg, 6, "validation") != a
    assert [len(e.vessels) for e in a] == [1] * 6


@dataclass
class _Probe:
    """Goal pursuit on the ``scene`` observation, with one habit in meetings (below)."""

    habit: str  # "port-in-head-on" | "holds-course"
    observation: str = "scene"
    action: str = "gaussian"

    def reset(self, n_boats: int) -> None:
        self.n = n_boats

    def act(self, obs: Any) -> Any:
        obs = np.asarray(obs, dtype=float)
        n = obs.shape[0]
        course = obs[:, 1].copy()
        if self.habit == "port-in-head-on":  # a vessel ahead on a reciprocal course: 45° to port
            slots = obs[:, 4:].reshape(n, -1, SCENE_FEATURES)
            r, phi, ok = slots[..., 0], slots[..., 1], slots[..., 5] > 0.5
            v = slots[..., 3:5] + obs[:, None, 2:4]
            reciprocal = np.abs(ssa(np.arctan2(v[..., 1], v[..., 0]) - np.pi)) < 20 * DEG
            meeting = ok & reciprocal & (np.abs(phi) < 30 * DEG) & (r < 200.0)
            course = np.where(meeting.any(axis=1), obs[:, 1] - 45 * DEG, course)
        crab = np.arctan2(obs[:, 3], obs[:, 2])
        return heading_change_to_action(ssa(course - crab), 30 * DEG)


def _violating_share(habit: str, set_name: str, n: int) -> tuple[float, int]:
    """Share of the episodes with a scored encounter in which one failed, and how many."""
    from usvsim.evaluation.colreg import evaluate_colreg
    from usvsim.evaluation.colreg_rollout import run_encounters

    episodes = colreg_episodes(select_colreg_sets([set_name])[0], n)
    result = evaluate_colreg(run_encounters(_Probe(habit), episodes).tracks)
    scored = result.scored
    failed = (scored & ~np.asarray(result.passed, dtype=bool)).any(axis=1)
    applies = scored.any(axis=1)
    return float(failed[applies].mean()), int(applies.sum())


def test_turning_to_port_head_on_scores_as_violating() -> None:
    """Issue 39: a helmsman that turns to port in every head-on meeting violates in >= 95 % of
    the episodes where the rule applies (Imazu 1, head-on, 20 episodes)."""
    pytest.importorskip("usvsim.evaluation.colreg")
    share, applies = _violating_share("port-in-head-on", "imazu-01", 20)
    assert applies >= 19 and share >= 0.95, (share, applies)


def test_holding_course_when_giving_way_scores_as_violating() -> None:
    """Issue 39: a helmsman that holds course when it must give way (Imazu 2, crossing from
    starboard, 20 episodes) violates in >= 95 % of the episodes where the rule applies."""
    pytest.importorskip("usvsim.evaluation.colreg")
    share, applies = _violating_share("holds-course", "imazu-02", 20)
    assert applies >= 19 and share >= 0.95, (share, applies)


def test_cli_colreg_suite_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("usvsim.evaluation.colreg")
    from usvsim.cli import main

    argv = ["bench", "--suite", "colreg", "--sets", "imazu-02,trafficgen-1ts", "--helmsmen",
            "sb-mpc,vo", "--colreg-episodes", "5", "--json", "--out", str(tmp_path)]  # fmt: skip
    assert main(argv) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["suite"] == "colreg" and payload["sets"] == ["imazu-02", "trafficgen-1ts"]
    rows = {(r["helmsman"], r["episode_set"]): r for r in payload["rows"]}
    assert len(rows) == 4 and all(r["episodes"] == 5 for r in rows.values())
    row = rows[("sb-mpc", "imazu-02")]
    assert 0.0 <= row["compliance_ci95_low"] <= row["compliance_rate"] <= 1.0
    # Imazu 2: one target crossing from starboard, so every encounter is a give-way crossing
    assert row["encounters_crossing_give_way"] == row["encounters"] == 5
    assert {"colreg.md", "colreg.csv", "colreg-heatmap.png"} <= {p.name for p in tmp_path.iterdir()}


def test_test_split_refused_in_selection_code() -> None:
    from usvsim.common.splits import TestSplitInSelectionError, selection_mode

    tg = select_colreg_sets(["trafficgen-1ts"])[0]
    with selection_mode("a test"):
        assert len(colreg_episodes(tg, 2, "validation")) == 2
        with pytest.raises(TestSplitInSelectionError):
            colreg_episodes(select_colreg_sets(["imazu-03"])[0], 2)
        with pytest.raises(TestSplitInSelectionError):
            colreg_episodes(tg, 2)


def test_study_task_models_are_labelled_not_made_for_traffic() -> None:
    from usvsim.evaluation.colreg_suite import traffic_fitness
    from usvsim.evaluation.model_cards import load_cards

    cards = load_cards()
    study = [n for n, c in cards.items() if c.task == "study"]
    open_water = [n for n, c in cards.items() if c.task == "open-water"]
    assert study and open_water
    for name in study:
        fit = traffic_fitness(name, cards[name].observation, cards)
        assert not fit.meets_traffic and "pole" in fit.why and fit.trained_for == cards[name].use
    assert all(traffic_fitness(n, cards[n].observation, cards).meets_traffic for n in open_water)
    assert not traffic_fitness("los", "positional", cards).meets_traffic
    assert traffic_fitness("sb-mpc", "scene", cards).meets_traffic
    assert not traffic_fitness("my-run", "positional", {}).meets_traffic  # a card-less checkpoint
    assert traffic_fitness("my-run", "radar+goal", {}).meets_traffic


def test_default_selection_leaves_study_models_out_and_named_ones_are_labelled() -> None:
    from usvsim.evaluation.bench import BenchArgs
    from usvsim.evaluation.colreg_report import colreg_json, colreg_markdown
    from usvsim.evaluation.colreg_suite import made_for_traffic, run_colreg_args
    from usvsim.evaluation.model_cards import load_cards
    from usvsim.helm.registry import available_helmsmen

    cards = load_cards()
    study = {n for n, c in cards.items() if c.task == "study"}
    default = {n for n in available_helmsmen() if made_for_traffic(n, cards)}
    assert not study & default and "los" not in default
    assert {"vo", "sb-mpc", "vo-radar", "los-avoid"} <= default
    assert {n for n, c in cards.items() if c.task == "open-water"} <= default
    named = sorted(study)[0]
    run = run_colreg_args(
        BenchArgs(suite="colreg", sets="imazu-01", colreg_episodes=1, helmsmen=f"vo,{named}"),
        progress=False,
    )
    payload = json.loads(colreg_json(run))
    assert payload["helmsmen_traffic"][named]["meets_traffic"] is False
    assert payload["helmsmen_traffic"]["vo"]["meets_traffic"] is True
    assert len(payload["rows"]) == 2  # run and scored all the same
    md = colreg_markdown(run)
    assert f"| set | vo | {named}† |" in md and f"- `{named}` (" in md


@pytest.mark.parametrize("targets", [1, 2, 3])
def test_trafficgen_baseline_sets_hold_situations_with_their_number_of_targets(targets) -> None:
    from usvsim.evaluation.trafficgen_io import read_situation

    (tg,) = select_colreg_sets([f"trafficgen-{targets}ts"])
    situations = [read_situation(f) for f in tg.trafficgen_files]
    assert all(len(s.targets) == targets for s in situations)
    assert all(len(s.title.split(", ")) == targets for s in situations)  # "HO, CR-GW", ...
    assert len({s.title for s in situations}) == len(situations)  # every combination once
    episodes = colreg_episodes(tg, len(situations), "validation")
    assert [len(e.vessels) for e in episodes] == [targets] * len(situations)


def test_radar_models_see_the_imazu_targets_on_their_radar() -> None:
    """The radar observation of a colreg rollout holds the targets: blank without them, lit
    once the head-on target of Imazu 1 is within radar range (straight ahead, 2 s decisions)."""
    from dataclasses import replace

    from usvsim.evaluation.imazu import imazu_episodes
    from usvsim.task.openwater_batch import OpenWaterBatch

    episodes = list(imazu_episodes(1, 2, "validation"))
    lit = {}
    for label, eps in (("targets", episodes), ("none", [replace(e, vessels=()) for e in episodes])):
        sim = OpenWaterBatch(len(eps), observation="radar+goal", action="gaussian")
        sim.reset(None, eps)
        lit[label] = [
            float(np.abs(sim.step(np.zeros((len(eps), 1))).observation["radar"]).sum())
            for _ in range(40)
        ]
    assert max(lit["none"]) == 0.0
    assert lit["targets"][0] == 0.0 and max(lit["targets"]) > 0.0  # out of range, then seen
