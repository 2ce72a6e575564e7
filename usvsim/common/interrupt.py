"""Ctrl-C and SIGTERM that a C extension cannot swallow.

Python runs a signal handler between two bytecodes of the main thread. When that happens while
a C extension is calling back into Python, the handler's ``KeyboardInterrupt`` is raised inside
the callback, and an extension that treats any error there as "try the next way" clears it and
carries on: CasADi's SWIG overload resolution converts its arguments that way (found with
``usvsim bench``: a Ctrl-C that landed while the plant's CasADi model was being built was lost in
3 runs of 4, and the bench ran to completion).

:func:`interrupt_signals` (the command line wraps every command in it) installs one handler for
SIGINT and SIGTERM that *records* the signal and then raises ``KeyboardInterrupt`` as Python's
own handler does; :func:`check_interrupt`, called where long work passes from one batch to the
next (every step of the pole-task batch, every set of ``usvsim bench``, every vessel of
``usvsim manoeuvre``), raises it again when the signal was recorded but its exception never
arrived. Where no handler of this module is installed (a library user, a Ray worker, a thread)
nothing is recorded and :func:`check_interrupt` does nothing.
"""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator
from types import FrameType

__all__ = ["check_interrupt", "interrupt_signals"]

SIGNALS = (signal.SIGINT, signal.SIGTERM)
_recorded: list[int] = []  # signals received under interrupt_signals(), newest last


def _record_and_raise(signum: int, frame: FrameType | None) -> None:
    _recorded.append(signum)
    raise KeyboardInterrupt(f"signal {signum}")


@contextlib.contextmanager
def interrupt_signals() -> Iterator[None]:
    """SIGINT and SIGTERM raise ``KeyboardInterrupt`` and are recorded for
    :func:`check_interrupt` inside the block; the previous handlers come back after it. Outside
    the main thread (where signals cannot be handled) the block runs with signals left alone."""
    try:
        previous = {s: signal.signal(s, _record_and_raise) for s in SIGNALS}
    except ValueError:  # not the main thread
        yield
        return
    _recorded.clear()
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _recorded.clear()


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if a signal arrived under :func:`interrupt_signals` since the
    last check, whether or not its first exception got through; the record is then cleared, so
    a signal is raised again at most once (an interrupted command ends at the first exception it
    sees; the work it does after that, writing what it has, runs no check). Cheap: one list
    test, fit for every step of a batch."""
    if _recorded:
        signum = _recorded[-1]
        _recorded.clear()
        raise KeyboardInterrupt(f"signal {signum} (raised again where the work went on)")
