"""Model cards: what each shipped policy is, where it came from, how it scored, and which one to
pick for a use (issue 37). ``usvsim models`` lists them; the docs render
:func:`cards_markdown`.

Every ``usvsim/models/<name>.pt`` has a card under ``"card"`` in its ``models.json`` entry. A
model's name says what it is: ``observation-action-algorithm-task``, with ``gail-trpo`` for
GAIL followed by TRPO fine-tuning and ``-continued`` for more TRPO from another model (e.g.
``scene-categorical-gail-trpo-openwater``); the names the file was published under before are
its ``former_names``, still loadable (:func:`usvsim.helm.registry.model_aliases`).

=====================  ===========================================================================
field                  meaning
=====================  ===========================================================================
``former_names``       the names the file was published under before (the setup's name,
                       e.g. ``il-categorical-scene-ow``); published results and the notes use
                       them, and ``usvsim bench --helmsmen`` still loads the file by them
``observation``        what the policy sees (``positional``, ``radar+goal``, ``scene``)
``action``             what it outputs (``gaussian``: continuous heading change;
                       ``categorical``: one of a few heading changes)
``algorithm``          the algorithm of the policy's agent, as the checkpoint records it
``method``             how it was trained, in words (RL by TRPO; IL by behavioural cloning,
                       then GAIL with TRPO policy steps; or IL followed by TRPO)
``family``             ``RL`` or ``IL``: the algorithm family of its last training stage
``task``               ``study`` (the study's pole task) or ``open-water`` (the family of
                       :mod:`usvsim.task.openwater_env`)
``use``                one of :data:`USES`: the task and what the policy perceives
``setup``, ``seed``    the training setup and seed recorded in the checkpoint
``code_commit``        the git revision that trained it (the checkpoint's), or ``unknown``
``date``               the day the file was written (UTC)
``best_iteration``     the iteration of the validation ``best.pt`` was kept at
``runs``               every chained training run: its command, wall-clock (s, or null if
                       unknown) and a note (what it started from)
``validation``         figures on validation episodes: the run's own validation record at
                       ``best.pt`` (the study's 15, the family, crowded and harsh-radar sets)
                       and the stress suite's validation split (mean success, sets >= 95 %);
                       traffic uses also the COLREG suite's (``colreg``: success, compliance)
``test``               figures on test episodes, computed after selection: the study's 200
                       held-out episodes, the stress suite's test split and, for traffic uses,
                       the COLREG suite's
``recommended``        the uses it is recommended for (empty or ``[use]``)
``notes``              anything else a user should know (free text)
=====================  ===========================================================================

:func:`check_cards` compares every card with its file (setup, observation, action, algorithm,
seed, code commit, best iteration as the checkpoint records them), finds files without cards and
cards without files, and allows at most one recommended model per use and family; the first
problem is one :class:`usvsim.common.errors.UserError` line naming the model and the field.

The recommended marks follow :data:`RECOMMENDATION_RULE` (:func:`recommend`), written down before
the validation figures it reads were computed (its seed condition was added later, after a tie:
docs/notes/2026-12-seeds.md), and read validation figures only.

Why this module is long: the card format (the table above), its checks and its Markdown
rendering are one contract with ``models.json``; the checks name each field the format defines.
"""

from __future__ import annotations

import json
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usvsim.common.errors import UserError
from usvsim.evaluation.seed_stats import SeedTable, load_seed_tables

__all__ = [
    "CARD_FIELDS",
    "RECOMMENDATION_RULE",
    "TRAFFIC_USES",
    "USES",
    "ModelCard",
    "ModelsArgs",
    "TrainingRun",
    "cards_json",
    "cards_markdown",
    "cards_table",
    "check_cards",
    "colreg_summary",
    "default_helmsmen",
    "load_cards",
    "models_report",
    "recommend",
    "recommendation_mismatches",
    "shipped_setups",
    "stress_summary",
    "with_recommendations",
    "with_stress_figures",
    "write_cards",
]

USES: dict[str, str] = {
    "study-positional": "the study's pole task, own position and the pole's (positional)",
    "study-radar": "the study's pole task, a radar image and the goal (radar+goal)",
    "open-water-scene": "the open-water family, the true obstacle and vessel list (scene)",
    "open-water-radar": "the open-water family, a radar image and the goal (radar+goal)",
    "traffic-radar": "traffic under the rules of the road: the open-water family with COLREG "
    "encounters (Imazu and trafficgen situations), a radar image and the goal (radar+goal)",
}
# the uses judged on the COLREG suite (their cards hold validation["colreg"], test["colreg"])
TRAFFIC_USES = ("traffic-radar",)
# the stress sets a use's recommendation is judged on first (empty: all of them)
USE_SETS: dict[str, tuple[str, ...]] = {
    "study-positional": ("study", "waypoints"),
    "study-radar": ("study", "waypoints"),
    "open-water-scene": (),
    "open-water-radar": (),
    "traffic-radar": (),
}
RECOMMENDATION_RULE = (
    "For each use and each family (RL, IL): the model with the highest mean success over the "
    "stress suite's validation split (100 episodes per set, usvsim bench --suite stress --split "
    "validation) on the use's sets (open-water uses: all sets; study uses: study and waypoints, "
    "the task they were trained for); ties broken by the mean over all sets of the validation "
    "split, then by name. Where a model of the use and family was trained over at least 3 seeds "
    "(its setup's seed table in usvsim/models/seeds/), only such models compete. Traffic uses "
    "(traffic-radar) rank instead by success x compliance over the COLREG suite's validation "
    "split (25 sets x 5 episodes, usvsim bench --suite colreg --split validation), ties broken "
    "by the mean over all stress validation sets, then by name (written 2026-12-07, "
    "docs/notes/2026-12-traffic.md). Test-split figures play no part."
)
MIN_SEEDS = 3  # issue 37: every recommended model trained over >= 3 seeds
CARD_FIELDS = (
    "former_names", "observation", "action", "algorithm", "method", "family", "task", "use",
    "setup", "seed", "code_commit", "date", "best_iteration", "runs", "validation", "test",
    "recommended", "notes",
)  # fmt: skip
# card field -> the checkpoint fact it must equal (usvsim.helm.registry.checkpoint_facts)
CHECKED_FIELDS = (
    "setup", "observation", "action", "algorithm", "seed", "code_commit", "best_iteration",
)  # fmt: skip


@dataclass(frozen=True)
class TrainingRun:
    """One training run of a model's chain."""

    command: str
    wall_clock_s: float | None  # s; None where no record gives it
    note: str = ""


@dataclass(frozen=True)
class ModelCard:
    """A model's card (module table)."""

    name: str
    former_names: tuple[str, ...]
    observation: str
    action: str
    algorithm: str
    method: str
    family: str
    task: str
    use: str
    setup: str
    seed: int
    code_commit: str
    date: str
    best_iteration: int | None
    runs: tuple[TrainingRun, ...]
    validation: Mapping[str, Any] = field(default_factory=dict)
    test: Mapping[str, Any] = field(default_factory=dict)
    recommended: tuple[str, ...] = ()
    notes: str = ""

    @classmethod
    def from_json(cls, name: str, card: Mapping[str, Any]) -> ModelCard:
        """The card of model ``name`` from its JSON object; ``UserError`` naming a missing or
        unknown field."""
        missing = [k for k in CARD_FIELDS if k not in card]
        unknown = [k for k in card if k not in CARD_FIELDS]
        if missing or unknown:
            what = f"missing field {missing[0]!r}" if missing else f"unknown field {unknown[0]!r}"
            raise UserError(f"model card {name}: {what} (fields: {', '.join(CARD_FIELDS)})")
        if card["use"] not in USES:
            raise UserError(
                f"model card {name}: field 'use' is {card['use']!r}; allowed: {', '.join(USES)}"
            )
        runs = tuple(TrainingRun(**r) for r in card["runs"])
        lists = ("runs", "recommended", "former_names")
        values = {k: card[k] for k in CARD_FIELDS if k not in lists}
        return cls(name=name, runs=runs, recommended=tuple(card["recommended"]),
                   former_names=tuple(card["former_names"]), **values)  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        """The card as the JSON object of ``models.json`` (fields in :data:`CARD_FIELDS` order)."""
        out: dict[str, Any] = {}
        for k in CARD_FIELDS:
            value = getattr(self, k)
            if k == "runs":
                value = [vars(r).copy() for r in value]
            elif k in ("recommended", "former_names"):
                value = list(value)
            elif k in ("validation", "test"):
                value = dict(value)
            out[k] = value
        return out

    @property
    def training_s(self) -> float | None:
        """Wall-clock of the whole chain (s); None if a run's is unknown."""
        times = [r.wall_clock_s for r in self.runs]
        return None if any(t is None for t in times) else float(sum(t or 0.0 for t in times))


def _models_dir(models_dir: Path | None) -> Path:
    if models_dir is not None:
        return models_dir
    from usvsim.helm.registry import MODELS_DIR

    return MODELS_DIR


def load_cards(models_dir: Path | None = None) -> dict[str, ModelCard]:
    """Every card of ``models_dir``'s ``models.json`` (default: the shipped models), by name;
    an entry without a card is left out (:func:`check_cards` reports it)."""
    path = _models_dir(models_dir) / "models.json"
    try:
        models = json.loads(path.read_text())["models"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise UserError(f"{path}: not a models.json with a 'models' object ({err})") from None
    return {
        name: ModelCard.from_json(name, entry["card"])
        for name, entry in sorted(models.items())
        if isinstance(entry, dict) and "card" in entry
    }


def check_cards(models_dir: Path | None = None) -> dict[str, ModelCard]:
    """The cards, each checked against its file (module docstring).

    Raises
    ------
    UserError
        One line for the first problem: a file without a card, a card without a file, a card
        field that disagrees with the checkpoint, two recommended models for one use and
        family, or a former name that is another model's name or former name.
    """
    from usvsim.helm.registry import checkpoint_facts

    folder = _models_dir(models_dir)
    cards = load_cards(folder)
    files = {p.stem: p for p in sorted(folder.glob("*.pt"))}
    for name in files.keys() - cards.keys():
        raise UserError(f"model {name}: no card in {folder / 'models.json'} (field 'card')")
    for name in cards.keys() - files.keys():
        raise UserError(f"model card {name}: no file {folder / (name + '.pt')}")
    for name, card in cards.items():
        facts = checkpoint_facts(files[name])
        for key in CHECKED_FIELDS:
            if getattr(card, key) != facts[key]:
                raise UserError(
                    f"model card {name}: field {key!r} is {getattr(card, key)!r}, "
                    f"the file says {facts[key]!r}"
                )
    _check_recommended(cards)
    seen: dict[str, str] = {name: name for name in cards}
    for name, card in cards.items():
        for former in card.former_names:
            if former in seen:
                raise UserError(
                    f"model card {name}: field 'former_names' holds {former!r}, "
                    f"which is also {seen[former]}'s name"
                )
            seen[former] = name
    return cards


def _check_recommended(cards: Mapping[str, ModelCard]) -> None:
    chosen: dict[tuple[str, str], str] = {}
    for name, card in cards.items():
        for use in card.recommended:
            if use != card.use:
                raise UserError(
                    f"model card {name}: field 'recommended' names {use!r}, "
                    f"but the model's use is {card.use!r}"
                )
            key = (use, card.family)
            if key in chosen:
                raise UserError(
                    f"model card {name}: field 'recommended': {chosen[key]} is already the "
                    f"recommended {card.family} model for {use} (at most one)"
                )
            chosen[key] = name


def stress_summary(stress: Mapping[str, Any], helmsman: str) -> dict[str, Any]:
    """One helmsman's figures of a stress JSON (``usvsim bench --suite stress --json``): split,
    episodes per set, success per set (%), mean over sets (%), sets at >= 95 %, collisions."""
    rows = [r for r in stress["rows"] if r["helmsman"] == helmsman]
    if not rows:
        return {}
    per_set = {r["episode_set"]: round(100.0 * r["success_rate"], 1) for r in rows}
    return {
        "split": stress.get("split", "test"),
        "episodes_per_set": int(stress["episodes_per_set"]),
        "mean_success_pct": round(sum(per_set.values()) / len(per_set), 2),
        "sets_at_95_pct": sum(v >= 95.0 for v in per_set.values()),
        "sets": len(per_set),
        "collisions": int(sum(r["collisions"] for r in rows)),
        "success_pct": per_set,
    }


def with_stress_figures(
    cards: Mapping[str, ModelCard], stress: Mapping[str, Any]
) -> dict[str, ModelCard]:
    """The cards with a stress JSON's figures (:func:`stress_summary`) under
    ``validation["stress"]`` or ``test["stress"]``, by the JSON's ``split``; cards of models the
    JSON has no rows for are unchanged."""
    from dataclasses import replace

    split = stress.get("split", "test")
    where = "validation" if split == "validation" else "test"
    out = dict(cards)
    for name, card in cards.items():
        summary = stress_summary(stress, name)
        if summary:
            figures = {**getattr(card, where), "stress": summary}
            out[name] = (
                replace(card, validation=figures)
                if where == "validation"
                else replace(card, test=figures)
            )
    return out


def with_recommendations(cards: Mapping[str, ModelCard]) -> dict[str, ModelCard]:
    """The cards with their ``recommended`` marks set by :func:`recommend` (validation only)."""
    from dataclasses import replace

    chosen = recommend(cards)
    return {
        name: replace(card, recommended=(card.use,) if chosen.get((card.use, card.family)) == name
                      else ())
        for name, card in cards.items()
    }  # fmt: skip


def write_cards(cards: Mapping[str, ModelCard], models_dir: Path | None = None) -> None:
    """Put ``cards`` into ``models.json`` (each entry's ``"card"``; the rest of the file kept),
    written atomically."""
    from usvsim.common.fileio import atomic_write_text

    path = _models_dir(models_dir) / "models.json"
    data = json.loads(path.read_text())
    for name, card in cards.items():
        data["models"].setdefault(name, {})["card"] = card.to_json()
    atomic_write_text(path, json.dumps(data, indent=2) + "\n")


def shipped_setups(labels: Sequence[str], models_dir: Path | None = None) -> dict[str, str]:
    """Label -> training setup (the card's ``setup``) of each label that names a shipped model,
    by its name or a former name (:func:`usvsim.helm.registry.model_aliases`)."""
    from usvsim.helm.registry import model_aliases

    cards = load_cards(models_dir)
    aliases = model_aliases(models_dir)
    found = {label: cards.get(aliases.get(label, label)) for label in labels}
    return {label: card.setup for label, card in found.items() if card is not None}


def default_helmsmen(models_dir: Path | None = None) -> list[str]:
    """The helmsmen ``usvsim bench`` compares when none are named: every classical baseline and
    the recommended models, in the registry's order; ``[]`` (every available helmsman, as
    ``--helmsmen all``) where no card can be read or none is recommended."""
    from usvsim.helm.registry import available_helmsmen

    folder = _models_dir(models_dir)
    try:
        cards = load_cards(folder)
    except UserError:
        return []
    recommended = {name for name, card in cards.items() if card.recommended}
    if not recommended:
        return []
    files = {p.stem for p in folder.glob("*.pt")}
    return [n for n in available_helmsmen(folder) if n not in files or n in recommended]


def colreg_summary(scores: Mapping[str, Any]) -> dict[str, Any]:
    """A card's ``validation["colreg"]`` or ``test["colreg"]`` from one split's record of
    ``benchmarks/colreg_seed_scores.py`` (a seed's ``scores.json``, ``validation[file]`` or
    ``test``): episodes, success and compliance (%), encounters and collisions."""
    return {
        "episodes": int(scores["episodes"]),
        "success_pct": round(100.0 * scores["success_rate"], 1),
        "compliance_pct": round(100.0 * scores["compliance_rate"], 1),
        "encounters": int(scores["encounters"]),
        "collisions": int(scores["collisions"]),
    }


def _competes(card: ModelCard) -> bool:
    """Whether the card holds the validation figures its use is ranked on."""
    return bool(card.validation.get("colreg" if card.use in TRAFFIC_USES else "stress"))


def _score(card: ModelCard) -> tuple[float, float, str]:
    """The rule's key (higher first; the name breaks ties alphabetically)."""
    stress = card.validation.get("stress", {})
    per_set: dict[str, float] = stress.get("success_pct", {})
    everything = sum(per_set.values()) / len(per_set) if per_set else -math.inf
    if card.use in TRAFFIC_USES:
        colreg = card.validation.get("colreg", {})
        if not colreg:
            return (-math.inf, everything, card.name)
        return (colreg["success_pct"] * colreg["compliance_pct"] / 100.0, everything, card.name)
    if not per_set:
        return (-math.inf, -math.inf, card.name)
    wanted = [per_set[s] for s in USE_SETS[card.use] if s in per_set] or list(per_set.values())
    return (sum(wanted) / len(wanted), everything, card.name)


def recommend(
    cards: Mapping[str, ModelCard], seeded: Collection[str] | None = None
) -> dict[tuple[str, str], str]:
    """(use, family) -> the recommended model under :data:`RECOMMENDATION_RULE`; only cards
    with their use's validation figures compete (``validation["stress"]``;
    ``validation["colreg"]`` for :data:`TRAFFIC_USES`), and where a
    use and family has a card whose setup is in ``seeded`` (default: the setups with a seed
    table of at least :data:`MIN_SEEDS` seeds), only those."""
    if seeded is None:
        seeded = {s for s, t in load_seed_tables().items() if len(t.seeds) >= MIN_SEEDS}
    competing = [c for c in cards.values() if _competes(c)]
    replicated = {(c.use, c.family) for c in competing if c.setup in seeded}
    best: dict[tuple[str, str], ModelCard] = {}
    for card in competing:
        key = (card.use, card.family)
        if key in replicated and card.setup not in seeded:
            continue
        incumbent = best.get(key)
        if incumbent is None or _better(_score(card), _score(incumbent)):
            best[key] = card
    return {key: card.name for key, card in sorted(best.items())}


def _better(a: tuple[float, float, str], b: tuple[float, float, str]) -> bool:
    return (a[0], a[1]) > (b[0], b[1]) or ((a[0], a[1]) == (b[0], b[1]) and a[2] < b[2])


def _pct(summary: Mapping[str, Any]) -> str:
    if not summary:
        return "–"
    return f"{summary['mean_success_pct']:.1f} % ({summary['sets_at_95_pct']}/{summary['sets']})"


def _seed_cell(card: ModelCard, seeds: Mapping[str, SeedTable]) -> str:
    """Its setup's test-split mean over the 22 original sets across seeds, or ``""``."""
    t = seeds.get(card.setup)
    return f"{t.original.cell()} ({len(t.seeds)} seeds)" if t else ""


def _rows(cards: Mapping[str, ModelCard], seeds: Mapping[str, SeedTable]) -> list[tuple[str, ...]]:
    rows: list[tuple[str, ...]] = []
    for name, c in sorted(cards.items(), key=lambda kv: (kv[1].use, kv[1].family, kv[0])):
        train = "unknown" if c.training_s is None else f"{c.training_s:.0f}"
        rows.append((
            name, ", ".join(c.recommended) or "", c.use, c.family, c.observation, c.action,
            _pct(c.validation.get("stress", {})), _pct(c.test.get("stress", {})),
            _seed_cell(c, seeds), train, ", ".join(c.former_names),
        ))  # fmt: skip
    return rows


_HEADER = (
    "model", "recommended", "use", "family", "observation", "action",
    "stress validation: mean (sets >= 95 %)", "stress test: mean (sets >= 95 %)",
    "stress test: IQM over N seeds [95 % CI]", "training s", "former name",
)  # fmt: skip


def cards_table(
    cards: Mapping[str, ModelCard], seeds: Mapping[str, SeedTable] | None = None
) -> str:
    """The cards as a fixed-width terminal table (``usvsim models``); ``seeds``: setup ->
    across-seed figures (:func:`usvsim.evaluation.seed_stats.load_seed_tables`)."""
    lines = [_HEADER, *_rows(cards, seeds or {})]
    widths = [max(len(line[i]) for line in lines) for i in range(len(_HEADER))]
    text = ["  ".join(c.ljust(w) for c, w in zip(line, widths, strict=True)) for line in lines]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(t.rstrip() for t in text)


def cards_json(cards: Mapping[str, ModelCard], seeds: Mapping[str, SeedTable] | None = None) -> str:
    """``usvsim models --json``: the rule, the uses, every card by name and, under
    ``across_seeds``, the across-seed figures of each model whose setup has them."""
    seeds = seeds or {}
    payload = {
        "recommendation_rule": RECOMMENDATION_RULE,
        "uses": USES,
        "models": {name: card.to_json() for name, card in sorted(cards.items())},
        "across_seeds": {
            name: seeds[c.setup].to_json() for name, c in sorted(cards.items()) if c.setup in seeds
        },
    }
    return json.dumps(payload, indent=2, allow_nan=False)


def cards_markdown(
    cards: Mapping[str, ModelCard], seeds: Mapping[str, SeedTable] | None = None
) -> str:
    """The cards as a Markdown page: the overview table, then one section per model."""
    seeds = seeds or {}
    lines = [
        "# Shipped models",
        "",
        "Generated from `usvsim models --json` (`usvsim.evaluation.model_cards`); "
        "do not edit by hand.",
        "",
        f"Recommended marks: {RECOMMENDATION_RULE}",
        "",
        "| " + " | ".join(_HEADER) + " |",
        "|" + "---|" * len(_HEADER),
        *("| " + " | ".join((f"`{r[0]}`", *r[1:])) + " |" for r in _rows(cards, seeds)),
        "",
    ]
    for name, c in sorted(cards.items()):
        lines += _card_section(name, c, seeds.get(c.setup))
    return "\n".join(lines)


def _card_section(name: str, c: ModelCard, seeds: SeedTable | None) -> list[str]:
    study = c.validation.get("best_pt", {})
    heldout = c.test.get("study_heldout", {})
    mark = f" — recommended for {', '.join(c.recommended)}" if c.recommended else ""
    lines = [
        f"## `{name}`{mark}",
        "",
        f"- What: {c.method}; observation `{c.observation}`, action `{c.action}`, task "
        f"`{c.task}` ({USES[c.use]}). Former name "
        + ", ".join(f"`{n}`" for n in c.former_names)
        + " (still loadable).",
        f"- Setup `{c.setup}`, seed {c.seed}, code commit `{c.code_commit}`, written {c.date}, "
        f"`best.pt` at iteration {c.best_iteration}.",
        "- Training runs:",
        *(_run_line(r) for r in c.runs),
    ]
    if study:
        lines.append("- Validation at `best.pt`: " + _best_pt_text(study))
    lines.append(f"- Stress suite, validation split: {_pct(c.validation.get('stress', {}))}; "
                 f"test split: {_pct(c.test.get('stress', {}))}")  # fmt: skip
    if c.validation.get("colreg") or c.test.get("colreg"):
        lines.append(f"- COLREG suite (success, compliance, collisions), validation split: "
                     f"{_colreg_text(c.validation.get('colreg', {}))}; test split: "
                     f"{_colreg_text(c.test.get('colreg', {}))}")  # fmt: skip
    if seeds is not None:
        each = " / ".join(f"{100 * v:.1f}" for v in seeds.original.per_seed)
        lines.append(
            f"- Setup `{c.setup}` over seeds {', '.join(map(str, seeds.seeds))} (stress test "
            f"split, mean of the 22 original sets): {seeds.label} {seeds.original.cell()}; "
            f"seeds {each} %; the seed rule picks seed {seeds.picked_seed}"
        )
    if heldout:
        lines.append(
            f"- Study held-out (test): {heldout['successes']}/{heldout['episodes']} successes"
        )
    if c.notes:
        lines.append(f"- Notes: {c.notes}")
    return [*lines, ""]


def _colreg_text(summary: Mapping[str, Any]) -> str:
    if not summary:
        return "–"
    return (f"{summary['success_pct']:.1f} %, {summary['compliance_pct']:.1f} % of "
            f"{summary['encounters']} encounters, {summary['collisions']} in "
            f"{summary['episodes']} episodes")  # fmt: skip


def _run_line(run: TrainingRun) -> str:
    wall = "wall-clock unknown" if run.wall_clock_s is None else f"{run.wall_clock_s:.0f} s"
    return f"  - `{run.command}` ({wall})" + (f": {run.note}" if run.note else "")


def _best_pt_text(study: Mapping[str, Any]) -> str:
    parts = [f"study {study['successes']}/{study['n_episodes']}"]
    for key, label in (("family", "family"), ("crowded", "crowded"), ("radar", "harsh radar")):
        if f"{key}_successes" in study:
            parts.append(f"{label} {study[f'{key}_successes']}/{study[f'{key}_n_episodes']}")
    return ", ".join(parts)


@dataclass(frozen=True)
class ModelsArgs:
    """List the shipped models with their cards (checked against the files)."""

    json: bool = False  # print every card as JSON (stdout) instead of the table


def models_report(args: ModelsArgs, models_dir: Path | None = None) -> str:
    """What ``usvsim models`` prints (the cards checked first: ``UserError`` on a problem)."""
    cards = check_cards(models_dir)
    seeds = load_seed_tables()
    if args.json:
        return cards_json(cards, seeds)
    return (
        cards_table(cards, seeds)
        + f"\n\n{len(cards)} models; recommended marks: {RECOMMENDATION_RULE}\n"
        + "Uses: "
        + "; ".join(f"{k}: {v}" for k, v in USES.items())
    )


def recommendation_mismatches(cards: Mapping[str, ModelCard]) -> list[str]:
    """Models whose ``recommended`` marks differ from what :func:`recommend` gives (sorted);
    empty when the marks follow the rule."""
    rule = set(recommend(cards).values())
    marked = {name for name, c in cards.items() if c.recommended}
    return sorted(rule ^ marked)
