"""The files and progress display of a training run, shared by RL and IL (``usvsim train``).

``log.csv`` and ``curve.png`` (:class:`RunLog`, :func:`plot_learning_curve`), the milestones of
the validations (:class:`Milestones`), reading a log back for ``--resume``
(:func:`read_log_rows`) and the tqdm bar (:func:`progress_bar`, :func:`advance`). The columns
and the run itself are :mod:`learning.experiments.train_rl`'s (RL) and
:mod:`learning.experiments.train_il`'s (IL).

With a TensorBoard folder (``usvsim train --tensorboard DIR``, ``usvsim sweep --tensorboard
DIR``) :class:`RunLog` also writes every row as TensorBoard scalars (torch's
:class:`~torch.utils.tensorboard.SummaryWriter`; ``pip install "usvsim[tensorboard]"``), as
Stable-Baselines3 and CleanRL do: one scalar per ``log.csv`` column, tagged
:func:`scalar_tag` (``train/mean_return``, ``validation/val_successes``, ``time/rollout_s``),
at step ``env_steps`` (the x axis of ``curve.png``; validation columns on validation
iterations only). A resumed run hides the events its checkpoint had not reached
(``purge_step``), as it drops those rows of ``log.csv``.
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

from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_savefig, atomic_write_text

__all__ = [
    "VALIDATION_EPISODES",
    "Milestones",
    "RunLog",
    "advance",
    "check_tensorboard",
    "plot_learning_curve",
    "progress_bar",
    "read_log_rows",
    "scalar_tag",
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


def scalar_tag(column: str) -> str:
    """The TensorBoard tag of a ``log.csv`` column, grouped as SB3 groups its scalars:
    ``validation/`` for ``val_*``, ``time/`` for the wall-clock columns (``*_s``), ``train/``
    for the rest."""
    if column.startswith("val_"):
        return f"validation/{column}"
    return f"time/{column}" if column.endswith("_s") else f"train/{column}"


def check_tensorboard(option: str = "--tensorboard") -> None:
    """Raise :class:`UserError` (naming ``option`` and the extra to install) where torch's
    TensorBoard writer cannot be imported; called before a run starts."""
    try:
        from torch.utils.tensorboard import SummaryWriter  # noqa: F401
    except ImportError:
        raise UserError(
            f'{option} needs the tensorboard package: pip install "usvsim[tensorboard]"'
        ) from None


class RunLog:
    """A run's ``log.csv`` (one row per iteration, ``fields`` columns) and ``curve.png``, and
    with ``tensorboard`` (a folder) its TensorBoard scalars (module docstring).

    ``return_key`` names the column plotted as the training return and ``return_label`` its
    axis label. Both files are rewritten atomically; :meth:`plot_due` limits the plot (the
    slow part) to once per 30 s of a long run, and an unchanged log is not plotted again.
    :meth:`write_scalars` adds the rows not yet in the event file (call it once per iteration,
    after the row is complete); :meth:`close` writes the rest and closes the event file.
    """

    def __init__(
        self,
        out: Path,
        fields: Sequence[str],
        title: str,
        rows: list[dict[str, Any]],
        return_key: str = "mean_return",
        return_label: str = "training return\n(fixed-horizon)",
        tensorboard: str | Path | None = None,
    ) -> None:
        self.out, self.fields, self.title, self.rows = out, tuple(fields), title, rows
        self.return_key, self.return_label = return_key, return_label
        self.last_plot = 0.0
        self.plotted_rows = -1  # len(rows) at the last plot
        self.scalar_rows = len(rows)  # rows already in the event file (a resumed run's kept ones)
        self.tensorboard: Any = None
        if tensorboard:
            from torch.utils.tensorboard import SummaryWriter

            # a resumed run redoes the iterations after its checkpoint: hide their old events
            purge = int(rows[-1]["env_steps"]) + 1 if rows else None
            self.tensorboard = SummaryWriter(log_dir=str(tensorboard), purge_step=purge)

    def plot_due(self) -> bool:
        return time.monotonic() - self.last_plot > 30.0

    def write_scalars(self) -> None:
        """Add the rows not yet written to the TensorBoard event file (none without one)."""
        if self.tensorboard is None:
            return
        for row in self.rows[self.scalar_rows :]:
            step = int(row["env_steps"])
            for column in self.fields:
                value = _scalar(row.get(column))
                if column != "env_steps" and value is not None:
                    self.tensorboard.add_scalar(scalar_tag(column), value, step)
        self.scalar_rows = len(self.rows)
        self.tensorboard.flush()

    def close(self) -> None:
        """Write the last scalars and close the event file (a no-op without one, or twice)."""
        if self.tensorboard is not None:
            self.write_scalars()
            self.tensorboard.close()
            self.tensorboard = None

    def write(self, plot: bool = True) -> None:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=self.fields, restval="")
        writer.writeheader()
        writer.writerows(self.rows)
        atomic_write_text(self.out / "log.csv", buf.getvalue())
        self.write_scalars()
        if plot and len(self.rows) != self.plotted_rows:
            self.last_plot, self.plotted_rows = time.monotonic(), len(self.rows)
            plot_learning_curve(
                self.rows, self.out / "curve.png", self.title, self.return_key, self.return_label
            )


def _scalar(value: Any) -> float | None:
    """A log cell as a TensorBoard scalar; None for an empty cell (a non-validation iteration's
    validation columns) or one that is not a number."""
    if value is None or value == "":
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


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
