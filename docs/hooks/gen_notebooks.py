"""The example notebooks, executed at build time so their plots appear in the site.

Each notebook of ``examples/`` runs top to bottom in a fresh kernel (nbclient), in a scratch
working directory (so nothing lands in ``examples/``), with matplotlib's inline backend even
where ``MPLBACKEND=Agg`` is set (``.ci/run`` sets it; an inherited Agg would leave every plot
blank). A cell error stops the build, and so does a built notebook page without an image or
with fewer images than its notebook plotted (:func:`check_pages`, after the build: the plots
must reach the site). ``USVSIM_DOCS_EXECUTE=0`` skips the execution and that check (a quick
local preview; the pages then show the notebooks as committed). This build is where the
notebooks run in CI: ``.ci/run`` sets ``USVSIM_NOTEBOOKS_IN_DOCS=1`` so that ``pytest -m slow``
does not run them a second time (``tests/test_notebooks.py``).
"""

from __future__ import annotations

import os
import re
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


def executing() -> bool:
    """Whether this build executes the notebooks (``USVSIM_DOCS_EXECUTE``, default on)."""
    return os.environ.get("USVSIM_DOCS_EXECUTE", "1") != "0"


def execute_all(out_dir: Path, log: Any) -> dict[str, float]:
    """Execute every notebook into ``out_dir`` (same file names); returns {name: seconds}.

    ``USVSIM_DOCS_JOBS`` notebooks run at once (default: 2, or 1 on a one-core machine), each
    kernel with one OpenMP thread, so two kernels keep the CI machine's two cores busy.
    """
    from concurrent.futures import ThreadPoolExecutor

    execute = executing()
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


_PAGE_IMAGE = re.compile(r"<img\b[^>]*\bsrc=[\"']data:image/(?:png|jpeg|svg\+xml)")


def count_page_images(html: str) -> int:
    """Images embedded in a built notebook page (mkdocs-jupyter inlines each plot as a
    ``data:image/...`` ``<img>``)."""
    return len(_PAGE_IMAGE.findall(html))


def check_pages(pages: dict[str, int], outputs: dict[str, int]) -> list[str]:
    """What is wrong with the built notebook pages: a page without an image, or with fewer
    images than its executed notebook has plots (a plot lost on the way to the site); a
    notebook without a built page. ``pages``/``outputs``: {notebook name: image count}."""
    problems = [f"{name}: no page was built" for name in outputs if name not in pages]
    for name, shown in pages.items():
        plotted = outputs.get(name, 0)
        if shown == 0 or shown < plotted:
            problems.append(f"{name}: {shown} images on its page, {plotted} plots executed")
    return problems


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
