"""The error type of bad user input, shared by every command.

:class:`UserError` is raised for anything the user can fix: an option out of range, a file that
is missing or malformed, an output folder that cannot be written, a URL or port that cannot be
used. Its message is one line that names the option or file and what is allowed. The command
line (:func:`usvsim.cli.main.main`) prints it and exits with status 2, without a traceback
(``--debug`` shows one). Format errors of files (checkpoints, missions, demonstrations) derive
from it, so a library caller can catch them one by one or all at once.
"""

from __future__ import annotations

__all__ = ["UserError"]


class UserError(ValueError):
    """Bad input from the user; the message is one line naming what is wrong and what is allowed.

    A ``ValueError``, so library code that already catches ``ValueError`` keeps working.
    """
