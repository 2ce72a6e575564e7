"""The example notebooks, executed at build time so their plots appear in the site.

Each notebook of ``examples/`` runs top to bottom in a fresh kernel (nbclient), in a scratch
working directory (so nothing lands in ``examples/``), with matplotlib's inline backend even
where ``MPLBACKEND=Agg`` is set (``.ci/run`` sets it; an inherited Agg would leave every plot
blank). A cell error stops the build. ``USVSIM_DOCS_EXECUTE=0`` skips the execution (a quick
local preview; the pages then show the notebooks as committed).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
INLINE = "module://matplotlib_inline.backend_inline"


def notebooks() -> list[Path]:
    """``examples/*.ipynb`` in name order."""
    return sorted(EXAMPLES.glob("*.ipynb"))


def execute_all(out_dir: Path, log: object) -> dict[str, float]:
    """Execute every notebook into ``out_dir`` (same file names); returns {name: seconds}."""
    import nbclient
    import nbformat

    execute = os.environ.get("USVSIM_DOCS_EXECUTE", "1") != "0"
    env = {**os.environ, "MPLBACKEND": INLINE, "OMP_NUM_THREADS": "1"}
    times: dict[str, float] = {}
    for path in notebooks():
        nb = nbformat.read(path, as_version=4)
        start = time.perf_counter()
        if execute:
            work = out_dir / f"run-{path.stem}"
            work.mkdir(parents=True, exist_ok=True)
            client = nbclient.NotebookClient(
                nb, timeout=900, kernel_name="python3", allow_errors=False,
                resources={"metadata": {"path": str(work)}},
            )  # fmt: skip
            client.execute(env=env)
        times[path.name] = time.perf_counter() - start
        nbformat.write(nb, out_dir / path.name)
        log.info(
            "notebook %s: %.0f s%s", path.name, times[path.name], "" if execute else " (not run)"
        )  # type: ignore[attr-defined]
    return times


def count_images(path: Path) -> int:
    """PNG/SVG outputs in an (executed) notebook."""
    import nbformat

    nb = nbformat.read(path, as_version=4)
    return sum(
        1
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.get("outputs", [])
        if {"image/png", "image/svg+xml"} & set(out.get("data", {}))
    )


def index_page(names: list[str], images: dict[str, int], times: dict[str, float]) -> str:
    """The examples' overview: each notebook with its plots and run time in this build."""
    lines = [
        "# Example notebooks",
        "",
        "The notebooks of `examples/`, executed when this site was built (`docs/hooks/"
        "gen_notebooks.py`); open one in Jupyter to run it yourself.",
        "",
        "| notebook | plots | run time in this build |",
        "|---|---|---|",
    ]
    for name in names:
        stem = Path(name).stem
        lines.append(f"| [{stem}]({stem}.ipynb) | {images[name]} | {times[name]:.0f} s |")
    return "\n".join(lines) + "\n"
