"""Every boolean option of every ``usvsim`` command is a ``--x`` / ``--no-x`` switch
(:class:`argparse.BooleanOptionalAction`) whose stated default is the real one.

The cases are collected from the real parsers (:func:`usvsim.cli.main.build_parser`, one per
command), so a boolean option added later is tested without editing this file, and a plain
``store_true`` / ``store_false`` flag (which has no ``--no-`` form and, with a default of True,
cannot be turned off) is a failing case.
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import typing

import pytest

from usvsim.cli.main import COMMANDS, build_parser, command_spec

# a value for each positional argument, so a command line of the command parses
POSITIONALS = {"setup": "rl-gaussian-positional", "checkpoint": "rl-gaussian-positional"}
PLAIN_FLAGS = (argparse._StoreTrueAction, argparse._StoreFalseAction, argparse._StoreConstAction)


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = build_parser(command)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


def _is_flag(action: argparse.Action) -> bool:
    """A boolean-valued option: a switch, or a plain flag that should have been one."""
    if isinstance(action, argparse.BooleanOptionalAction):
        return True
    return isinstance(action, PLAIN_FLAGS) and not isinstance(action, argparse._HelpAction)


def _positionals(parser: argparse.ArgumentParser) -> list[str]:
    return [POSITIONALS[a.dest] for a in parser._actions if not a.option_strings]


def _cases() -> list[tuple[str, str]]:
    cases = []
    for command in COMMANDS:
        parser = _subparser(command)
        cases += [(command, a.dest) for a in parser._actions if _is_flag(a)]
    return cases


CASES = _cases()


def _action(command: str, dest: str) -> tuple[argparse.ArgumentParser, argparse.Action]:
    parser = _subparser(command)
    return parser, next(a for a in parser._actions if a.dest == dest and a.option_strings)


def test_the_cases_cover_every_bool_field_of_every_command() -> None:
    fields = {
        (command, f.name)
        for command in COMMANDS
        for f in dataclasses.fields(command_spec(command)[0])
        if typing.get_type_hints(command_spec(command)[0])[f.name] is bool
    }
    assert set(CASES) == fields
    # the 16 of issue 36 (bench 3, perf 3, train 2, sweep 2, evaluate 2, sitl 2, bridge 2)
    assert len(CASES) >= 16
    assert ("sitl", "ekf_status_report") in CASES


@pytest.mark.parametrize(("command", "dest"), CASES, ids=[f"{c}:{d}" for c, d in CASES])
def test_switch_has_its_no_form_and_its_stated_default(command: str, dest: str) -> None:
    parser, action = _action(command, dest)
    assert isinstance(action, argparse.BooleanOptionalAction), (
        f"usvsim {command} {action.option_strings[0]} is a plain flag: no --no- form"
    )
    name = "--" + dest.replace("_", "-")
    assert action.option_strings == [name, "--no-" + name[2:]]
    cls = command_spec(command)[0]
    default = next(f.default for f in dataclasses.fields(cls) if f.name == dest)
    stated = re.search(r"\(default: (on|off)\)$", action.help or "")
    assert stated is not None, f"{name}: help states no default: {action.help!r}"
    assert stated.group(1) == ("on" if default else "off")
    assert f"{name}, --no-{name[2:]}" in parser.format_help()

    base = _positionals(parser)
    values = {"": default, name: True, "--no-" + name[2:]: False}
    for flag, expected in values.items():
        ns = parser.parse_args([*base, flag] if flag else base)
        assert getattr(ns, dest) is expected, (command, flag)
        # the options object the command runs with (as usvsim.cli.main.main builds it)
        assert getattr(cls(**vars(ns)), dest) is expected
    # the last of --x / --no-x wins, as with any option
    assert getattr(parser.parse_args([*base, name, "--no-" + name[2:]]), dest) is False
    assert getattr(parser.parse_args([*base, "--no-" + name[2:], name]), dest) is True


def test_ekf_status_report_is_on_by_default_and_can_be_turned_off() -> None:
    """The issue's example: ``--ekf-status-report`` (default on) was a store_true flag, so the
    command line's default was off and nothing could turn it off."""
    parser = _subparser("sitl")
    assert parser.parse_args([]).ekf_status_report is True
    assert parser.parse_args(["--no-ekf-status-report"]).ekf_status_report is False
    assert parser.parse_args(["--ekf-status-report"]).ekf_status_report is True


def test_a_plain_store_true_flag_would_be_a_failing_case() -> None:
    """The collection sees plain flags, so the parametrised test fails on them."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--quiet", action="store_true")
    parser.add_argument("--loud", action=argparse.BooleanOptionalAction, default=False)
    flags = [a for a in parser._actions if _is_flag(a)]
    assert [a.dest for a in flags] == ["quiet", "loud"]
    assert not isinstance(flags[0], argparse.BooleanOptionalAction)


@pytest.mark.parametrize("flipped", [(), ("resume",), ("quiet",), ("resume", "quiet")])
def test_train_command_line_reproduces_its_switches(flipped: tuple[str, ...]) -> None:
    """``summary.json``'s command (:func:`learning.cli.train.command_of`) parses back to the
    same options, switches included."""
    from learning.cli.train import TrainArgs, command_of

    args = TrainArgs(POSITIONALS["setup"], **{name: True for name in flipped})
    argv = command_of(args).split()[1:]  # without "usvsim"
    parsed = vars(_subparser("train").parse_args(argv[1:]))
    assert TrainArgs(**parsed) == args
