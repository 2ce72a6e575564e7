"""Property tests (hypothesis) of the command-line option dataclasses: any value of any option
of any command gives a checked options object or a :class:`UserError` naming the flag; any
command line of numbers gives exit status 2 with one line, or gets past the checks."""

from __future__ import annotations

import dataclasses
import importlib
import math
import typing

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usvsim.cli.args import check_options
from usvsim.cli.main import COMMANDS
from usvsim.common.errors import UserError
from usvsim.common.options import BOUNDS_KEY, flag


def _options_class(target: str) -> type:
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


OPTION_CLASSES = {name: _options_class(c.options) for name, c in COMMANDS.items()}
# the commands of issue 14, then manoeuvre and sweep (issue 19); a later command declares its
# ranges the same way
CHECKED = (
    *("bench", "bridge", "demo", "evaluate", "manoeuvre", "perf", "sitl", "sitl-physics"),
    *("sweep", "train"),
)
numbers = st.one_of(
    st.integers(-(2**40), 2**40),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1, 0.0, -0.0, 1e-9, 65535, 65536, 255, 256, 90.0, 90.5, 180.0]),
)


def _numeric_fields(cls: type) -> list[dataclasses.Field]:
    hints = typing.get_type_hints(cls)
    return [f for f in dataclasses.fields(cls) if hints[f.name] in (int, float)]


def _required(cls: type, option: str = "") -> dict[str, typing.Any]:
    """Values for the positional fields (setup, checkpoint) so the class can be built with
    ``option``: an open-water radar RL setup, which takes every numeric option of ``train``
    (``--crowded-share`` and ``--harsh-radar-share`` included) but ``--harsh-radar-copies``,
    for which it is the open-water radar IL setup."""
    setup = "il-gaussian-radar-ow" if option == "harsh_radar_copies" else "rl-gaussian-radar-ow"
    return {
        f.name: setup if f.name == "setup" else "x.pt"
        for f in dataclasses.fields(cls)
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    }


def _in_range(f: dataclasses.Field, value: float) -> bool:
    spec = f.metadata.get(BOUNDS_KEY)
    if not math.isfinite(value):
        return False
    if spec is None:
        return True
    limits, zero_ok = spec
    if zero_ok and value == 0:
        return True
    tests = {"ge": value >= limits.get("ge", -math.inf), "gt": value > limits.get("gt", -math.inf)}
    tests |= {"le": value <= limits.get("le", math.inf), "lt": value < limits.get("lt", math.inf)}
    return all(tests[k] for k in limits)


def test_every_numeric_option_of_every_command_has_a_range_or_is_free() -> None:
    """A numeric option without declared bounds must be one where every finite value is fine."""
    free = {
        (name, f.name)
        for name, cls in OPTION_CLASSES.items()
        if name in CHECKED
        for f in _numeric_fields(cls)
        if BOUNDS_KEY not in f.metadata
    }
    assert free == set(), free


@pytest.mark.parametrize("command", sorted(set(OPTION_CLASSES) & set(CHECKED)))
@settings(database=None, max_examples=150, deadline=200)
@given(data=st.data())
def test_any_option_value_is_checked_or_refused(command: str, data: st.DataObject) -> None:
    cls = OPTION_CLASSES[command]
    fields = _numeric_fields(cls)
    if not fields:
        return
    f = data.draw(st.sampled_from(fields))
    value = data.draw(numbers)
    if typing.get_type_hints(cls)[f.name] is int:
        value = int(value) if isinstance(value, int) or math.isfinite(value) else 0
    try:
        options = cls(**_required(cls, f.name), **{f.name: value})
        check_options(options)
    except UserError as err:
        # the flag leads, or a rule across several options names each of them
        assert str(err).startswith(flag(f.name)) or flag(f.name) in str(err), err
        # rules between options refuse some values inside the range: sitl-physics (two channels
        # must differ, PWM min < trim < max), manoeuvre (--speed at most 5x the cruise speed of
        # each vessel chosen)
        assert not _in_range(f, value) or command in ("sitl-physics", "manoeuvre")
        return
    assert _in_range(f, value), (command, f.name, value)
