"""The ``usvsim`` command line (:mod:`usvsim.cli.main`); one module per group of commands."""

from usvsim.cli.main import main

__all__ = ["main"]
