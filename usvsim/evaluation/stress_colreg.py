"""COLREG compliance columns of the stress suite's traffic sets (issue 39).

A stress set *has traffic* when its scenario draws moving vessels (``moving-vessels`` and
``everything``: :func:`has_traffic`). For those sets every helmsman's records are turned into
own-ship and target tracks (:func:`usvsim.evaluation.colreg_rollout.encounter_tracks`, 1 s
samples, the targets' own motion laws) and scored by the same scorer as the COLREG suite
(:func:`usvsim.evaluation.colreg.evaluate_colreg`, Woerner et al. 2019). A row of the stress
table then carries (:class:`StressRow`, the other sets NaN and 0):

===============================  ==============================================================
``colreg_encounters``            encounters scored (own ship × target pairs with a risk of
                                 collision inside the entry range)
``colreg_compliant``             of those, the ones that pass
``colreg_compliance_rate``       compliant / encounters, with its Wilson 95 % interval
``colreg_compliance_ci95_low``   (``..._high``)
``colreg_mean_score``            mean encounter score in [0, 1]
``colreg_s``                     s, time spent making the tracks and scoring them (the overhead
                                 of the columns on the set's run, :func:`colreg_overhead`)
===============================  ==============================================================
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

from usvsim.evaluation.bench import BenchRow

__all__ = [
    "StressRow",
    "colreg_markdown_table",
    "colreg_overhead",
    "has_traffic",
    "stress_row",
]


@dataclass(frozen=True)
class StressRow(BenchRow):
    """A stress-suite row: :class:`usvsim.evaluation.bench.BenchRow` and the COLREG columns
    (module docstring; NaN and 0 on a set without traffic)."""

    colreg_encounters: int = 0
    colreg_compliant: int = 0
    colreg_compliance_rate: float = math.nan
    colreg_compliance_ci95_low: float = math.nan
    colreg_compliance_ci95_high: float = math.nan
    colreg_mean_score: float = math.nan
    colreg_s: float = 0.0  # s, tracks and scoring (included in wall_s)


def has_traffic(stress_set: Any) -> bool:
    """Whether a :class:`usvsim.evaluation.stress.StressSet` draws moving vessels."""
    scenario = stress_set.scenario
    return scenario is not None and scenario.n_vessels_range[1] > 0


def stress_row(
    row: BenchRow, stress_set: Any, records: Sequence[Any], *, colreg: bool = True
) -> StressRow:
    """``row`` with the COLREG columns of ``records`` (open-water records of a traffic set;
    other sets, or ``colreg=False``: the empty columns). The scoring time is added to
    ``wall_s`` and kept in ``colreg_s``."""
    base = {f.name: getattr(row, f.name) for f in fields(BenchRow)}
    if not (colreg and has_traffic(stress_set)):
        return StressRow(**base)
    from usvsim.evaluation.colreg_rollout import encounter_tracks
    from usvsim.evaluation.colreg_suite import colreg_columns

    t0 = time.perf_counter()
    columns = colreg_columns(encounter_tracks(records))
    spent = time.perf_counter() - t0
    base["wall_s"] = row.wall_s + spent
    return StressRow(**base, **columns, colreg_s=spent)


def colreg_overhead(rows: Sequence[Any]) -> float:
    """Scoring time over the time of the runs it scored (traffic rows only): the share the
    COLREG columns add to those sets' run time; NaN without scored rows."""
    scored = [r for r in rows if getattr(r, "colreg_s", 0.0) > 0.0]
    run = sum(r.wall_s - r.colreg_s for r in scored)
    return sum(r.colreg_s for r in scored) / run if run > 0.0 else math.nan


def colreg_markdown_table(rows: Sequence[Any], sets: Sequence[str], helmsmen: Sequence[str]) -> str:
    """The traffic sets' COLREG table (sets × helmsmen): compliance [Wilson 95 %] of the scored
    encounters, mean score and the number of encounters; empty if no row was scored."""
    by = {(r.episode_set, r.helmsman): r for r in rows if getattr(r, "colreg_s", 0.0) > 0.0}
    scored_sets = [s for s in sets if any((s, h) in by for h in helmsmen)]
    if not scored_sets:
        return ""
    lines = [
        "COLREG compliance on the sets with traffic (usvsim.evaluation.colreg, after Woerner et "
        "al. 2019): compliant / scored encounters [Wilson 95 %], mean score, encounters.",
        "",
        "| set | " + " | ".join(helmsmen) + " |",
        "|---|" + "---|" * len(helmsmen),
    ]
    for s in scored_sets:
        cells = []
        for h in helmsmen:
            r = by.get((s, h))
            if r is None or r.colreg_encounters == 0:
                cells.append("–")
                continue
            low, high = r.colreg_compliance_ci95_low, r.colreg_compliance_ci95_high
            cells.append(
                f"{100 * r.colreg_compliance_rate:.1f} % [{100 * low:.1f}, {100 * high:.1f}], "
                f"{r.colreg_mean_score:.2f}, n = {r.colreg_encounters}"
            )
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    overhead = colreg_overhead(list(by.values()))
    lines += ["", f"COLREG scoring added {100 * overhead:.1f} % to these sets' run time.", ""]
    return "\n".join(lines)
