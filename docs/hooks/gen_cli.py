"""The CLI reference, generated from the ``usvsim`` argparse parsers at build time."""

from __future__ import annotations

import contextlib
import io
import os


def _help(argv: list[str]) -> str:
    """What ``usvsim ARGV --help`` prints (the parser's own text)."""
    from usvsim.cli.main import build_parser

    parser = build_parser(argv[0] if argv else None)
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.suppress(SystemExit):
        parser.parse_args([*argv, "--help"])
    return out.getvalue().rstrip()


def cli_markdown() -> str:
    """One section per command of :data:`usvsim.cli.main.COMMANDS`, in the table's order."""
    from usvsim.cli.main import COMMANDS

    os.environ["COLUMNS"] = "100"  # argparse wraps at the terminal width: fix it for the page
    lines = [
        "# CLI reference",
        "",
        "Generated when this site is built, from the parsers `usvsim` itself uses "
        "(`usvsim.cli.main.build_parser`): each block is exactly what `usvsim COMMAND --help` "
        "prints.",
        "",
        "```text",
        _help([]),
        "```",
        "",
    ]
    for name, command in COMMANDS.items():
        lines += [
            f"## `usvsim {name}`",
            "",
            command.summary,
            "",
            "```text",
            _help([name]),
            "```",
            "",
        ]
    return "\n".join(lines)
