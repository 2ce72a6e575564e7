"""Build and cache small C shared libraries with the system compiler (the compiled fast paths).

Each library is compiled on first use and cached under :func:`cache_dir` by the hash of its
source, flags, compiler, platform and (for CPU-specific builds) the CPU's model and feature
flags; a finished library is moved into place atomically, so concurrent processes see the whole
file or none. Where no compiler is found, :class:`CompileError` says so and callers fall back to
their NumPy or CasADi path.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "CompileError",
    "cache_dir",
    "compile_library",
    "cpu_signature",
    "find_compiler",
    "load_function",
]


class CompileError(RuntimeError):
    """The C fast path could not be built."""


def cache_dir() -> Path:
    """Folder for compiled libraries: ``$USVSIM_CACHE_DIR`` or ``~/.cache/usvsim``."""
    root = os.environ.get("USVSIM_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "usvsim"


def find_compiler() -> str | None:
    """The C compiler to use: ``$CC``, else the first of ``cc``, ``gcc``, ``clang`` on PATH."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return name
    return None


def cpu_signature() -> str:
    """The CPU's model and feature flags (a -march=native build is cached per CPU)."""
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
    except OSError:
        return platform.machine() + platform.processor()
    wanted = [ln for ln in lines if ln.startswith(("model name", "flags", "Features"))]
    return platform.machine() + "\n".join(dict.fromkeys(wanted))


def compile_library(source: str, flags: list[str], machine: str = "", prefix: str = "step") -> Path:
    """The shared library of C ``source`` built with ``flags`` (``-l...`` flags go after the
    code), cached as ``cache_dir()/<prefix>_<hash>.so``; ``machine`` (e.g. :func:`cpu_signature`
    for a ``-march=native`` build) joins the cache key.

    Raises
    ------
    CompileError
        If no compiler is found or the compiler fails (the end of its message attached).
    """
    cc = find_compiler()
    if cc is None:
        raise CompileError("no C compiler found (set CC, or install gcc)")
    key = hashlib.sha256(
        (source + " ".join(flags) + cc + sys.platform + machine).encode()
    ).hexdigest()
    out_dir = cache_dir()
    out_dir.mkdir(parents=True, exist_ok=True)
    lib = out_dir / f"{prefix}_{key[:20]}.so"
    if lib.exists():
        return lib
    with tempfile.TemporaryDirectory(dir=out_dir) as tmp:
        src = Path(tmp) / "lib.c"
        src.write_text(source)
        tmp_lib = Path(tmp) / "lib.so"
        proc = subprocess.run(
            [
                cc,
                *(f for f in flags if not f.startswith("-l")),
                str(src),
                "-o",
                str(tmp_lib),
                *(f for f in flags if f.startswith("-l")),  # libraries after the code
                "-lm",
            ],
            capture_output=True,
            text=True,
            check=False,
        )
        if proc.returncode != 0:
            raise CompileError(f"{cc} failed:\n{proc.stderr[-2000:]}")
        os.replace(tmp_lib, lib)  # atomic: other processes see the whole library or none
    return lib


_BASE_FLAGS = ["-O3", "-fPIC", "-shared", "-fopenmp", "-fno-fast-math", "-ffp-contract=off"]
_BUILDS: tuple[tuple[list[str], bool], ...] = (
    ([*_BASE_FLAGS, "-march=native", "-mprefer-vector-width=512"], True),  # (flags, per CPU)
    (_BASE_FLAGS, False),
)


def load_function(
    source: str, name: str, argtypes: list[Any], prefix: str, link: Sequence[str] = ()
) -> Any | None:
    """The C function ``name`` of ``source`` with ``argtypes`` set (returns void), built with
    ``-O3 -march=native`` (IEEE arithmetic, no FMA contraction, OpenMP) or, where that fails,
    the same flags without ``-march``, plus ``link`` (e.g. ``-L<dir>``, ``-l<name>``); None
    where no build loads (no compiler, an unwritable cache, an unloadable library): the
    caller's NumPy path runs then."""
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")  # as the plant's kernels (codegen)
    for flags, native in _BUILDS:
        try:
            machine = cpu_signature() if native else ""
            lib = compile_library(source, [*flags, *link], machine, prefix=prefix)
            fn = getattr(ctypes.CDLL(str(lib)), name)
        except (CompileError, OSError):  # OSError: an unwritable cache, an unloadable library
            continue
        fn.argtypes = argtypes
        fn.restype = None
        return fn
    return None
