"""Atomic file writes: a reader sees the whole new file or the old one, never half a file.

Also the checks a command makes before a long computation (:func:`check_writable_dir`,
:func:`check_writable_file`: the output location can be written, else a one-line
:class:`usvsim.common.errors.UserError`), a folder of results written as one unit
(:func:`staged_dir`: files go to a hidden staging folder and are moved in only when all are
written) and the removal of temporaries a killed process left behind
(:func:`remove_stale_temporaries`). Temporary names: ``.<name>.<random>.tmp`` beside the file
(:func:`atomic_open`) and ``.staging-<stem>`` inside a results folder (:func:`staged_dir`).
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from usvsim.common.errors import UserError

__all__ = [
    "atomic_open",
    "atomic_savefig",
    "atomic_write_text",
    "check_writable_dir",
    "check_writable_file",
    "json_safe",
    "remove_stale_temporaries",
    "staged_dir",
]

STAGING_PREFIX = ".staging-"


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path``; on success fsync and rename it over ``path``.

    If the block raises, the temporary file is removed and ``path`` is untouched.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open supports modes 'w' and 'wb', got {mode!r}")
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        # mkstemp creates the file 0600: give it the permissions an ordinary open would
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)
        with os.fdopen(fd, mode) as handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_open(path, "w") as handle:
        handle.write(text)


def atomic_savefig(fig: Any, path: str | os.PathLike[str], **kwargs: Any) -> None:
    """``fig.savefig`` to ``path`` atomically (format from the suffix, default PNG)."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format=fmt, **kwargs)


def _probe(folder: Path, what: str) -> None:
    """Create and remove a temporary file in ``folder``; UserError naming ``what`` if that fails."""
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".write-test.", suffix=".tmp")
    except OSError as err:
        raise UserError(f"{what}: cannot write in {folder} ({err.strerror})") from None
    os.close(fd)
    os.unlink(tmp)


def check_writable_dir(path: str | os.PathLike[str], what: str = "--out") -> Path:
    """Make sure folder ``path`` exists (created if needed) and a file can be written in it.

    ``what`` names the option in the message. Returns the folder.

    Raises
    ------
    UserError
        If ``path`` is a file, cannot be created, or is not writable.
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise UserError(f"{what} {folder}: is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UserError(f"{what} {folder}: cannot create the folder ({err.strerror})") from None
    _probe(folder, f"{what} {folder}")
    return folder


def check_writable_file(path: str | os.PathLike[str], what: str) -> Path:
    """Make sure file ``path`` can be (over)written: not a folder, its folder writable.

    Raises
    ------
    UserError
        If ``path`` is a folder or its folder cannot be created or written.
    """
    target = Path(path)
    if target.is_dir():
        raise UserError(f"{what} {target}: is a folder, not a file")
    check_writable_dir(target.parent, f"{what} {target}: folder")
    return target


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove what killed writers left in ``folder``: ``.*.tmp`` files and staging folders.

    Call it before writing new results into ``folder`` (a process killed by SIGKILL cannot
    clean up after itself). Returns what was removed.
    """
    removed: list[Path] = []
    base = Path(folder)
    if not base.is_dir():
        return removed
    for path in base.iterdir():
        if path.name.startswith(".") and path.name.endswith(".tmp") and path.is_file():
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
            removed.append(path)
        elif path.name.startswith(STAGING_PREFIX) and path.is_dir():
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


@contextlib.contextmanager
def staged_dir(
    folder: str | os.PathLike[str], stem: str, replaces: Iterable[str] = ()
) -> Iterator[Path]:
    """Write a set of result files as one unit: yield a staging folder, then move them in.

    The block writes its files (plain writes are fine) into the yielded hidden folder
    ``folder/.staging-<stem>``. When it ends normally, files of ``folder`` matching a glob of
    ``replaces`` (an older result set) that the new set does not contain are removed, the new
    files are moved into ``folder`` (each by one ``rename``) and the staging folder is removed.
    If the block raises (or is interrupted), the staging folder is removed and ``folder`` is
    untouched: a reader sees the previous result set or the new one, never a mix. A staging
    folder left by a killed process is removed by the next call (or
    :func:`remove_stale_temporaries`).
    """
    base = Path(folder)
    base.mkdir(parents=True, exist_ok=True)
    staging = base / f"{STAGING_PREFIX}{stem}"
    shutil.rmtree(staging, ignore_errors=True)
    staging.mkdir()
    try:
        yield staging
        new = {p.name for p in staging.iterdir()}
        for name in new:  # on disk before any rename, so a crash cannot leave empty files
            fd = os.open(staging / name, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        for pattern in replaces:
            for old in base.glob(pattern):
                if old.is_file() and old.name not in new:
                    old.unlink()
        for name in sorted(new):
            os.replace(staging / name, base / name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float (NaN, ±inf) replaced by ``None`` (JSON ``null``),
    through dicts, lists and tuples; strict JSON has no NaN."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value
