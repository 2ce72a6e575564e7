"""Command-line options from a dataclass: one flag per field, its ``# comment`` as the help.

This is the one place where options are checked: :func:`check_options` runs the range checks
declared on the fields (:func:`usvsim.common.options.bounds`; every float must also be finite)
and then the dataclass's own ``check()`` for rules between options, before any work starts.
:class:`OneLineParser` reports a value argparse cannot convert in one line, exit status 2.

Every ``bool`` field is a :class:`Switch` (:class:`argparse.BooleanOptionalAction`): ``--x``
turns it on, ``--no-x`` off, and its help ends in ``(default: on)`` or ``(default: off)``, the
field's default. A switch that once took a path (field metadata
:func:`usvsim.common.options.legacy_path`) also accepts the deprecated ``--x PATH`` form.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import typing
from typing import Any, NoReturn

from usvsim.common.options import LEGACY_PATH_KEY, check_bounds, describe_bounds, flag

__all__ = [
    "HelpFormatter",
    "LegacyPathSwitch",
    "OneLineParser",
    "Switch",
    "add_dataclass_arguments",
    "check_options",
    "field_comments",
    "switch_help",
]

USAGE_ERROR = 2  # exit status of a user error (argparse's, too)


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line (``usvsim train: error: ...``), status 2."""

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message} (see {self.prog} --help)\n")
        raise SystemExit(USAGE_ERROR)


def switch_help(comment: str, default: bool) -> str:
    """The help of a switch: its comment and its default in words (``... (default: on)``)."""
    return f"{comment} (default: {'on' if default else 'off'})".strip()


class Switch(argparse.BooleanOptionalAction):
    """``--x`` / ``--no-x``: sets the field to True / False (help: :func:`switch_help`)."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        help_text = kwargs.get("help")
        super().__init__(option_strings, dest, **kwargs)
        self.help = help_text  # Python 3.10 appends "(default: True)"; ours says on/off


class LegacyPathSwitch(Switch):
    """A :class:`Switch` that still takes the path it took before it became a switch: ``--x
    PATH`` warns (deprecated) and sets ``path_dest`` to PATH, the switch off; ``--x`` alone
    and ``--no-x`` are the switch."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        self.path_dest: str = kwargs.pop("path_dest")
        super().__init__(option_strings, dest, **kwargs)
        self.nargs = "?"
        self.metavar = "PATH"

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        negative = bool(option_string and option_string.startswith("--no-"))
        if values is None:
            setattr(namespace, self.dest, not negative)
            return
        if negative:
            parser.error(f"{option_string} takes no value, got {values!r}")
        new = flag(self.path_dest)
        sys.stderr.write(
            f"{parser.prog}: warning: {option_string} PATH is deprecated, use {new} PATH "
            f"({option_string} alone prints JSON on stdout)\n"
        )
        setattr(namespace, self.path_dest, values)
        setattr(namespace, self.dest, False)


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """A command's ``--help``: a switch reads ``--x, --no-x`` (also one that still takes its
    deprecated path); an epilog keeps its line breaks (``usvsim train``'s table of setups)."""

    def _format_action_invocation(self, action: argparse.Action) -> str:
        if isinstance(action, Switch):
            return ", ".join(action.option_strings)
        return super()._format_action_invocation(action)


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
        option = flag(f.name)
        allowed = describe_bounds(f)
        allowed = f"; {allowed}" if allowed else ""
        help_text = f"{comments.get(f.name, '')} (default: {f.default}{allowed})"
        if f.type in ("bool", bool):
            comment, legacy = comments.get(f.name, ""), f.metadata.get(LEGACY_PATH_KEY)
            extra: dict[str, Any] = {"path_dest": legacy} if legacy else {}
            if legacy:
                comment += f"; {option} PATH: deprecated, use {flag(legacy)} PATH"
            parser.add_argument(
                option,
                dest=f.name,
                action=LegacyPathSwitch if legacy else Switch,
                default=f.default,
                help=switch_help(comment, bool(f.default)),
                **extra,
            )
        else:
            kind = {"float": float, "int": int}.get(str(f.type), str)
            parser.add_argument(
                option, dest=f.name, type=kind, default=f.default, choices=choices, help=help_text
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
