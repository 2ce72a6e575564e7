"""What a sweep prints while it runs: a Ray Tune callback (:class:`Progress`) with one line per
trial start, end and crash, and every ``every_s`` seconds one line on the running trials (their
last logged iteration and validation, read from their ``log.csv``)."""

from __future__ import annotations

import csv
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ray import tune

from learning.experiments.run_log import VALIDATION_EPISODES

__all__ = ["Progress"]


def _trial_dir(trial: Any) -> str:
    from learning.experiments.sweep import trial_dir_name

    c = trial.config
    return trial_dir_name(c["setup"], int(c["seed"]), c["overrides"], c["search"])


def _last_row(log_csv: Path) -> tuple[str, str]:
    """(last iteration, last validation successes) of a run's log, "-" where none yet."""
    if not log_csv.is_file():
        return "-", "-"
    with log_csv.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    vals = [r["val_successes"] for r in rows if r.get("val_successes")]
    return (rows[-1]["iteration"] if rows else "-"), (vals[-1] if vals else "-")


class Progress(tune.Callback):
    """Progress lines of a sweep (module docstring); ``say`` prints one line."""

    def __init__(
        self, root: Path, say: Callable[[str], None], every_s: float = 30.0, total: int = 0
    ) -> None:
        """``total``: the trials the sweep will run (0: count those Tune knows so far)."""
        self.root, self.say, self.every_s, self.total = root, say, every_s, total
        self.last = time.monotonic()
        self.t0 = time.monotonic()

    def setup(
        self,
        stop: Any = None,
        num_samples: int | None = None,
        total_num_samples: int | None = None,
        **info: Any,
    ) -> None:
        """Start the clock when the experiment (or its continuation) starts."""
        self.last = self.t0 = time.monotonic()

    def _count(self, trials: list[Any], ended: Any = None, as_: str = "") -> str:
        """Counts by status; ``ended`` (a trial that just ended) counted ``as_``."""
        status = [as_ if t is ended else t.status for t in trials]
        done, crashed = status.count("TERMINATED"), status.count("ERROR")
        running = status.count("RUNNING")
        total = max(self.total, len(trials))
        return f"{done}/{total} finished, {crashed} crashed, {running} running"

    def on_trial_start(self, iteration: int, trials: list[Any], trial: Any, **info: Any) -> None:
        self.say(f"[sweep] start {_trial_dir(trial)} ({self._count(trials)})")

    def on_trial_complete(self, iteration: int, trials: list[Any], trial: Any, **info: Any) -> None:
        r = trial.last_result or {}
        first = r.get("first_full_iteration", -1)
        self.say(
            f"[sweep] done  {_trial_dir(trial)}: best validation "
            f"{r.get('val_best_successes', '?')}/{VALIDATION_EPISODES}, first 15/15 "
            f"{'never' if first == -1 else f'at iteration {first}'}, "
            f"{r.get('iterations', '?')} iterations, {r.get('train_wall_s', 0.0):.0f} s "
            f"({self._count(trials, trial, 'TERMINATED')})"
        )

    def on_trial_error(self, iteration: int, trials: list[Any], trial: Any, **info: Any) -> None:
        self.say(
            f"[sweep] CRASHED {_trial_dir(trial)}: see {trial.path} "
            f"({self._count(trials, trial, 'ERROR')}); "
            "it is retried when the sweep is run again"
        )

    def on_step_end(self, iteration: int, trials: list[Any], **info: Any) -> None:
        if time.monotonic() - self.last < self.every_s:
            return
        self.last = time.monotonic()
        running = [t for t in trials if t.status == "RUNNING"]
        parts = []
        for t in running:
            it, val = _last_row(self.root / "runs" / _trial_dir(t) / "log.csv")
            parts.append(f"{_trial_dir(t)} it {it} val {val}/{VALIDATION_EPISODES}")
        elapsed = time.monotonic() - self.t0
        self.say(f"[sweep] {elapsed:.0f} s: {self._count(trials)}; " + "; ".join(parts))
