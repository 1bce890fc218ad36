"""Notebooks are stored without outputs; the built site holds them executed, with their figures.

The notebooks are executed when the documentation site is built (myst-nb, which fails the build
on any cell error); ``.ci/run`` builds the site before the tests. These checks are cheap: they
read the ``.ipynb`` files and, when a site was built, each notebook's page.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tests.docs.site_util import built_site, site_dir

__all__ = ["site_dir"]  # the fixture of the built-site checks

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
IDS = [p.stem for p in NOTEBOOKS]


def test_every_notebook_is_numbered_and_in_the_gallery() -> None:
    assert len(NOTEBOOKS) >= 11
    for p in NOTEBOOKS:
        assert re.fullmatch(r"\d\d_[a-z0-9_]+", p.stem), p.name
    gallery = (ROOT / "docs" / "gallery.md").read_text(encoding="utf-8")
    assert "notebooks/*" in gallery  # the gallery's toctree globs every notebook
    assert (ROOT / "docs" / "notebooks").resolve() == (ROOT / "notebooks").resolve()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_is_stored_without_outputs(path: Path) -> None:
    nb = json.loads(path.read_text(encoding="utf-8"))
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert code, "a notebook without code"
    for cell in code:
        assert cell.get("outputs", []) == [], f"{path.name}: outputs stored in git"
        assert cell.get("execution_count") is None, f"{path.name}: execution count stored"
    assert nb["metadata"]["kernelspec"]["name"] == "python3"
    assert nb["cells"][0]["cell_type"] == "markdown"
    assert nb["cells"][0]["source"][0].startswith("# ") if isinstance(
        nb["cells"][0]["source"], list) else nb["cells"][0]["source"].startswith("# ")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_built_page_holds_the_executed_notebook(path: Path, site_dir: Path) -> None:
    page = site_dir / "notebooks" / f"{path.stem}.html"
    assert page.is_file(), f"{page} was not built"
    html = page.read_text(encoding="utf-8")
    nb = json.loads(path.read_text(encoding="utf-8"))
    n_code = sum(c["cell_type"] == "code" for c in nb["cells"])
    # every code cell is on the page; the executed ones show outputs, figures as PNG files
    assert html.count('class="cell docutils container"') == n_code
    assert 'class="cell_output docutils container"' in html
    assert "output error" not in html and "Traceback (most recent call last)" not in html
    images = re.findall(r'<img[^>]+src="(\.\./_images/[^"]+\.png)"', html)
    assert images, f"{path.stem}: no figure on its page"
    for src in images:
        assert (page.parent / src).is_file(), src


def test_site_is_checked_when_present() -> None:
    """Without a built site the page checks above skip; say so rather than pass silently."""
    if built_site() is None:
        pytest.skip("no built site: the executed notebooks were not checked")
