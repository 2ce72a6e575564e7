"""The example notebooks: committed clean, plots inline, and each one executes top to bottom.

Execution is slow (all ten take minutes on two cores), so it runs with ``-m slow`` and with the
notebooks' small budgets (``USVSIM_NOTEBOOK_QUICK=1``, read by the notebooks that train or run
large episode sets). ``MPLBACKEND=Agg`` is set as ``.ci/run`` sets it: a notebook must select the
inline backend itself, or its figures stay blank in Jupyter and in the documentation site.

In CI the notebooks run once, in the documentation build (``docs/hooks/gen_notebooks.py``: it
executes them and fails the build when a notebook page lacks its plots); ``.ci/run`` sets
``USVSIM_NOTEBOOKS_IN_DOCS=1`` and the slow execution test here is then skipped. The default run
checks that page check against mkdocs-jupyter's own rendering of a small executed notebook.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES_DIR = ROOT / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("*.ipynb"))
QUICK_ENV = "USVSIM_NOTEBOOK_QUICK"  # "1": the notebooks' small budgets (tests)
IN_DOCS_ENV = "USVSIM_NOTEBOOKS_IN_DOCS"  # "1" (.ci/run): the docs build executes them instead

# inline figures each notebook shows when executed with the small budgets
FIGURES = {
    "01_plant": 5,
    "02_environment": 5,
    "03_los_baseline": 5,
    "04_train_trpo": 3,
    "05_gail": 3,
    "06_mavlink": 1,
    "07_stress_suite": 2,
    "08_gymnasium_sb3": 3,
    "09_your_vessel_and_helmsman": 3,
    "10_bridge_against_sitl": 1,
}


def _code_cells(path: Path) -> list[dict[str, Any]]:
    nb = json.loads(path.read_text(encoding="utf-8"))
    return [c for c in nb["cells"] if c["cell_type"] == "code"]


def _source(cell: dict[str, Any]) -> str:
    src = cell["source"]
    return src if isinstance(src, str) else "".join(src)


def test_every_notebook_has_its_figure_count() -> None:
    assert sorted(p.stem for p in EXAMPLES) == sorted(FIGURES)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_notebook_is_committed_without_outputs(path: Path) -> None:
    cells = _code_cells(path)
    assert [c["outputs"] for c in cells] == [[]] * len(cells)
    assert [c["execution_count"] for c in cells] == [None] * len(cells)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_notebook_selects_the_inline_backend_first(path: Path) -> None:
    sources = [_source(c) for c in _code_cells(path)]
    assert sources[0].startswith("%matplotlib inline\n")
    assert not [s for s in sources if "matplotlib.use(" in s or "switch_backend" in s]


def _gen_notebooks() -> Any:
    """``docs/hooks/gen_notebooks.py``, the docs build's notebook module."""
    hooks = str(ROOT / "docs" / "hooks")
    if hooks not in sys.path:
        sys.path.insert(0, hooks)
    import gen_notebooks

    return gen_notebooks


def test_page_check_names_a_page_without_its_plots() -> None:
    check = _gen_notebooks().check_pages
    assert check({"a.ipynb": 3, "b.ipynb": 1}, {"a.ipynb": 3, "b.ipynb": 1}) == []
    assert check({"a.ipynb": 0}, {"a.ipynb": 0}) == [
        "a.ipynb: 0 images on its page, 0 plots executed"
    ]
    assert check({"a.ipynb": 2}, {"a.ipynb": 3}) == [
        "a.ipynb: 2 images on its page, 3 plots executed"
    ]
    assert check({}, {"a.ipynb": 1}) == ["a.ipynb: no page was built"]


def test_built_page_images_are_counted_as_mkdocs_jupyter_renders_them(tmp_path: Path) -> None:
    """Two inline plots, executed as the docs build executes, converted by mkdocs-jupyter: the
    page check counts two images (and none before execution)."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    convert = pytest.importorskip("mkdocs_jupyter.convert")
    gen = _gen_notebooks()
    code = "%matplotlib inline\nimport matplotlib.pyplot as plt\n"
    code += "plt.plot([0, 1])\nplt.show()\nplt.plot([1, 0])\nplt.show()\nprint('done')"
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
    path = tmp_path / "plots.ipynb"
    nbformat.write(nb, path)
    assert gen.count_page_images(convert.nb2html(str(path))) == 0
    env = {**os.environ, "MPLBACKEND": gen.INLINE}
    nbclient.NotebookClient(nb, kernel_name="python3").execute(env=env)
    nbformat.write(nb, path)
    assert gen.count_images(path) == 2
    assert gen.count_page_images(convert.nb2html(str(path))) == 2


@pytest.mark.slow
@pytest.mark.skipif(
    os.environ.get(IN_DOCS_ENV) == "1",
    reason=f"{IN_DOCS_ENV}=1: the docs build executes the notebooks and checks their plots",
)
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_notebook_executes_and_shows_its_figures(
    path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv(QUICK_ENV, "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    outputs = [out for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs]
    assert [out for out in outputs if out.get("output_type") == "error"] == []
    images = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(images) == FIGURES[path.stem]
    assert list(tmp_path.iterdir()) == []  # files go to temporary folders, never the cwd
