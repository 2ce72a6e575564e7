"""mkdocs hook: the generated parts of the usvsim site (``hooks:`` in ``mkdocs.yml``).

Generated at every build, from the code and the tools' outputs, so none of it is written by hand:

- ``environments/*.md``: one page per Gymnasium id ``import usvsim`` registers, from the env
  class's docstring, with a rendered episode (:mod:`gen_envs`);
- ``cli.md``: every command's ``--help`` (:mod:`gen_cli`);
- ``results.md``: tables from ``docs/data/*.json`` (:mod:`gen_results`), and the model zoo and
  stress summary on the helmsmen page; ``models.md``: the model cards (``usvsim models``);
- the manoeuvring table and plant plots on the vessels page, by ``usvsim manoeuvre`` and
  ``usvsim demo`` (:mod:`gen_plant`);
- ``api/*.md``: mkdocstrings pages (:mod:`gen_api`);
- ``notebooks/*.ipynb``: ``examples/`` executed (:mod:`gen_notebooks`), rendered by mkdocs-jupyter;
  the images on each built notebook page are counted and the build fails where a page lacks the
  plots its notebook drew (:func:`on_post_build`);
- ``changelog.md``: the repository's ``CHANGELOG.md``;
- the reward weights, the traffic setups and the expert-likeness table on the "Training in
  traffic" page (:mod:`gen_traffic`).
"""

from __future__ import annotations

import io
import logging
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.plugins import event_priority
from mkdocs.structure.files import File, Files

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
for _path in (HERE, ROOT / "benchmarks"):  # the generators; readme_figures.py
    if str(_path) not in sys.path:
        sys.path.insert(0, str(_path))

import gen_api  # noqa: E402
import gen_cli  # noqa: E402
import gen_envs  # noqa: E402
import gen_notebooks  # noqa: E402
import gen_plant  # noqa: E402
import gen_results  # noqa: E402
import gen_traffic  # noqa: E402
import readme_figures  # noqa: E402

log = logging.getLogger("mkdocs.hooks.usvsim")
PLANT_DIR = "assets/generated/plant"


class _Build:
    """What one build generated and the placeholders' replacements (one instance per build)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Forget the previous build (``mkdocs serve`` rebuilds in one process)."""
        self.tmp: Path | None = None
        self.fragments: dict[str, str] = {}
        self.plant_images: list[str] = []
        self.notebook_plots: dict[str, int] = {}  # {notebook: plots in its executed outputs}
        self.notebook_pages: dict[str, int] = {}  # {notebook: images on its built page}


_build = _Build()


def _extend_nav(nav: list[Any], index: str, pages: list[str]) -> bool:
    """Append ``pages`` to the nav section that lists ``index`` (recursively); True if found."""
    for item in nav:
        children = next(iter(item.values())) if isinstance(item, dict) else None
        if isinstance(children, list):
            flat = [next(iter(c.values())) if isinstance(c, dict) else c for c in children]
            if index in flat:
                children.extend(p for p in pages if p not in flat)
                return True
            if _extend_nav(children, index, pages):
                return True
    return False


def on_config(config: Any) -> Any:
    """Add the generated pages to the nav (the sections holding their index pages)."""
    nav = config["nav"] or []
    envs = [f"environments/{gen_envs.slug(i)}.md" for i in gen_envs.env_ids()]
    notebooks = [f"notebooks/{p.name}" for p in gen_notebooks.notebooks()]
    api = [p for p in gen_api.pages() if p != "api/index.md"]
    for index, pages in (
        ("environments/index.md", envs),
        ("notebooks/index.md", notebooks),
        ("api/index.md", api),
    ):
        if not _extend_nav(nav, index, pages):
            raise ValueError(f"mkdocs.yml: no nav section lists {index}")
    return config


def _add(files: Files, config: Any, uri: str, content: str | bytes) -> None:
    files.append(File.generated(config, uri, content=content))


def _env_pages(files: Files, config: Any) -> None:
    ids = gen_envs.env_ids()
    _add(files, config, "environments/index.md", gen_envs.index_page(ids))
    pole_png = gen_envs.pole_episode_png()
    _add(files, config, "assets/generated/env-poleavoidance.png", pole_png)
    buf = io.BytesIO()
    fig = readme_figures.open_water_episode_figure()
    fig.savefig(buf, format="png", dpi=80)
    _add(files, config, "assets/generated/env-openwater.png", buf.getvalue())
    images = {
        "usvsim/PoleAvoidance-v0": (
            "../assets/generated/env-poleavoidance.png",
            gen_envs.POLE_CAPTION,
        ),
        "usvsim/OpenWater-v0": (
            "../assets/generated/env-openwater.png",
            "One episode of the family's hardest stress set (`everything`) steered by "
            "`scene-gaussian-gail-trpo-openwater`: this env has no `render()` (its top view "
            "would draw one pole), so the page shows the evaluation's path plot "
            "(`benchmarks/readme_figures.py`, `open_water_episode_figure`).",
        ),
    }
    for env_id in ids:
        image, caption = images.get(env_id, (None, ""))
        _add(files, config, f"environments/{gen_envs.slug(env_id)}.md",
             gen_envs.env_page(env_id, image, caption))  # fmt: skip


def _notebooks(files: Files, config: Any) -> None:
    assert _build.tmp is not None
    out = _build.tmp / "nbsrc" / "notebooks"
    out.mkdir(parents=True)
    times = gen_notebooks.execute_all(out, log)
    images = {name: gen_notebooks.count_images(out / name) for name in times}
    _build.notebook_plots = images
    for name in times:
        files.append(File(f"notebooks/{name}", src_dir=str(_build.tmp / "nbsrc"),
                          dest_dir=config["site_dir"],
                          use_directory_urls=config["use_directory_urls"]))  # fmt: skip
        log.info("notebook %s: %d plots", name, images[name])
    _add(files, config, "notebooks/index.md", gen_notebooks.index_page(list(times), images, times))


@event_priority(50)  # before mkdocs-jupyter's on_files, which wraps the notebooks it finds
def on_files(files: Files, config: Any) -> Files:
    """Generate the pages and images of the module docstring."""
    _build.reset()
    _build.tmp = Path(tempfile.mkdtemp(prefix="usvsim-docs-"))
    _env_pages(files, config)
    _add(files, config, "cli.md", gen_cli.cli_markdown())
    _add(files, config, "results.md", gen_results.results_page())
    _add(files, config, "models.md", gen_results.models_page())
    for uri, text in gen_api.pages().items():
        _add(files, config, uri, text)
    changelog = (ROOT / "CHANGELOG.md").read_text().replace("](docs/", "](")
    _add(files, config, "changelog.md", changelog)
    table, images = gen_plant.plant_outputs()
    for name, data in images.items():
        _add(files, config, f"{PLANT_DIR}/{name}", data)
    stress = gen_results.load("stress")
    _build.fragments = {
        "manoeuvre-table": table,
        "plant-plots": gen_plant.plots_markdown(list(images), f"../{PLANT_DIR}"),
        "stress-summary": gen_results.stress_summary(stress),
        "model-zoo": gen_results.model_zoo(),
        "training-times": gen_results.training_times(),
        "colreg-reward-weights": gen_traffic.reward_weights_markdown(),
        "traffic-setups": gen_traffic.traffic_setups_markdown(),
        "colreg-likeness": gen_traffic.likeness_table(),
    }
    _notebooks(files, config)
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    """Replace ``<!-- generated:NAME -->`` by the fragment NAME (unknown names fail the build)."""
    import re

    def fragment(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in _build.fragments:
            raise ValueError(f"{page.file.src_uri}: unknown generated fragment {name!r}")
        return _build.fragments[name]

    return re.sub(r"<!-- generated:([a-z0-9-]+) -->", fragment, markdown)


def on_post_page(output: str, page: Any, config: Any) -> str:
    """Count the images on each built notebook page (checked in :func:`on_post_build`)."""
    uri = page.file.src_uri
    if uri.startswith("notebooks/") and uri.endswith(".ipynb"):
        _build.notebook_pages[Path(uri).name] = gen_notebooks.count_page_images(output)
    return output


def on_post_build(config: Any) -> None:
    """Fail the build if a notebook's plots did not reach its page (executed builds only); log
    the images per notebook page; remove the build's scratch folder (executed notebooks)."""
    if _build.tmp is not None:
        shutil.rmtree(_build.tmp, ignore_errors=True)
    for name, count in sorted(_build.notebook_pages.items()):
        log.info("notebook page %s: %d images", name, count)
    if gen_notebooks.executing():
        problems = gen_notebooks.check_pages(_build.notebook_pages, _build.notebook_plots)
        if problems:
            raise PluginError("notebook pages without their plots: " + "; ".join(problems))
