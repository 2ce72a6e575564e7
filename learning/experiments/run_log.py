"""The files and progress display of a training run, shared by RL and IL (``usvsim train``).

``log.csv`` and ``curve.png`` (:class:`RunLog`, :func:`plot_learning_curve`), the milestones of
the validations (:class:`Milestones`), reading a log back for ``--resume``
(:func:`read_log_rows`) and the tqdm bar (:func:`progress_bar`, :func:`advance`). The columns
and the run itself are :mod:`learning.experiments.train_rl`'s (RL) and
:mod:`learning.experiments.train_il`'s (IL).
"""

from __future__ import annotations

import csv
import io
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usvsim.common.fileio import atomic_savefig, atomic_write_text

__all__ = [
    "VALIDATION_EPISODES",
    "Milestones",
    "RunLog",
    "advance",
    "plot_learning_curve",
    "progress_bar",
    "read_log_rows",
]

VALIDATION_EPISODES = 15


@dataclass
class Milestones:
    """What a run's validations reached: the first >= 14/15, the first 15/15 (whole validation
    records) and how many 15/15 in a row up to the last one."""

    first_14_of_15: dict[str, Any] | None = None
    first_full: dict[str, Any] | None = None
    consecutive: int = 0

    def add(self, record: dict[str, Any]) -> None:
        """Count one validation record (``successes``, ``n_episodes``, ...), in run order."""
        successes, n = int(record["successes"]), int(record["n_episodes"])
        self.consecutive = self.consecutive + 1 if successes == n else 0
        if successes >= n - 1 and self.first_14_of_15 is None:
            self.first_14_of_15 = dict(record)
        if successes == n and self.first_full is None:
            self.first_full = dict(record)

    def stop_reason(self, stop_after: int) -> str:
        """Why to stop after ``stop_after`` consecutive 15/15 (0: never); "" to go on."""
        if stop_after > 0 and self.consecutive >= stop_after:
            return f"{stop_after} consecutive 15/15 validations"
        return ""


class RunLog:
    """A run's ``log.csv`` (one row per iteration, ``fields`` columns) and ``curve.png``.

    ``return_key`` names the column plotted as the training return and ``return_label`` its
    axis label. Both files are rewritten atomically; :meth:`plot_due` limits the plot (the
    slow part) to once per 30 s of a long run, and an unchanged log is not plotted again.
    """

    def __init__(
        self,
        out: Path,
        fields: Sequence[str],
        title: str,
        rows: list[dict[str, Any]],
        return_key: str = "mean_return",
        return_label: str = "training return\n(fixed-horizon)",
    ) -> None:
        self.out, self.fields, self.title, self.rows = out, tuple(fields), title, rows
        self.return_key, self.return_label = return_key, return_label
        self.last_plot = 0.0
        self.plotted_rows = -1  # len(rows) at the last plot

    def plot_due(self) -> bool:
        return time.monotonic() - self.last_plot > 30.0

    def write(self, plot: bool = True) -> None:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=self.fields, restval="")
        writer.writeheader()
        writer.writerows(self.rows)
        atomic_write_text(self.out / "log.csv", buf.getvalue())
        if plot and len(self.rows) != self.plotted_rows:
            self.last_plot, self.plotted_rows = time.monotonic(), len(self.rows)
            plot_learning_curve(
                self.rows, self.out / "curve.png", self.title, self.return_key, self.return_label
            )


def plot_learning_curve(
    rows: list[dict[str, Any]],
    path: Path,
    title: str,
    return_key: str = "mean_return",
    return_label: str = "training return\n(fixed-horizon)",
) -> None:
    """Training return (column ``return_key``) and validation successes against env steps."""
    from usvsim.common.mpl import use_file_backend_if_headless

    use_file_backend_if_headless()  # Agg, but a notebook's inline backend is left alone
    import matplotlib.pyplot as plt

    steps = np.array([r["env_steps"] for r in rows], dtype=float)
    ret = np.array([r[return_key] for r in rows], dtype=float)
    val = [
        (r["env_steps"], r["val_successes"])
        for r in rows
        if r.get("val_successes") != "" and "val_successes" in r
    ]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    ax1.plot(steps, ret, lw=1)
    ax1.set_ylabel(return_label)
    ax1.set_title(title)
    ax1.grid(alpha=0.3)
    if val:
        vx, vy = zip(*val, strict=True)
        ax2.plot(vx, vy, "o-", ms=3)
    ax2.axhline(VALIDATION_EPISODES, color="g", ls="--", lw=1)
    ax2.set_ylim(-0.5, VALIDATION_EPISODES + 0.5)
    ax2.set_ylabel("validation successes / 15")
    ax2.set_xlabel("environment steps (decisions)")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    atomic_savefig(fig, path, dpi=100)
    plt.close(fig)


def read_log_rows(path: Path, up_to_iteration: int) -> list[dict[str, Any]]:
    """The rows of a run's ``log.csv`` up to ``up_to_iteration`` (a resumed run's checkpoint);
    later rows, logged after that checkpoint, are dropped: the resumed run redoes them."""
    if not path.is_file():
        return []
    with path.open(newline="") as handle:
        rows = [dict(r) for r in csv.DictReader(handle)]
    kept = []
    for r in rows:
        if int(r["iteration"]) > up_to_iteration:
            break
        for key in ("iteration", "env_steps", "episodes", "line_search_accepted"):
            r[key] = int(r[key])
        if r.get("val_successes"):
            r["val_successes"] = int(r["val_successes"])
        kept.append(r)
    return kept


def progress_bar(total: int, initial: int, desc: str, quiet: bool) -> Any:
    """The run's tqdm bar (iterations, on stderr); disabled by ``quiet``."""
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit="it", file=sys.stderr, disable=quiet)


def advance(bar: Any, ret: float, kl: float, last_validation: dict[str, Any] | None) -> None:
    """One iteration on ``bar``: training return, KL and the last validation's successes."""
    bar.set_postfix(
        ret=f"{ret:.1f}",
        kl=f"{kl:.4f}",
        val="-" if last_validation is None else f"{last_validation['successes']}/15",
        refresh=False,
    )
    bar.update(1)
