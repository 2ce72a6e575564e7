"""Across-seed figures of a recommended setup on the stress suite (issue 37, Build 4).

A recommended setup is trained with several seeds (``usvsim sweep``); each seed's ``best.pt``
runs the stress suite's validation and test splits (``usvsim bench --suite stress --split ...
--json``). From those rows this module gives

* per stress set, the interquartile mean (IQM, the mean of the middle 50 % of runs,
  ``scipy.stats.trim_mean`` with 25 % cut at each end; Agarwal et al. 2021, "Deep reinforcement
  learning at the edge of the statistical precipice", §4.3) of the seeds' test-split success,
  with rliable's 95 % stratified-bootstrap percentile interval over seeds, seeded
  (:data:`BOOTSTRAP_SEED`), and each seed's own figure; with 3 seeds the IQM is their mean;
* the same for each seed's mean success over the 22 original sets (the weather sets of
  :mod:`usvsim.task.weather_draw` left out), comparable with the shipped file's mean;
* the seed the written rule picks (:func:`pick_seed`): the seed whose ``best.pt`` has the median
  mean success over the **validation** split's sets (the lower median for an even count, ties
  by seed). Only validation figures reach it.

The result is a :class:`SeedTable`, written by ``benchmarks/seed_table.py`` to
``usvsim/models/seeds/<setup>.json`` (:data:`SEEDS_DIR`, package data: the file records the
command that made it). ``usvsim bench --suite stress``, ``usvsim models`` and the Results page
read those files (:func:`load_seed_tables`) and show "IQM over N seeds [95 % CI]" beside the
shipped file's own figure; a setup without a file shows nothing extra. Reading needs no
rliable (the figures are in the file); computing them does (the ``sweep`` extra).
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from usvsim.common.errors import UserError
from usvsim.common.splits import selection_mode

__all__ = [
    "BOOTSTRAP_REPS",
    "BOOTSTRAP_SEED",
    "SEEDS_DIR",
    "SEED_RULE",
    "SeedFigure",
    "SeedTable",
    "bootstrap_intervals",
    "iqm",
    "iqm_with_interval",
    "load_seed_tables",
    "original_sets",
    "pick_seed",
    "seed_header",
    "seed_rates",
    "seed_table",
    "seed_tables_for",
    "with_seed_columns",
    "write_seed_table",
]

SEEDS_DIR = Path(__file__).resolve().parents[1] / "models" / "seeds"
BOOTSTRAP_REPS = 10_000  # resamples (rliable's default is 50 000; see sweep_report's note)
BOOTSTRAP_SEED = 0  # the bootstrap's generator: the same rows give the same intervals
SEED_RULE = (
    "the seed whose best.pt has the median mean success over the stress suite's validation "
    "split ({sets}); the lower median for an even number of seeds, ties by seed number"
)
RuleSets = Literal["all", "original"]


def iqm(values: Sequence[float] | np.ndarray) -> float:
    """Interquartile mean: the mean after cutting ``int(0.25 n)`` values from each end, as
    rliable's ``aggregate_iqm`` (``scipy.stats.trim_mean(x, 0.25)``) without its per-call
    overhead (the bootstrap calls it once per resample).

    >>> round(iqm([0.8, 0.9, 1.0]), 12)  # 3 values: nothing is cut, the mean
    0.9
    >>> round(iqm([0.0, 0.5, 0.7, 1.0]), 12)  # 4 values: one cut at each end
    0.6
    """
    x = np.sort(np.asarray(values, dtype=float).ravel())
    cut = int(0.25 * x.size)
    return float(np.mean(x[cut : x.size - cut]))


def bootstrap_intervals(
    score_dict: Mapping[str, Any], func: Callable[..., Any], reps: int = BOOTSTRAP_REPS
) -> tuple[dict[str, Any], dict[str, Any]]:
    """rliable's stratified-bootstrap point estimates and 95 % percentile intervals, seeded.

    ``score_dict`` maps a name to a (runs, tasks) array; the bootstrap resamples runs within
    each task. rliable's ``StratifiedBootstrap.update_indices`` draws from NumPy's *global*
    generator (its ``random_state`` only reaches arch), so the global state is seeded with
    :data:`BOOTSTRAP_SEED` here and put back after.
    """
    from rliable import library as rly

    saved = np.random.get_state()  # noqa: NPY002 (rliable draws from the global generator)
    np.random.seed(BOOTSTRAP_SEED)  # noqa: NPY002
    try:
        with warnings.catch_warnings():  # arch 7 deprecates the RandomState rliable passes
            warnings.simplefilter("ignore", FutureWarning)
            return rly.get_interval_estimates(
                dict(score_dict),
                func,
                reps=reps,
                random_state=np.random.RandomState(BOOTSTRAP_SEED),
            )
    finally:
        np.random.set_state(saved)  # noqa: NPY002


def iqm_with_interval(
    scores: np.ndarray, reps: int = BOOTSTRAP_REPS
) -> tuple[float, tuple[float, float]]:
    """IQM of a (seeds, sets) array and its stratified-bootstrap 95 % interval (rliable,
    :func:`bootstrap_intervals`); needs rliable."""
    points, cis = bootstrap_intervals({"x": scores}, lambda x: np.array([iqm(x)]), reps)
    return float(points["x"][0]), (float(cis["x"][0][0]), float(cis["x"][1][0]))


@dataclass(frozen=True)
class SeedFigure:
    """Success over seeds on one stress set (or over several: :attr:`SeedTable.original`);
    rates in [0, 1]."""

    name: str  # the set, or "original sets"
    iqm: float  # IQM over seeds
    ci95: tuple[float, float]  # rliable's 95 % stratified-bootstrap interval of the IQM
    per_seed: tuple[float, ...]  # each seed's figure, in SeedTable.seeds order

    def cell(self) -> str:
        """``"98.1 % [97.0, 99.0]"``."""
        return f"{100 * self.iqm:.1f} % [{100 * self.ci95[0]:.1f}, {100 * self.ci95[1]:.1f}]"

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "iqm": self.iqm,
            "ci95": list(self.ci95),
            "per_seed": list(self.per_seed),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SeedFigure:
        lo, hi = data["ci95"]
        per_seed = tuple(float(v) for v in data["per_seed"])
        return cls(str(data["name"]), float(data["iqm"]), (float(lo), float(hi)), per_seed)


@dataclass(frozen=True)
class SeedTable:
    """A setup's across-seed figures (module docstring); what ``usvsim/models/seeds/`` holds."""

    setup: str
    seeds: tuple[int, ...]
    split: str  # the split the figures report ("test")
    episodes_per_set: int
    sets: tuple[SeedFigure, ...]  # per stress set, in the suite's order
    original: SeedFigure  # over the 22 original sets
    validation_means: Mapping[int, float]  # seed -> mean validation success over rule_sets
    rule_sets: RuleSets
    picked_seed: int  # by SEED_RULE (validation only)
    command: str  # what wrote the file
    provenance: str = ""  # how the seeds were trained and benched (free text)

    @property
    def label(self) -> str:
        """The column header: ``"IQM over 3 seeds [95 % CI]"``."""
        return f"IQM over {len(self.seeds)} seeds [95 % CI]"

    @property
    def rule(self) -> str:
        """:data:`SEED_RULE` with its sets."""
        sets = "all its sets" if self.rule_sets == "all" else "the 22 original sets"
        return SEED_RULE.format(sets=sets)

    def figure(self, stress_set: str) -> SeedFigure | None:
        """The figure of ``stress_set``; None if the seeds did not run it."""
        return next((f for f in self.sets if f.name == stress_set), None)

    def to_json(self) -> dict[str, Any]:
        return {
            "setup": self.setup,
            "seeds": list(self.seeds),
            "split": self.split,
            "episodes_per_set": self.episodes_per_set,
            "label": self.label,
            "statistic": (
                "IQM over seeds of each seed's best.pt success (scipy trim_mean 25 %), rliable's "
                f"95 % stratified-bootstrap percentile interval ({BOOTSTRAP_REPS} resamples, "
                f"seed {BOOTSTRAP_SEED}); 'original': the same of each seed's mean success over "
                "the 22 original sets"
            ),
            "rule": self.rule,
            "rule_sets": self.rule_sets,
            "validation_means": {str(k): v for k, v in self.validation_means.items()},
            "picked_seed": self.picked_seed,
            "original": self.original.to_json(),
            "sets": [f.to_json() for f in self.sets],
            "command": self.command,
            "provenance": self.provenance,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SeedTable:
        rule_sets = data["rule_sets"]
        if rule_sets not in ("all", "original"):
            raise ValueError(f"rule_sets {rule_sets!r}")
        return cls(
            setup=str(data["setup"]),
            seeds=tuple(int(s) for s in data["seeds"]),
            split=str(data["split"]),
            episodes_per_set=int(data["episodes_per_set"]),
            sets=tuple(SeedFigure.from_json(f) for f in data["sets"]),
            original=SeedFigure.from_json(data["original"]),
            validation_means={int(k): float(v) for k, v in data["validation_means"].items()},
            rule_sets=rule_sets,
            picked_seed=int(data["picked_seed"]),
            command=str(data["command"]),
            provenance=str(data.get("provenance", "")),
        )


def original_sets(sets: Sequence[str]) -> list[str]:
    """``sets`` without the weather sets (:data:`usvsim.task.weather_draw.WEATHER_SETS`): the
    stress suite's 22 original sets where ``sets`` is the whole suite."""
    from usvsim.task.weather_draw import WEATHER_SETS

    return [s for s in sets if s not in WEATHER_SETS]


def seed_rates(
    payloads: Sequence[Mapping[str, Any]], rename: Mapping[str, int], split: str
) -> tuple[dict[int, dict[str, float]], int]:
    """Seed -> {set: success rate} from stress JSONs (``usvsim bench --suite stress --json``) of
    one ``split``, and their episodes per set. ``rename`` maps a helmsman label of the rows to
    its seed; rows of other helmsmen are ignored.

    Raises
    ------
    UserError
        A JSON of another split or episode count, a seed with no rows or rows twice, or seeds
        that ran different sets.
    """
    rates: dict[int, dict[str, float]] = {}
    episodes = {int(p["episodes_per_set"]) for p in payloads}
    for p in payloads:
        if p.get("split", "test") != split:
            raise UserError(f"a --{split} JSON holds the {p.get('split', 'test')} split")
        for row in p["rows"]:
            seed = rename.get(row["helmsman"])
            if seed is None:
                continue
            per_set = rates.setdefault(seed, {})
            if row["episode_set"] in per_set:
                raise UserError(f"seed {seed}: set {row['episode_set']!r} twice in the {split}")
            per_set[row["episode_set"]] = float(row["success_rate"])
    missing = [f"{h} (seed {s})" for h, s in rename.items() if s not in rates]
    if missing:
        raise UserError(f"no {split} rows for {', '.join(missing)}")
    if len(episodes) != 1:
        raise UserError(f"the {split} JSONs ran {sorted(episodes)} episodes per set; need one")
    sets = {frozenset(v) for v in rates.values()}
    if len(sets) != 1:
        raise UserError(f"the seeds ran different {split} sets")
    return dict(sorted(rates.items())), episodes.pop()


@selection_mode("the shipped-seed rule")
def pick_seed(validation: Mapping[int, Mapping[str, float]], sets: Sequence[str]) -> int:
    """The seed :data:`SEED_RULE` picks from each seed's **validation** success per set: the
    median mean over ``sets`` (the lower median for an even count, ties by seed).

    >>> pick_seed({0: {"a": 0.9}, 1: {"a": 1.0}, 2: {"a": 0.8}}, ["a"])
    0
    """
    means = {seed: float(np.mean([v[s] for s in sets])) for seed, v in validation.items()}
    ranked = sorted(means, key=lambda seed: (means[seed], seed))
    return ranked[(len(ranked) - 1) // 2]


def seed_table(
    setup: str,
    validation: Sequence[Mapping[str, Any]],
    test: Sequence[Mapping[str, Any]],
    rename: Mapping[str, int],
    rule_sets: RuleSets = "all",
    command: str = "",
    provenance: str = "",
    reps: int = BOOTSTRAP_REPS,
) -> SeedTable:
    """The :class:`SeedTable` of ``setup`` from its seeds' stress JSONs (``validation`` and
    ``test`` split payloads; ``rename``: helmsman label -> seed). Needs rliable."""
    val, _ = seed_rates(validation, rename, "validation")
    tst, episodes = seed_rates(test, rename, "test")
    if val.keys() != tst.keys():
        raise UserError("the validation and test JSONs hold different seeds")
    seeds = tuple(tst)
    val_sets = list(next(iter(val.values())))
    rule = val_sets if rule_sets == "all" else original_sets(val_sets)
    picked = pick_seed(val, rule)
    sets = list(next(iter(tst.values())))
    scores = np.array([[tst[seed][s] for s in sets] for seed in seeds])  # (seeds, sets)
    figures = []
    for j, name in enumerate(sets):
        point, ci = iqm_with_interval(scores[:, j : j + 1], reps)
        figures.append(SeedFigure(name, point, ci, tuple(float(x) for x in scores[:, j])))
    cols = [j for j, s in enumerate(sets) if s in original_sets(sets)]
    means = scores[:, cols].mean(axis=1, keepdims=True)  # (seeds, 1): each seed's mean
    point, ci = iqm_with_interval(means, reps)
    return SeedTable(
        setup=setup,
        seeds=seeds,
        split="test",
        episodes_per_set=episodes,
        sets=tuple(figures),
        original=SeedFigure("original sets", point, ci, tuple(float(m) for m in means[:, 0])),
        validation_means={s: float(np.mean([val[s][k] for k in rule])) for s in seeds},
        rule_sets=rule_sets,
        picked_seed=picked,
        command=command,
        provenance=provenance,
    )


def write_seed_table(table: SeedTable, path: Path) -> None:
    """``table`` as JSON at ``path``, written atomically."""
    from usvsim.common.fileio import atomic_write_text

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps(table.to_json(), indent=2, allow_nan=False) + "\n")


def load_seed_tables(folder: Path | None = None) -> dict[str, SeedTable]:
    """Setup -> its :class:`SeedTable`, from every ``*.json`` in ``folder`` (default
    :data:`SEEDS_DIR`); ``{}`` if there is no such folder.

    Raises
    ------
    UserError
        One line naming a file that cannot be read as a seed table.
    """
    root = SEEDS_DIR if folder is None else folder
    tables: dict[str, SeedTable] = {}
    for path in sorted(root.glob("*.json")) if root.is_dir() else []:
        try:
            table = SeedTable.from_json(json.loads(path.read_text()))
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise UserError(f"{path}: not a seed table ({type(err).__name__}: {err})") from None
        if not all(math.isfinite(f.iqm) for f in table.sets):
            raise UserError(f"{path}: a set's IQM is not a number")
        tables[table.setup] = table
    return tables


def seed_tables_for(
    helmsmen: Sequence[str], models_dir: Path | None = None, folder: Path | None = None
) -> dict[str, SeedTable]:
    """Helmsman label -> the :class:`SeedTable` of the setup its shipped file was trained with
    (the model card's ``setup``), for each label that names a shipped model (by file name or
    alias, :func:`usvsim.helm.registry.model_aliases`) whose setup has seed figures."""
    tables = load_seed_tables(folder)
    if not tables:
        return {}
    from usvsim.evaluation.model_cards import shipped_setups

    setups = shipped_setups(helmsmen, models_dir)
    return {label: tables[s] for label, s in setups.items() if s in tables}


def seed_header(tables: Mapping[str, SeedTable]) -> str:
    """The column header: :attr:`SeedTable.label` where every table has as many seeds."""
    labels = {t.label for t in tables.values()}
    return labels.pop() if len(labels) == 1 else "IQM over N seeds [95 % CI]"


def with_seed_columns(
    table: str, rows: Sequence[Any], tables: Mapping[str, SeedTable], split: str
) -> str:
    """``table`` (:func:`usvsim.evaluation.bench.format_table` of stress ``rows`` of ``split``)
    with an "IQM over N seeds [95 % CI]" column filled on the rows of helmsmen in ``tables``
    (:func:`seed_tables_for`) and a line per setup saying where the figures come from;
    unchanged where no table reports ``split``."""
    from usvsim.evaluation.bench_sweep import append_columns

    shown = {h: t for h, t in tables.items() if t.split == split}
    if not shown:
        return table
    cells = []
    for row in rows:
        figure = shown[row.helmsman].figure(row.episode_set) if row.helmsman in shown else None
        cells.append((figure.cell() if figure else "",))
    lines = [append_columns(table, (seed_header(shown),), cells)]
    for helmsman, t in shown.items():
        lines.append(
            f"{helmsman}: IQM over seeds {', '.join(map(str, t.seeds))} of setup {t.setup} "
            f"({t.episodes_per_set} episodes per set, {t.split} split; "
            f"usvsim/models/seeds/{t.setup}.json); the seed rule picks seed {t.picked_seed}"
        )
    return "\n".join(lines)
