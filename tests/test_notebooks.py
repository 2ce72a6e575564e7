"""The example notebooks: committed clean, plots inline, and each one executes top to bottom.

Execution is slow (all ten take minutes on two cores), so it runs with ``-m slow`` and with the
notebooks' small budgets (``USVSIM_NOTEBOOK_QUICK=1``, read by the notebooks that train or run
large episode sets). ``MPLBACKEND=Agg`` is set as ``.ci/run`` sets it: a notebook must select the
inline backend itself, or its figures stay blank in Jupyter and in the documentation site.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("*.ipynb"))
QUICK_ENV = "USVSIM_NOTEBOOK_QUICK"  # "1": the notebooks' small budgets (tests, CI)

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


@pytest.mark.slow
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
