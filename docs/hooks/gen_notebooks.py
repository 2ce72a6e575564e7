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
from typing import Any

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
INLINE = "module://matplotlib_inline.backend_inline"


def notebooks() -> list[Path]:
    """``examples/*.ipynb`` in name order."""
    return sorted(EXAMPLES.glob("*.ipynb"))


def _execute(path: Path, out_dir: Path, env: dict[str, str], execute: bool) -> float:
    """Run one notebook (in its own kernel and scratch folder), write it to ``out_dir``."""
    import nbclient
    import nbformat

    nb = nbformat.read(path, as_version=4)
    start = time.perf_counter()
    if execute:
        work = out_dir.parent / f"run-{path.stem}"
        work.mkdir(parents=True, exist_ok=True)
        client = nbclient.NotebookClient(
            nb, timeout=900, kernel_name="python3", allow_errors=False,
            resources={"metadata": {"path": str(work)}},
        )  # fmt: skip
        client.execute(env=env)
    nbformat.write(nb, out_dir / path.name)
    return time.perf_counter() - start


def execute_all(out_dir: Path, log: Any) -> dict[str, float]:
    """Execute every notebook into ``out_dir`` (same file names); returns {name: seconds}.

    ``USVSIM_DOCS_JOBS`` notebooks run at once (default: 2, or 1 on a one-core machine), each
    kernel with one OpenMP thread, so two kernels keep the CI machine's two cores busy.
    """
    from concurrent.futures import ThreadPoolExecutor

    execute = os.environ.get("USVSIM_DOCS_EXECUTE", "1") != "0"
    jobs = int(os.environ.get("USVSIM_DOCS_JOBS", min(2, os.cpu_count() or 1)))
    env = {**os.environ, "MPLBACKEND": INLINE, "OMP_NUM_THREADS": "1"}
    paths = notebooks()
    # the longest first (by size, a proxy), so the last one to start is a short one
    order = sorted(paths, key=lambda p: -p.stat().st_size)
    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = {p.name: pool.submit(_execute, p, out_dir, env, execute) for p in order}
        times = {p.name: futures[p.name].result() for p in paths}
    for name, seconds in times.items():
        log.info("notebook %s: %.0f s%s", name, seconds, "" if execute else " (not run)")
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
