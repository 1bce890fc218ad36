"""Sphinx configuration of the marsscene documentation site.

Build it with ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (``.ci/run``
does). The notebooks in ``notebooks/`` (linked as ``docs/notebooks``) are executed during the
build by myst-nb and their outputs go into the site only, never into git. Set
``MARSSCENE_DOCS_EXECUTE`` to ``force`` (run every notebook), ``cache`` (the default: rerun a
notebook only when its code changed) or ``off`` (no execution: a quick check of the pages).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

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
myst_enable_extensions = ["colon_fence", "deflist", "attrs_inline"]
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
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "getting_started": []}
