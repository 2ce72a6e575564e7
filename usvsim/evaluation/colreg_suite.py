"""``usvsim bench --suite colreg``: every traffic-capable helmsman on the standard encounter sets,
scored for success and COLREG compliance.

Sets (:data:`COLREG_SETS`): ``imazu-01`` … ``imazu-22``, Imazu's problems scaled to the boat
(:mod:`usvsim.evaluation.imazu`), and ``trafficgen-1ts`` / ``-2ts`` / ``-3ts``, DNV
trafficgen's 55 baseline situations with one (5), two (15) and three (35) targets, DNV's own
files (:mod:`usvsim.evaluation.trafficgen_io`, in ``usvsim/evaluation/data/trafficgen`` with
their MIT licence; episode k runs situation k mod S, so ``n`` ≥ S covers every situation).
Each set draws its ``n`` perturbed episodes from its own seeds, the ``test`` split by default
(``validation`` for choosing). ``reactive_targets`` (per set, or ``--reactive-targets`` for all)
steers the target vessels with ``vo`` (:mod:`usvsim.evaluation.colreg_rollout`); by default
they hold course and speed, as Imazu's problems are defined.

Every episode is recorded as own-ship and target tracks and scored by
:func:`usvsim.evaluation.colreg.evaluate_colreg` (Woerner et al. 2019). A row (set × helmsman):
success with its Wilson 95 % interval (:mod:`usvsim.evaluation.bench`'s strict success),
collisions, COLREG compliance (the share of scored encounters that pass) with its Wilson
interval, the mean score and the violations per rule. Files
(:mod:`usvsim.evaluation.colreg_report`): ``colreg.md``, ``colreg.csv``, ``colreg-heatmap.png``
(success, compliance and collisions, sets × helmsmen); ``--json`` prints the same on stdout.

Which helmsmen: by default every available one (:func:`usvsim.helm.registry.available_helmsmen`)
that is made to meet traffic (:func:`traffic_fitness`): not ``los``, which never looks at
obstacles, nor the models trained on the study's pole task (model card task ``study``: one static
pole, never a moving vessel; the ``positional`` ones see only the nearest obstacle's position,
no velocity and no second vessel). ``--helmsmen all`` runs them too, labelled (``helmsmen_traffic``
in the JSON, a dagger in the Markdown); ``--helmsmen`` names others.
"""

from __future__ import annotations

import math
import sys
import time
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from usvsim.common.splits import check_test_draw
from usvsim.evaluation.stats import Proportion, proportion

__all__ = [
    "COLREG_SETS",
    "TRAFFIC_BLIND",
    "ColregRow",
    "ColregSet",
    "ColregSuiteResult",
    "TrafficFitness",
    "colreg_columns",
    "colreg_compliance",
    "colreg_episodes",
    "colreg_row",
    "colreg_set_names",
    "encounters_by_type",
    "made_for_traffic",
    "run_colreg",
    "run_colreg_args",
    "select_colreg_sets",
    "traffic_fitness",
    "user_trafficgen_set",
]

Split = Literal["validation", "test"]
TRAFFIC_BLIND = ("los",)  # helmsmen that never look at traffic: left out by default
# usvsim.helm.registry's classical helmsmen
BASELINES = ("los", "los-avoid", "vo", "sb-mpc", "vo-radar", "sb-mpc-radar")
TRAFFICGEN_DIR = Path(__file__).resolve().parent / "data" / "trafficgen"


@dataclass(frozen=True)
class ColregSet:
    """A named encounter set: an Imazu problem or trafficgen situation files."""

    name: str
    description: str
    imazu_problem: int = 0  # 1-22, or 0 for a trafficgen set
    trafficgen_files: tuple[str, ...] = ()  # paths of situation files (trafficgen sets)
    reactive_targets: bool = False  # targets steered by vo (module docstring)

    def seed(self, split: Split) -> int:
        """The set's seed for a split: CRC-32 of ``name/split``."""
        return zlib.crc32(f"{self.name}/{split}".encode())


_IMAZU_KINDS = {1: "head-on", 2: "crossing, give way", 3: "overtaking", 4: "crossing, stand on"}
COLREG_SETS: tuple[ColregSet, ...] = (
    *(
        ColregSet(
            f"imazu-{p:02d}",
            f"Imazu problem {p}: "
            + (_IMAZU_KINDS[p] if p in _IMAZU_KINDS else f"{1 + (p >= 12) + (p >= 5)} targets"),
            imazu_problem=p,
        )
        for p in range(1, 23)
    ),
    *(
        ColregSet(
            f"trafficgen-{k}ts",
            f"DNV trafficgen's {len(files)} baseline situations with {k} target"
            + ("s" if k > 1 else "")
            + (" (HO, CR-GW, CR-SO, OT-GW, OT-SO)" if k == 1 else " (every combination)"),
            trafficgen_files=tuple(
                str(TRAFFICGEN_DIR / f"baseline_situation_{i:02d}.json") for i in files
            ),
        )
        for k, files in ((1, range(1, 6)), (2, range(6, 21)), (3, range(21, 56)))
    ),
)


def colreg_set_names() -> tuple[str, ...]:
    return tuple(s.name for s in COLREG_SETS)


def select_colreg_sets(names: Sequence[str]) -> tuple[ColregSet, ...]:
    """The sets named (all for an empty list), in the suite's order; ``UserError`` if unknown."""
    from usvsim.common.errors import UserError

    known = colreg_set_names()
    unknown = [n for n in names if n not in known]
    if unknown:
        raise UserError(f"unknown colreg set {unknown[0]!r}; choose from {', '.join(known)}")
    return tuple(s for s in COLREG_SETS if not names or s.name in names)


def user_trafficgen_set(path: str) -> ColregSet:
    """The set ``trafficgen-user`` of a situation file or a folder of them (``--trafficgen``);
    every file is read and checked now: ``UserError`` (one line naming the file and field)."""
    from usvsim.common.errors import UserError
    from usvsim.evaluation.trafficgen_io import read_situation

    p = Path(path)
    files = sorted(p.glob("*.json")) if p.is_dir() else [p]
    if not p.exists() or not files:
        raise UserError(f"--trafficgen {path}: no such file, or a folder without .json files")
    for f in files:
        read_situation(f)
    return ColregSet(
        "trafficgen-user",
        f"trafficgen situations from {path}",
        trafficgen_files=tuple(str(f) for f in files),
    )


def colreg_episodes(cset: ColregSet, n: int, split: Split = "test") -> tuple[Any, ...]:
    """The ``n`` episodes of a set (module docstring); ``UserError`` for a bad situation file."""
    if cset.imazu_problem:
        from usvsim.evaluation.imazu import imazu_episodes

        return imazu_episodes(cset.imazu_problem, n, split)
    from usvsim.evaluation.trafficgen_io import read_situation, situation_episodes

    situations = [read_situation(f) for f in cset.trafficgen_files]
    if not situations:
        from usvsim.common.errors import UserError

        raise UserError(f"colreg set {cset.name}: no trafficgen situation files")
    if split == "test":
        check_test_draw(cset.name)
    seed = cset.seed(split)
    return tuple(
        situation_episodes(situations[k % len(situations)], np.random.default_rng([seed, k]))
        for k in range(n)
    )


@dataclass(frozen=True)
class ColregRow:
    """One cell of the suite: a helmsman on one set."""

    helmsman: str
    episode_set: str
    success: Proportion
    collisions: int
    compliance: Proportion  # passed / scored encounters (Woerner et al. 2019)
    mean_score: float  # mean encounter score in [0, 1]; NaN without encounters
    violations: dict[str, int] = field(default_factory=dict)  # failed encounters per rule
    wall_s: float = 0.0  # s, evaluation and scoring of the set
    by_type: dict[str, int] = field(default_factory=dict)  # scored encounters per type

    def flat(self) -> dict[str, Any]:
        """Flat dict for CSV and JSON."""
        s, c = self.success, self.compliance
        return {
            "helmsman": self.helmsman,
            "episode_set": self.episode_set,
            "episodes": s.n,
            "successes": s.successes,
            "success_rate": s.rate,
            "success_ci95_low": s.lower,
            "success_ci95_high": s.upper,
            "collisions": self.collisions,
            "encounters": c.n,
            "compliant": c.successes,
            "compliance_rate": c.rate,
            "compliance_ci95_low": c.lower,
            "compliance_ci95_high": c.upper,
            "mean_score": self.mean_score,
            **{f"violations_{k}": v for k, v in sorted(self.violations.items())},
            **{f"encounters_{k}": v for k, v in sorted(self.by_type.items())},
            "wall_s": self.wall_s,
        }


def _empty() -> Proportion:
    """No trials: rate and interval NaN (shown as "–")."""
    return Proportion(0, 0, math.nan, math.nan, math.nan, 0.95)


def colreg_compliance(result: Any) -> tuple[Proportion, float, dict[str, int]]:
    """Compliance (passed / scored encounters, Wilson interval), mean score and per-rule counts
    of a :class:`usvsim.evaluation.colreg.ColregResult`, from the scorer's own summary
    (:func:`usvsim.evaluation.colreg.summarize_colreg`): per encounter type the failed
    encounters (``<type>_failed``), per penalty component the encounters it hit."""
    from usvsim.evaluation.colreg import summarize_colreg

    summary = summarize_colreg(result)
    per_rule = {
        f"{name}_failed": d["encounters"] - d["passed"]
        for name, d in summary.by_type.items()
        if d["encounters"]
    }
    per_rule.update({name: n for name, n in summary.penalty_counts.items() if n})
    return summary.compliance or _empty(), summary.mean_score, per_rule


def encounters_by_type(result: Any) -> dict[str, int]:
    """Scored encounters per type (``head_on``, ``overtaking_give_way``, ...) of a
    :class:`usvsim.evaluation.colreg.ColregResult`; types without one left out."""
    from usvsim.evaluation.colreg import summarize_colreg

    by = summarize_colreg(result).by_type
    return {name: d["encounters"] for name, d in by.items() if d["encounters"]}


def colreg_columns(tracks: Any) -> dict[str, Any]:
    """The COLREG columns of a stress-suite row (:class:`usvsim.evaluation.bench.BenchRow`) for
    the tracks of its episodes: encounters, compliant ones, rate with its Wilson interval, mean
    score."""
    from usvsim.evaluation.colreg import evaluate_colreg

    compliance, mean, _ = colreg_compliance(evaluate_colreg(tracks))
    return {
        "colreg_encounters": compliance.n,
        "colreg_compliant": compliance.successes,
        "colreg_compliance_rate": compliance.rate,
        "colreg_compliance_ci95_low": compliance.lower,
        "colreg_compliance_ci95_high": compliance.upper,
        "colreg_mean_score": mean,
    }


def colreg_row(helmsman: str, set_name: str, run: Any, wall_s: float) -> ColregRow:
    """The row of an :class:`usvsim.evaluation.colreg_rollout.EncounterRun`, scored."""
    from usvsim.evaluation.colreg import evaluate_colreg

    result = evaluate_colreg(run.tracks)
    compliance, mean, per_rule = colreg_compliance(result)
    ok = sum(bool(r.success) for r in run.records)
    return ColregRow(
        helmsman,
        set_name,
        proportion(ok, len(run.records)),
        sum(bool(r.collision) for r in run.records),
        compliance,
        mean,
        per_rule,
        wall_s,
        encounters_by_type(result),
    )


def made_for_traffic(name: str, cards: Any) -> bool:
    """Whether the default selection runs helmsman ``name`` (module docstring): not
    :data:`TRAFFIC_BLIND`, not a model whose card (in ``cards``) says task ``study``."""
    return name not in TRAFFIC_BLIND and (name not in cards or cards[name].task != "study")


@dataclass(frozen=True)
class TrafficFitness:
    """Whether a helmsman is made to meet traffic, and why (a label of the suite's columns)."""

    perceives: str  # what it sees of obstacles (usvsim.task.observations.PERCEPTION)
    trained_for: str  # "baseline", its model card's use, or "checkpoint" (no card)
    meets_traffic: bool
    why: str


def traffic_fitness(name: str, observation: str, cards: Any) -> TrafficFitness:
    """The :class:`TrafficFitness` of helmsman ``name`` seeing ``observation`` (kind), from its
    model card in ``cards`` (name → :class:`usvsim.evaluation.model_cards.ModelCard`) if any."""
    from usvsim.task.observations import PERCEPTION

    perceives = PERCEPTION.get(observation, observation)
    card = cards.get(name)
    if name in TRAFFIC_BLIND:
        return TrafficFitness(perceives, "baseline", False, "steers for the goal only (LOS)")
    if card is None:
        if name in BASELINES:
            return TrafficFitness(perceives, "baseline", True, "a classical COLAV")
        ok = observation != "positional"
        why = "a checkpoint without a model card, judged by its observation" + (
            "" if ok else ": the nearest obstacle's position only"
        )
        return TrafficFitness(perceives, "checkpoint", ok, why)
    if card.task == "study":
        sees = (
            "sees only the nearest obstacle's position (no velocity, no second vessel)"
            if observation == "positional"
            else "sees one radar image (no target velocity)"
        )
        return TrafficFitness(
            perceives,
            card.use,
            False,
            f"trained on the study's static pole, never a vessel; {sees}",
        )
    return TrafficFitness(perceives, card.use, True, "trained on the open-water family (vessels)")


@dataclass(frozen=True)
class ColregSuiteResult:
    """Rows (set × helmsman) and timing of one suite run."""

    rows: tuple[ColregRow, ...]
    sets: tuple[str, ...]
    helmsmen: tuple[str, ...]
    episodes_per_set: int
    split: str
    reactive_targets: bool
    wall_s: float
    interrupted: bool = False
    skipped: tuple[str, ...] = ()
    fitness: dict[str, TrafficFitness] = field(default_factory=dict)  # per helmsman

    def pooled(self, helmsman: str, prefix: str = "imazu-") -> tuple[Proportion, Proportion]:
        """Success and compliance of ``helmsman`` pooled over the sets named ``prefix*``."""
        rows = [r for r in self.rows if r.helmsman == helmsman and r.episode_set.startswith(prefix)]
        s = sum(r.success.successes for r in rows), sum(r.success.n for r in rows)
        c = sum(r.compliance.successes for r in rows), sum(r.compliance.n for r in rows)
        return (proportion(*s) if s[1] else _empty()), (proportion(*c) if c[1] else _empty())


def run_colreg(
    factories: dict[str, Any],
    sets: Sequence[ColregSet],
    n: int,
    *,
    split: Split = "test",
    reactive_targets: bool = False,
    progress: bool = True,
    skipped: Sequence[str] = (),
) -> ColregSuiteResult:
    """Every helmsman of ``factories`` (label → factory) on ``n`` episodes of every set; a set's
    episodes are drawn once for all helmsmen, and a helmsman runs all its sets in one batch
    (``wall_s`` of a row: the batch's time over its sets). Ctrl-C ends it early with the
    helmsmen finished so far."""
    from tqdm import tqdm

    from usvsim.evaluation.colreg_rollout import run_encounters
    from usvsim.evaluation.model_cards import load_cards
    from usvsim.helm.registry import helmsman_kinds

    cards = load_cards()
    fitness: dict[str, TrafficFitness] = {}
    start = time.perf_counter()
    bar = tqdm(
        total=len(sets) * len(factories),
        desc="colreg",
        unit="run",
        file=sys.stderr,
        disable=not progress,
    )
    interrupted = False
    rows_by: dict[tuple[str, str], ColregRow] = {}
    try:
        episodes = {s.name: colreg_episodes(s, n, split) for s in sets}  # bad files fail first
        groups = [[s for s in sets if (reactive_targets or s.reactive_targets) == flag]
                  for flag in (False, True)]  # fmt: skip
        for name, factory in factories.items():
            # every set of a helmsman in one batch (one model load, one vectorised rollout)
            for flag, group in zip((False, True), groups, strict=True):
                if not group:
                    continue
                bar.set_postfix_str(f"{name} ({len(group)} sets)")
                t0 = time.perf_counter()
                batch = [e for s in group for e in episodes[s.name]]
                helmsman = factory()
                fitness[name] = traffic_fitness(name, helmsman_kinds(helmsman)[0], cards)
                run = run_encounters(helmsman, batch, reactive_targets=flag)
                wall = (time.perf_counter() - t0) / len(group)
                for i, cset in enumerate(group):
                    part = run.part(slice(i * n, (i + 1) * n))
                    rows_by[(cset.name, name)] = colreg_row(name, cset.name, part, wall)
                    bar.update()
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    rows = [rows_by[(s.name, h)] for s in sets for h in factories if (s.name, h) in rows_by]
    return ColregSuiteResult(
        tuple(rows),
        tuple(s.name for s in sets),
        tuple(factories),
        n,
        split,
        reactive_targets,
        time.perf_counter() - start,
        interrupted,
        tuple(skipped),
        fitness,
    )


def run_colreg_args(args: Any, progress: bool = True) -> ColregSuiteResult:
    """The suite for ``usvsim bench`` options (:class:`usvsim.evaluation.bench.BenchArgs`):
    ``--helmsmen`` (empty: every available one but :data:`TRAFFIC_BLIND`), ``--sets``,
    ``--colreg-episodes``, ``--reactive-targets``."""
    from usvsim.common.errors import UserError
    from usvsim.common.options import check_bounds
    from usvsim.evaluation.bench import loadable_helmsmen
    from usvsim.helm.registry import select_helmsmen

    check_bounds(args)
    args.check()
    sets = select_colreg_sets([n.strip() for n in args.sets.split(",") if n.strip()])

    def warn(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    if args.trafficgen:  # the user's files: every one read (and checked) before anything runs
        sets = (*sets, user_trafficgen_set(args.trafficgen))
    chosen = select_helmsmen(args.names())
    if not args.names():  # made for traffic only (module docstring)
        from usvsim.evaluation.model_cards import load_cards

        cards = load_cards()
        chosen = {k: v for k, v in chosen.items() if made_for_traffic(k, cards)}
    factories, skipped = loadable_helmsmen(chosen, bool(args.names()), warn)
    if not factories:
        raise UserError("no helmsman to compare: " + "; ".join(skipped))
    return run_colreg(
        factories,
        sets,
        args.colreg_episodes,
        split=args.split,
        reactive_targets=args.reactive_targets,
        progress=progress,
        skipped=skipped,
    )
