"""Validation splits choose, test splits report: a guard that makes selection code fail loudly
when it draws a test episode.

Every function that draws a *test* split (the study's held-out episodes, the held-out waypoint
courses, the family's held-out set, the stress suite's test split) calls
:func:`check_test_draw` first. Code that *selects* (a training run's validations, ``best.pt``,
early stops, a sweep's search objective and shipped-seed rule) runs inside
:func:`selection_mode`; a test-split draw there raises :class:`TestSplitInSelectionError`
instead of returning episodes. Outside selection mode the guard does nothing, so reporting code
(``usvsim bench``, ``usvsim evaluate``, a sweep's held-out evaluation) draws the test split as
before.

The mode lives in a :class:`contextvars.ContextVar` (per thread and per asyncio task, reset on
leaving the ``with`` block even on an exception), not in a module-level variable.

>>> with selection_mode("a validation"):
...     try:
...         check_test_draw("study held-out")
...     except TestSplitInSelectionError as err:
...         print(str(err).split(";")[0])
a validation drew the test split 'study held-out'
>>> check_test_draw("study held-out")  # reporting: allowed
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

__all__ = [
    "TestSplitInSelectionError",
    "check_test_draw",
    "current_selection",
    "selection_mode",
]

# what is selecting now ("" outside selection mode); a ContextVar, not module state
_SELECTING: ContextVar[str] = ContextVar("usvsim_selecting", default="")


class TestSplitInSelectionError(RuntimeError):
    """Selection code drew a test-split episode (a bug in the code, not bad user input)."""

    __test__ = False  # not a pytest test class despite its name


@contextmanager
def selection_mode(what: str) -> Iterator[None]:
    """Mark the ``with`` block as selection code named ``what`` (e.g. ``"train_rl"``); nested
    blocks keep the innermost name."""
    token = _SELECTING.set(what or "selection")
    try:
        yield
    finally:
        _SELECTING.reset(token)


def current_selection() -> str:
    """The name of the selection code running now, or ``""`` outside selection mode."""
    return _SELECTING.get()


def check_test_draw(split: str) -> None:
    """Called by every test-split drawer before it draws ``split`` (its name).

    Raises
    ------
    TestSplitInSelectionError
        Inside :func:`selection_mode`.
    """
    what = _SELECTING.get()
    if what:
        raise TestSplitInSelectionError(
            f"{what} drew the test split {split!r}; selection uses validation episodes only"
        )
