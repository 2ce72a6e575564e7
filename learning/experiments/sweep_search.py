"""Tune search algorithms whose concurrency cap is the current session's, not the first one's.

Ray Tune pickles the search algorithm with the experiment and restores it, cap included, when a
sweep continues (:func:`ray.tune.Tuner.restore` takes no new ``TuneConfig``): a sweep started
with ``--max-concurrent 1`` and continued with ``--max-concurrent 2``, or on a cluster, would
still run one trial at a time, silently. These subclasses read the cap from
:func:`set_session_limit` (called by :mod:`learning.experiments.sweep` before every ``fit``), so
each session runs as many trials at once as its own command line says. Imports Ray: load it
only where the ``sweep`` extra is installed.
"""

from __future__ import annotations

from typing import Any

from ray.tune.search import ConcurrencyLimiter
from ray.tune.search.basic_variant import BasicVariantGenerator

__all__ = ["SessionLimitedGenerator", "SessionLimiter", "session_limit", "set_session_limit"]

_LIMIT = {"max_concurrent": 0}  # this driver process's --max-concurrent (0: no cap)


def set_session_limit(max_concurrent: int) -> None:
    """The cap (trials at once; 0: none) for every search algorithm of this module."""
    if max_concurrent < 0:
        raise ValueError(f"max_concurrent must be >= 0, got {max_concurrent}")
    _LIMIT["max_concurrent"] = int(max_concurrent)


def session_limit() -> int:
    """The cap :func:`set_session_limit` set (0: none)."""
    return _LIMIT["max_concurrent"]


class SessionLimitedGenerator(BasicVariantGenerator):
    """Grid / random variants (Tune's own generator) capped at :func:`session_limit`."""

    @property
    def max_concurrent(self) -> int:
        return session_limit()

    @max_concurrent.setter
    def max_concurrent(self, value: Any) -> None:
        """Tune's constructor and ``set_state`` assign the stored cap: ignored."""


class SessionLimiter(ConcurrencyLimiter):
    """Tune's :class:`~ray.tune.search.ConcurrencyLimiter` (for sequential searchers such as
    Optuna's TPE) capped at :func:`session_limit` (0: no cap, the CPUs decide)."""

    @property
    def max_concurrent(self) -> int:
        return session_limit() or 2**31 - 1

    @max_concurrent.setter
    def max_concurrent(self, value: Any) -> None:
        """Tune's constructor and ``set_state`` assign the stored cap: ignored."""
