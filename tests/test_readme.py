"""The README stays a front door (issue 36): short, no lab-notebook figures, a quick start that
CI reads, and a picture that exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def quickstart_commands() -> list[str]:
    """The lines ``.ci/run`` executes (its awk program, re-stated)."""
    block = README.split("<!-- quickstart:begin -->", 1)[1].split("<!-- quickstart:end -->", 1)[0]
    return [line for line in block.splitlines() if line.strip() and not line.startswith("```")]


def test_readme_is_at_most_10000_characters() -> None:
    assert len(README) <= 10_000


def test_readme_has_no_dated_measurement_or_load_figure() -> None:
    assert re.search(r"\b20\d\d-\d\d(-\d\d)?\b", README) is None
    assert re.search(r"\bload( average)? \d", README) is None


def test_quickstart_is_two_commands_that_install_run_test_and_build_the_docs() -> None:
    first, second = quickstart_commands()
    assert first.startswith("pip install -c constraints.txt -e .") and "usvsim bench" in first
    assert "pip install" in second and "docs" in second and "dev" in second
    for step in ("python -m pytest", "python -m pytest -m slow", "mkdocs build --strict"):
        assert step in second


def test_readme_images_and_local_links_exist() -> None:
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    local = [t for t in targets if not t.startswith(("http://", "https://"))]
    assert local
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing
    image = ROOT / "docs" / "assets" / "readme-figure.png"
    assert 0 < image.stat().st_size < 300_000
