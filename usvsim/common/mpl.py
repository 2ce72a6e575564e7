"""Matplotlib set-up shared by the plotting modules."""

from __future__ import annotations

import matplotlib

__all__ = ["use_file_backend_if_headless"]


def use_file_backend_if_headless() -> None:
    """Select Agg (files only) unless an interactive or notebook backend is already chosen.

    Command-line runs on a machine without a display get PNG files and never a window;
    Jupyter's inline backend (``module://...``) and GUI backends are left alone.
    """
    backend = matplotlib.get_backend().lower()
    if not backend.startswith(("module://", "qt", "tk", "gtk", "wx", "macosx")):
        matplotlib.use("Agg")
