"""Ranges of numeric command-line options, declared on the options dataclasses' fields.

An options dataclass (one per command) declares a field's allowed range as field metadata::

    seed: int = field(default=0, metadata=bounds(ge=0))  # seeds networks and episodes

:func:`check_bounds` checks every such field of an instance, and every ``float`` field for
being finite (NaN and ±inf are never a valid option). The command line calls it once, before any
work starts (:func:`usvsim.cli.args.check_options`), so a bad value fails in one place with one
message (``--seed must be >= 0, got -1``) instead of deep inside the library.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from usvsim.common.errors import UserError

__all__ = [
    "BOUNDS_KEY",
    "LEGACY_PATH_KEY",
    "bounds",
    "check_bounds",
    "describe_bounds",
    "flag",
    "legacy_path",
]

BOUNDS_KEY = "usvsim.bounds"
LEGACY_PATH_KEY = "usvsim.legacy_path"


def bounds(
    *,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    zero_ok: bool = False,
) -> dict[str, Any]:
    """Field metadata: the value must be ``>= ge``, ``> gt``, ``<= le``, ``< lt``.

    ``zero_ok`` also allows exactly 0 (the usual "0: off / default" of an option) outside the
    range, e.g. ``bounds(ge=1, zero_ok=True)`` for "0 or at least 1".
    """
    spec = {"ge": ge, "gt": gt, "le": le, "lt": lt}
    return {BOUNDS_KEY: ({k: v for k, v in spec.items() if v is not None}, zero_ok)}


def legacy_path(path_field: str) -> dict[str, Any]:
    """Field metadata of a switch that once took a path (``--json PATH``, now ``--json-out``).

    The switch still accepts the old form for backward compatibility: ``--json PATH`` warns that
    it is deprecated and means ``--json-out PATH`` (the switch itself stays off); ``--json``
    alone is the switch. ``path_field`` names the field that now holds the path.
    """
    return {LEGACY_PATH_KEY: path_field}


def flag(name: str) -> str:
    """The command-line flag of field ``name`` (``time_budget_s`` -> ``--time-budget-s``)."""
    return "--" + name.replace("_", "-")


_WORDS = {"ge": ">=", "gt": ">", "le": "<=", "lt": "<"}
_TESTS = {
    "ge": lambda v, b: v >= b,
    "gt": lambda v, b: v > b,
    "le": lambda v, b: v <= b,
    "lt": lambda v, b: v < b,
}


def describe_bounds(field: dataclasses.Field[Any]) -> str:
    """The allowed range of ``field`` in words (``">= 1 (or 0)"``); "" if it has none."""
    spec = field.metadata.get(BOUNDS_KEY)
    if spec is None:
        return ""
    limits, zero_ok = spec
    text = " and ".join(f"{_WORDS[k]} {_number(v)}" for k, v in limits.items())
    return text + (" (or 0)" if zero_ok else "")


def _number(value: float) -> str:
    """``value`` as the user would type it (integers in full, floats shortest)."""
    return str(int(value)) if float(value).is_integer() else f"{value:g}"


def check_bounds(options: Any) -> None:
    """Check every bounded field of dataclass instance ``options`` and that floats are finite.

    Raises
    ------
    UserError
        Naming the first bad option as its flag, what is allowed and what was given.
    """
    for f in dataclasses.fields(options):
        value = getattr(options, f.name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            continue
        if isinstance(value, float) and not math.isfinite(value):
            raise UserError(f"{flag(f.name)} must be a finite number, got {value}")
        spec = f.metadata.get(BOUNDS_KEY)
        if spec is None:
            continue
        limits, zero_ok = spec
        if zero_ok and value == 0:
            continue
        if not all(_TESTS[k](value, b) for k, b in limits.items()):
            raise UserError(f"{flag(f.name)} must be {describe_bounds(f)}, got {_number(value)}")
