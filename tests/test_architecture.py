"""The architecture holds: import contracts, no private names across modules, modules of one idea.

The contracts themselves live in ``pyproject.toml`` (``[tool.importlinter]``): the blocks of the
one picture (vessel ← nav ← task ← helm ← evaluation ← mavlink ← cli) import one way, library
code never imports a command line, and the simulator reaches ``learning`` only through the
helmsman registry.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("usvsim", "guidance", "baselines", "learning")
MAX_LINES = 500  # the style guide's "~500 lines"; a longer module says why at its top
LONG_REASON = "Why this module is long:"


def _modules() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_import_contracts_are_kept() -> None:
    linter = Path(sys.executable).with_name("lint-imports")
    command = [str(linter)] if linter.exists() else ["lint-imports"]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "BROKEN" not in done.stdout and " kept, 0 broken." in done.stdout


def test_contracts_cover_every_block() -> None:
    config = (ROOT / "pyproject.toml").read_text()
    blocks = {p.name for p in (ROOT / "usvsim").iterdir() if (p / "__init__.py").is_file()}
    blocks |= {p.name for p in (ROOT / "learning").iterdir() if (p / "__init__.py").is_file()}
    missing = sorted(
        b for b in blocks if f'"usvsim.{b}"' not in config and f'"learning.{b}"' not in config
    )
    assert missing == [], f"subpackages outside every import contract: {missing}"


def _private_imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] not in PACKAGES:
                continue
            found += [
                f"{path.relative_to(ROOT)}:{node.lineno} imports {node.module}.{alias.name}"
                for alias in node.names
                if alias.name.startswith("_")
            ]
    return found


@pytest.mark.parametrize("folder", [*PACKAGES, "tests", "benchmarks"])
def test_no_private_name_is_imported_across_modules(folder: str) -> None:
    found = [hit for p in sorted((ROOT / folder).rglob("*.py")) for hit in _private_imports(p)]
    assert found == []


def test_every_long_module_says_why() -> None:
    long = []
    for path in _modules():
        text = path.read_text()
        n = text.count("\n")
        if n > MAX_LINES and LONG_REASON not in (ast.get_docstring(ast.parse(text)) or ""):
            long.append(f"{path.relative_to(ROOT)} ({n} lines)")
    assert long == [], f"modules over {MAX_LINES} lines without '{LONG_REASON}': {long}"


def test_every_subpackage_is_a_package() -> None:
    """setuptools ships only folders with ``__init__.py``; a namespace folder would be lost."""
    folders = {p.parent for p in _modules()}
    assert (
        sorted(str(f.relative_to(ROOT)) for f in folders if not (f / "__init__.py").exists()) == []
    )


def test_one_module_imports_pymavlink() -> None:
    importers = []
    for path in _modules():
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            if any(n.split(".")[0] == "pymavlink" for n in names):
                importers.append(_module_name(path))
                break
    assert len(importers) == 1, importers
