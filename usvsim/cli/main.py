"""The ``usvsim`` command line: one sub-command per entry of :data:`COMMANDS`.

Each sub-command has one frozen dataclass holding its options (defined beside the code it
configures); argparse is built from it (:mod:`usvsim.cli.args`) so ``--help`` lists every field
with its default. Long work shows a progress bar; results are written atomically.

One error path for every command (:func:`main`):

==============================================  =============================================
what happens                                    what the user sees, exit status
==============================================  =============================================
bad option syntax or value, option out of       one line ``usvsim CMD: ...`` naming the option
range, bad file, URL, port, unwritable output   or file and what is allowed; status 2
(:class:`usvsim.common.errors.UserError`,
``OSError``, ``SystemExit("message")``)
Ctrl-C (SIGINT) or SIGTERM                      the command keeps what it has (train: the
                                                checkpoint, summary marked "interrupted";
                                                bench: the results so far; bridge: HOLD), one
                                                line; status 130
the command's own failure (a failsafe, a        its message; status 1
non-finite loss)
==============================================  =============================================

``usvsim --debug CMD ...`` (or ``--debug`` anywhere) shows the Python traceback of a user error
instead of the one line; ``usvsim --version`` prints the installed package's version. A command's
options class may add text after its options in ``--help`` with a ``cli_epilog()`` classmethod
(``usvsim train --help`` lists every setup).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

from usvsim.cli.args import (
    USAGE_ERROR,
    HelpFormatter,
    OneLineParser,
    add_dataclass_arguments,
    check_options,
)
from usvsim.common.errors import UserError
from usvsim.common.interrupt import interrupt_signals

INTERRUPTED = 130  # exit status after Ctrl-C or SIGTERM (128 + SIGINT, the shell's convention)

__all__ = ["COMMANDS", "Command", "build_parser", "main", "package_version"]


class Command(NamedTuple):
    """Where a sub-command lives: its options dataclass and its runner (``module:name``)."""

    options: str
    runner: str
    summary: str


# modules are imported only when their command is chosen, so `usvsim --help` does not pay for
# torch or pymavlink
COMMANDS: dict[str, Command] = {
    "bench": Command(
        "usvsim.evaluation.bench:BenchArgs",
        "usvsim.cli.bench:run_bench_command",
        "compare helmsmen (baselines + recommended models) on validation and held-out",
    ),
    "demo": Command(
        "usvsim.cli.plant:DemoArgs",
        "usvsim.cli.plant:run_demo",
        "vessel and autopilot design, plant plots (PNG)",
    ),
    "manoeuvre": Command(
        "usvsim.cli.plant:ManoeuvreArgs",
        "usvsim.cli.plant:run_manoeuvre",
        "manoeuvring trials (turning circle, zig-zags, stopping) vs IMO",
    ),
    "perf": Command(
        "usvsim.cli.plant:PerfArgs",
        "usvsim.cli.plant:run_perf",
        "throughput of the plant and the environments",
    ),
    "train": Command(
        "learning.cli.train:TrainArgs",
        "learning.cli.train:run",
        "train a policy (rl-* by TRPO, il-* by GAIL)",
    ),
    "sweep": Command(
        "learning.cli.sweep:SweepArgs",
        "learning.cli.sweep:run",
        "train setups x seeds x hyperparameters on Ray; across-seed statistics",
    ),
    "evaluate": Command(
        "learning.cli.evaluate:EvaluateArgs",
        "learning.cli.evaluate:run",
        "evaluate a trained checkpoint",
    ),
    "models": Command(
        "usvsim.evaluation.model_cards:ModelsArgs",
        "usvsim.cli.models:run_models_command",
        "the shipped models' cards: what each is, provenance, recommended per use",
    ),
    "sitl": Command(
        "usvsim.mavlink.sitl:SitlArgs",
        "usvsim.cli.mavlink:run_sitl",
        "the usvsim plant as a MAVLink (Rover boat) vehicle",
    ),
    "sitl-physics": Command(
        "usvsim.mavlink.sitl_physics:SitlPhysicsArgs",
        "usvsim.cli.mavlink:run_sitl_physics",
        "physics backend for ArduPilot SITL",
    ),
    "bridge": Command(
        "usvsim.mavlink.bridge:BridgeArgs",
        "usvsim.cli.mavlink:run_bridge",
        "a helmsman steers an ArduPilot boat over MAVLink",
    ),
}


def _resolve(target: str) -> Any:
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def command_spec(name: str) -> tuple[type, Callable[[Any], int]]:
    """The options dataclass and the run function of command ``name``."""
    command = COMMANDS[name]
    return _resolve(command.options), _resolve(command.runner)


def package_version() -> str:
    """The installed usvsim's version (its metadata; the source tree's if not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("usvsim")
    except PackageNotFoundError:
        import usvsim

        return str(usvsim.__version__)


def build_parser(chosen: str | None = None) -> argparse.ArgumentParser:
    """The parser; only the ``chosen`` command's options are built (its module imported)."""
    parser = OneLineParser(
        prog="usvsim",
        description="usvsim: learn and test steering policies for unmanned surface vehicles.",
    )
    parser.add_argument("--version", action="version", version=f"usvsim {package_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_, _, summary) in COMMANDS.items():
        if name == chosen:
            cls, _ = command_spec(name)
            doc = " ".join((cls.__doc__ or summary).strip().split("\n\n")[0].split())
            epilog = getattr(cls, "cli_epilog", None)
            command = sub.add_parser(
                name,
                help=summary,
                description=doc,
                epilog=epilog() if callable(epilog) else None,
                formatter_class=HelpFormatter,
            )
            add_dataclass_arguments(command, cls)
        else:
            sub.add_parser(name, help=summary, add_help=False)
    return parser


def _one_line(err: BaseException) -> str:
    if isinstance(err, OSError) and err.strerror:
        where = err.filename if err.filename is not None else ""
        return f"{where}: {err.strerror}" if where else err.strerror
    return " ".join(str(err).split()) or type(err).__name__


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; the exit status of the module docstring's table."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    args = [a for a in args if a != "--debug"]
    chosen = next((a for a in args if not a.startswith("-")), None)
    parser = build_parser(chosen if chosen in COMMANDS else None)
    ns = parser.parse_args(args)
    if ns.command is None:
        parser.print_help()
        return 0
    prog = f"usvsim {ns.command}"
    values = {k: v for k, v in vars(ns).items() if k != "command"}
    try:
        cls, run = command_spec(ns.command)
        options = cls(**values)
        check_options(options)
        with interrupt_signals():  # SIGTERM as Ctrl-C; neither lost in a C extension
            return run(options)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr, flush=True)
        return INTERRUPTED
    except SystemExit as stop:
        if isinstance(stop.code, str):  # a runner's one-line refusal
            print(stop.code, file=sys.stderr, flush=True)
            return USAGE_ERROR
        raise
    except (UserError, OSError) as err:
        if debug:
            raise
        print(f"{prog}: {_one_line(err)}", file=sys.stderr, flush=True)
        return USAGE_ERROR


if __name__ == "__main__":
    sys.exit(main())
