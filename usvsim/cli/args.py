"""Command-line options from a dataclass: one flag per field, its ``# comment`` as the help.

This is the one place where options are checked: :func:`check_options` runs the range checks
declared on the fields (:func:`usvsim.common.options.bounds`; every float must also be finite)
and then the dataclass's own ``check()`` for rules between options, before any work starts.
:class:`OneLineParser` reports a value argparse cannot convert in one line, exit status 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import typing
from typing import Any, NoReturn

from usvsim.common.options import check_bounds, describe_bounds

__all__ = ["OneLineParser", "add_dataclass_arguments", "check_options", "field_comments"]

USAGE_ERROR = 2  # exit status of a user error (argparse's, too)


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line (``usvsim train: error: ...``), status 2."""

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message} (see {self.prog} --help)\n")
        raise SystemExit(USAGE_ERROR)


def check_options(options: Any) -> None:
    """Range-check ``options`` (a command's options dataclass instance), then its ``check()``.

    Raises
    ------
    usvsim.common.errors.UserError
        For the first bad option, naming its flag and what is allowed.
    """
    check_bounds(options)
    extra = getattr(options, "check", None)
    if callable(extra):
        extra()


def add_dataclass_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """Add one argument per field of dataclass ``cls`` (no default: positional; bool: a switch).

    A field typed with a :data:`typing.Literal` of strings accepts only those values.
    """
    comments = field_comments(cls)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        choices = _literal_choices(hints[f.name])
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            # a field without a default is a positional argument
            parser.add_argument(f.name, choices=choices, help=comments.get(f.name))
            continue
        flag = "--" + f.name.replace("_", "-")
        allowed = describe_bounds(f)
        allowed = f"; {allowed}" if allowed else ""
        help_text = f"{comments.get(f.name, '')} (default: {f.default}{allowed})"
        if f.type in ("bool", bool):
            parser.add_argument(flag, dest=f.name, action="store_true", help=comments.get(f.name))
        else:
            kind = {"float": float, "int": int}.get(str(f.type), str)
            parser.add_argument(
                flag, dest=f.name, type=kind, default=f.default, choices=choices, help=help_text
            )


def _literal_choices(hint: Any) -> tuple[Any, ...] | None:
    """The values of a ``Literal`` (or of a union of ``Literal`` s); None for other types."""
    if typing.get_origin(hint) is typing.Literal:
        return typing.get_args(hint)
    members = typing.get_args(hint)
    if members and all(typing.get_origin(m) is typing.Literal for m in members):
        return tuple(v for m in members for v in typing.get_args(m))
    return None


def field_comments(cls: type) -> dict[str, str]:
    """The ``# comment`` after each field in the class source: the field's help text."""
    import inspect

    out: dict[str, str] = {}
    try:
        source = inspect.getsource(cls)
    except OSError:
        return out
    for line in source.splitlines():
        name, sep, rest = line.strip().partition(":")
        if sep and "#" in rest and name.isidentifier():
            out[name] = rest.split("#", 1)[1].strip()
    return out
