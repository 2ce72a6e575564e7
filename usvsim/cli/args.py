"""Command-line options from a dataclass: one flag per field, its ``# comment`` as the help."""

from __future__ import annotations

import argparse
import dataclasses
import typing

__all__ = ["add_dataclass_arguments", "field_comments"]


def add_dataclass_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """Add one argument per field of dataclass ``cls`` (no default: positional; bool: a switch).

    A field typed with a :data:`typing.Literal` of strings accepts only those values.
    """
    comments = field_comments(cls)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        literal = hints[f.name] if typing.get_origin(hints[f.name]) is typing.Literal else None
        choices = typing.get_args(literal) if literal is not None else None
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            # a field without a default is a positional argument
            parser.add_argument(f.name, choices=choices, help=comments.get(f.name))
            continue
        flag = "--" + f.name.replace("_", "-")
        help_text = f"{comments.get(f.name, '')} (default: {f.default})"
        if f.type in ("bool", bool):
            parser.add_argument(flag, dest=f.name, action="store_true", help=comments.get(f.name))
        else:
            kind = {"float": float, "int": int}.get(str(f.type), str)
            parser.add_argument(
                flag, dest=f.name, type=kind, default=f.default, choices=choices, help=help_text
            )


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
