"""Sphinx configuration of the marsscene documentation site.

Build it with ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (``.ci/run``
does). The notebooks in ``notebooks/`` (linked as ``docs/notebooks``) are executed during the
build by myst-nb and their outputs go into the site only, never into git. Set
``MARSSCENE_DOCS_EXECUTE`` to ``force`` (run every notebook), ``cache`` (the default: rerun a
notebook only when its code changed) or ``off`` (no execution: a quick check of the pages).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# The notebook kernels inherit this environment: they import this checkout's marsscene, render
# headless, and draw figures inline (an inherited MPLBACKEND=Agg would hide every figure).
os.environ["PYTHONPATH"] = os.pathsep.join(
    p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p
)
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"

import marsscene  # noqa: E402

project = "marsscene"
author = "marsscene developers"
copyright = "the marsscene developers, Apache License 2.0"  # noqa: A001
version = release = marsscene.__version__

extensions = [
    "myst_nb",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax 3 from a pip package, copied into the site's _static/mathjax: the pages render
    # their formulas offline (Sphinx's default MathJax comes from a CDN at view time).
    "sphinx-mathjax-offline",
    "sphinx_design",
]

exclude_patterns = [
    "_build",
    "**.ipynb_checkpoints",
    "notebooks/README.md",
    "examples",
    "Thumbs.db",
    ".DS_Store",
]
templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
suppress_warnings: list[str] = []

# -- MyST: Markdown pages --------------------------------------------------------------------
myst_enable_extensions = ["colon_fence", "deflist", "attrs_inline", "dollarmath", "amsmath"]
myst_heading_anchors = 4  # [text](page.md#a-heading) links resolve, and the build checks them

# -- myst-nb: notebooks executed during the build ---------------------------------------------
nb_execution_mode = os.environ.get("MARSSCENE_DOCS_EXECUTE", "cache")
nb_execution_cache_path = str(Path(__file__).parent / "_build" / ".jupyter_cache")
nb_execution_timeout = 900
nb_execution_raise_on_error = True  # a failing cell fails the build
nb_execution_in_temp = True  # each notebook runs in a fresh temporary folder
nb_execution_show_tb = True
nb_merge_streams = True
nb_render_markdown_format = "gfm"  # Markdown outputs (the benchmark table) keep their tables
nb_output_stderr = "show"

# -- API reference: autodoc + autosummary + numpydoc ------------------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_default_options = {"member-order": "bysource"}
autodoc_inherit_docstrings = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- HTML ---------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"marsscene {release}"
html_static_path = ["_static"]
html_css_files = ["marsscene.css"]
html_last_updated_fmt = None
html_show_sourcelink = False
html_copy_source = False
html_theme_options = {
    "logo": {"text": "marsscene"},
    "navbar_align": "left",
    "header_links_before_dropdown": 7,
    "show_toc_level": 2,
    "navigation_depth": 3,
    "show_nav_level": 1,
    # the gallery's cards take the width of the page's table of contents
    "secondary_sidebar_items": {"**": ["page-toc"], "gallery": []},
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "getting_started": []}


# -- Gallery thumbnails: a figure the build itself made ------------------------------------------
# docs/gallery.md shows each notebook's card with <img src="_static/gallery/NAME.png">. Once the
# site is written, that file is the first figure among the notebook page's cell outputs (as the
# build executed it), scaled down to GALLERY_THUMB_PX wide; a notebook without one (a build with
# MARSSCENE_DOCS_EXECUTE=off) gets a plain grey tile, so no card shows a broken image.
GALLERY_THUMB_PX = 480
_FIRST_OUTPUT_IMAGE = re.compile(r'class="cell_output.*?<img [^>]*src="\.\./(_images/[^"]+\.png)"',
                                 re.S)


def _gallery_thumbnails(app: Any, exception: Exception | None) -> None:
    if exception is not None or app.builder.format != "html":
        return
    from PIL import Image  # matplotlib's dependency: installed wherever the notebooks run

    out = Path(app.outdir)
    folder = out / "_static" / "gallery"
    folder.mkdir(parents=True, exist_ok=True)
    for page in sorted((out / "notebooks").glob("*.html")):
        m = _FIRST_OUTPUT_IMAGE.search(page.read_text(encoding="utf-8"))
        if m:
            with Image.open(out / m.group(1)) as im:
                im = im.convert("RGB")
                im.thumbnail((GALLERY_THUMB_PX, GALLERY_THUMB_PX))
                im.save(folder / f"{page.stem}.png", optimize=True)
        else:
            Image.new("RGB", (GALLERY_THUMB_PX, GALLERY_THUMB_PX // 2), "#d9d9d9").save(
                folder / f"{page.stem}.png")


def setup(app: Any) -> None:
    app.connect("build-finished", _gallery_thumbnails)
