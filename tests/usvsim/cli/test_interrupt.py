"""Ctrl-C (SIGINT) and SIGTERM end a command with status 130 and leave its outputs whole, even
when the first ``KeyboardInterrupt`` is swallowed by a C extension (:mod:`usvsim.common.interrupt`).

The swallowing is reproduced as it happens in CasADi's SWIG wrappers: the signal lands while the
extension runs Python code on its behalf (converting an argument), the handler's exception is
raised there, and the extension clears it and goes on.
"""

from __future__ import annotations

import csv
import os
import signal
from pathlib import Path
from typing import Any

import pytest

from usvsim.cli.main import main
from usvsim.common.interrupt import check_interrupt, interrupt_signals


def _swallowed_signal(sig: int = signal.SIGINT) -> None:
    """A signal arrives inside a C extension's call back into Python, which clears the error."""
    try:
        os.kill(os.getpid(), sig)
        for _ in range(10_000_000):  # the handler runs at the first chance it gets
            pass
    except KeyboardInterrupt:
        return  # cleared, as the extension does (PyErr_Clear), and the work goes on
    raise AssertionError("the signal handler never ran")


def test_a_swallowed_signal_is_raised_again_once() -> None:
    with interrupt_signals():
        _swallowed_signal()
        with pytest.raises(KeyboardInterrupt, match="raised again"):
            check_interrupt()
        check_interrupt()  # once only: the command is already ending
    check_interrupt()  # outside: nothing recorded, nothing raised


def test_without_the_handler_nothing_is_recorded() -> None:
    with pytest.raises(KeyboardInterrupt):  # Python's own handler
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(10_000_000):
            pass
    check_interrupt()  # a library user (or a Ray worker) never gets a late KeyboardInterrupt


def test_bench_ends_at_a_swallowed_ctrl_c(tmp_path: Path, monkeypatch: Any) -> None:
    """Failed before the fix: the bench ran to completion (exit 0, every set) although Ctrl-C
    had been pressed while the held-out batch was being built."""
    from usvsim.task.batch import PoleAvoidanceBatch

    original = PoleAvoidanceBatch.reset
    fired: list[bool] = []

    def reset(self: PoleAvoidanceBatch, *args: Any, **kwargs: Any) -> Any:
        if self.n_boats > 15 and not fired:  # the held-out set's batch, not validation's
            fired.append(True)
            _swallowed_signal()
        return original(self, *args, **kwargs)

    monkeypatch.setattr(PoleAvoidanceBatch, "reset", reset)
    out = tmp_path / "bench"
    argv = ["bench", "--helmsmen", "straight", "--heldout", "40", "--no-likeness", "--no-plots"]
    assert main([*argv, "--out", str(out)]) == 130
    assert fired
    assert "(interrupted" in (out / "bench.md").read_text().splitlines()[0]
    with (out / "bench.csv").open(newline="") as handle:
        assert [r["episode_set"] for r in csv.DictReader(handle)] == ["validation"]
    assert sorted(p.name for p in out.iterdir()) == ["bench.csv", "bench.md"]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_manoeuvre_interrupted_exits_130_and_keeps_the_previous_set(
    tmp_path: Path, monkeypatch: Any, capsys: Any, sig: int
) -> None:
    import usvsim.evaluation.manoeuvre as manoeuvre

    out = tmp_path / "man"
    args = ["manoeuvre", "--vessel", "all", "--out", str(out)]
    assert main(args) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert "manoeuvre.md" in before and len(before) == 1 + len(manoeuvre_names())

    original = manoeuvre.run_trials
    calls: list[str] = []

    def run_trials(vessel: Any, speed: Any = None) -> Any:
        calls.append(vessel.name)
        if len(calls) == 2:
            os.kill(os.getpid(), sig)  # Ctrl-C / kill while the second vessel runs
        return original(vessel, speed)

    monkeypatch.setattr(manoeuvre, "run_trials", run_trials)
    capsys.readouterr()
    assert main([*args[:-1], str(out), "--speed", "2"]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "usvsim manoeuvre: interrupted"
    assert len(calls) == 2
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after == before  # the previous table and plots, whole; no temporaries


def manoeuvre_names() -> list[str]:
    from usvsim.vessel.vessels import VESSELS

    return sorted(VESSELS)
