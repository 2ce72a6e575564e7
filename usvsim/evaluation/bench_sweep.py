"""``usvsim bench --sweep DIR``: a training sweep's across-seed columns beside the shipped models.

A sweep (``usvsim sweep``, :mod:`learning.experiments.sweep_report`) leaves ``report.json`` in
its folder; per arm it holds the held-out success of every seed's ``best.pt``, their
interquartile mean (IQM) and its 95 % stratified-bootstrap interval (Agarwal et al. 2021). The
bench's table shows, on the held-out row of each shipped model trained with a setup of the
sweep (its model card's ``setup``), two more columns: ``sweep seeds``
(finished seeds, crashed ones noted) and ``sweep held-out IQM [95 % CI]``. Only arms without
hyperparameter overrides are shown: the shipped models were trained with the setups' own
values. The file is read as plain JSON (no import of ``learning``); the sweep's held-out
episodes are the first ``spec.heldout`` of the same generator as the bench's ``--heldout``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from usvsim.common.errors import UserError

__all__ = [
    "SWEEP_HEADER",
    "SweepArm",
    "SweepColumns",
    "append_columns",
    "load_sweep",
    "with_sweep_columns",
]

SWEEP_HEADER = ("sweep seeds", "sweep held-out IQM [95 % CI]")


@dataclass(frozen=True)
class SweepArm:
    """One setup of a sweep as the bench shows it."""

    setup: str
    seeds: int  # finished seeds
    crashed: int  # crashed seeds
    iqm: float  # held-out IQM over the finished seeds; NaN if none
    ci95: tuple[float, float] | None  # 95 % stratified-bootstrap interval of the IQM

    def cells(self) -> tuple[str, str]:
        """The two table cells (``"5"``, ``"99.0 % [96.2, 100.0]"``)."""
        seeds = f"{self.seeds}" + (f" ({self.crashed} crashed)" if self.crashed else "")
        if not math.isfinite(self.iqm):
            return seeds, "–"
        ci = f" [{100 * self.ci95[0]:.1f}, {100 * self.ci95[1]:.1f}]" if self.ci95 else ""
        return seeds, f"{100 * self.iqm:.1f} %{ci}"

    def to_json(self) -> dict[str, Any]:
        return {
            "setup": self.setup,
            "seeds": self.seeds,
            "crashed_seeds": self.crashed,
            "heldout_iqm": self.iqm if math.isfinite(self.iqm) else None,
            "heldout_iqm_ci95": list(self.ci95) if self.ci95 else None,
        }


@dataclass(frozen=True)
class SweepColumns:
    """What ``--sweep DIR`` adds: the sweep's arms by setup and where they come from."""

    folder: Path
    name: str
    heldout_episodes: int  # per best.pt in the sweep
    arms: Mapping[str, SweepArm]

    def to_json(self) -> dict[str, Any]:
        return {
            "folder": str(self.folder),
            "name": self.name,
            "heldout_episodes": self.heldout_episodes,
            "arms": [a.to_json() for a in self.arms.values()],
        }


def _not_a_sweep(folder: Path, why: str) -> UserError:
    return UserError(f"--sweep {folder}: not a sweep folder ({why}); give a usvsim sweep --out")


def load_sweep(folder: str | Path) -> SweepColumns:
    """The across-seed columns of the sweep in ``folder`` (its ``report.json``).

    Raises
    ------
    UserError
        One line naming the folder if it is not a finished sweep's folder.
    """
    root = Path(folder)
    path = root / "report.json"
    if not root.is_dir():
        raise _not_a_sweep(root, "no such folder")
    if not path.is_file():
        hint = "; run usvsim sweep --report-only" if (root / "trials.json").is_file() else ""
        raise _not_a_sweep(root, f"no report.json{hint}")
    try:
        report = json.loads(path.read_text())
        spec, rows = report["spec"], report["arms"]
        arms = {r["setup"]: _arm(r) for r in rows if not r["overrides"]}
        heldout = int(spec["heldout"])
        name = str(spec["name"])
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise _not_a_sweep(root, f"report.json unreadable: {type(err).__name__} {err}") from None
    return SweepColumns(root, name, heldout, arms)


def _arm(row: Mapping[str, Any]) -> SweepArm:
    ci = row["heldout_iqm_ci95"]
    iqm = row["heldout_iqm"]
    return SweepArm(
        setup=str(row["setup"]),
        seeds=len(row["seeds"]),
        crashed=len(row["crashed_seeds"]),
        iqm=math.nan if iqm is None else float(iqm),
        ci95=(float(ci[0]), float(ci[1])) if ci else None,
    )


def with_sweep_columns(table: str, rows: Sequence[Any], sweep: SweepColumns) -> str:
    """``table`` (:func:`usvsim.evaluation.bench.format_table` of ``rows``: a header line, a
    rule, one line per row) with :data:`SWEEP_HEADER` columns on the right, filled on the
    held-out row of each shipped model trained with a setup of the sweep (its card's
    ``setup``; a checkpoint named after a setup counts too), and a line saying where the numbers
    come from."""
    from usvsim.evaluation.model_cards import shipped_setups

    setups = shipped_setups(sorted({r.helmsman for r in rows}))
    cells = [_row_cells(r, sweep, setups.get(r.helmsman, r.helmsman)) for r in rows]
    out = append_columns(table, SWEEP_HEADER, cells).splitlines()
    shown = sorted(h for h in {r.helmsman for r in rows} if setups.get(h, h) in sweep.arms)
    out.append(
        f"sweep {sweep.name} ({sweep.folder}/report.json): IQM over seeds of each seed's best.pt "
        f"on {sweep.heldout_episodes} held-out episodes; shown for "
        + (", ".join(shown) if shown else "no helmsman of this table (none of its setups)")
    )
    return "\n".join(out)


def append_columns(table: str, header: Sequence[str], cells: Sequence[Sequence[str]]) -> str:
    """``table`` (a fixed-width table: a header line, a rule, one line per row, as
    :func:`usvsim.evaluation.bench.format_table` writes) with the columns ``header`` on the
    right, row k's cells ``cells[k]`` (``""`` for none).

    >>> print(append_columns("a  b\\n-  -\\n1  2", ["c"], [["x"]]))
    a  b  c
    -  -  -
    1  2  x
    """
    lines = table.splitlines()
    if len(lines) != len(cells) + 2:
        raise ValueError(
            f"a table of {len(cells)} rows has {len(lines)} lines, not {len(cells) + 2}"
        )
    grid = [tuple(header), *(tuple(c) for c in cells)]
    widths = [max(len(c[i]) for c in grid) for i in range(len(header))]
    left = max(len(line) for line in lines)
    out = []
    for k, line in enumerate(lines):  # header, rule, then row k - 2 (grid[k - 1])
        if k == 1:
            extra = ["-" * w for w in widths]
        else:
            extra = [c.ljust(w) for c, w in zip(grid[max(k - 1, 0)], widths, strict=True)]
        out.append((line.ljust(left) + "  " + "  ".join(extra)).rstrip())
    return "\n".join(out)


def _row_cells(row: Any, sweep: SweepColumns, setup: str) -> tuple[str, str]:
    arm = sweep.arms.get(setup)
    if arm is None or row.episode_set != "held-out":
        return "", ""
    return arm.cells()
