"""Vessel and autopilot pages' generated parts: ``usvsim manoeuvre`` and ``usvsim demo`` run at
build time, their table and plots included as they wrote them."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path


def _usvsim(args: list[str]) -> None:
    """Run ``usvsim ARGS``; a failure stops the build with the command's last stderr lines."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    done = subprocess.run(
        [sys.executable, "-m", "usvsim.cli", *args], env=env, text=True,
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=False,
    )  # fmt: skip
    if done.returncode != 0:
        tail = "\n".join(done.stderr.strip().splitlines()[-5:])
        raise RuntimeError(f"usvsim {' '.join(args)} failed ({done.returncode}):\n{tail}")


def plant_outputs() -> tuple[str, dict[str, bytes]]:
    """(the manoeuvring table in Markdown, {file name: PNG bytes}) of both commands."""
    with tempfile.TemporaryDirectory(prefix="usvsim-docs-") as tmp:
        man, demo = Path(tmp) / "manoeuvre", Path(tmp) / "demo"
        _usvsim(["manoeuvre", "--out", str(man)])
        _usvsim(["demo", "--out", str(demo)])
        table = (man / "manoeuvre.md").read_text()
        images = {p.name: p.read_bytes() for d in (man, demo) for p in sorted(d.glob("*.png"))}
    return table, images


def plots_markdown(names: list[str], folder: str) -> str:
    """Image lines for the plots, ``usvsim demo``'s first."""
    demo = [n for n in names if not n.startswith("manoeuvre_")]
    trials = [n for n in names if n.startswith("manoeuvre_")]
    lines = ["### `usvsim demo` (usv105, pid)", ""]
    lines += [f"![{n}]({folder}/{n})" for n in demo]
    lines += ["", "### `usvsim manoeuvre`, per vessel", ""]
    lines += [f"![{n}]({folder}/{n})" for n in trials]
    return "\n".join(lines)
