"""Where the built documentation site is (shared by the site tests and tests/test_notebooks.py)."""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def built_site() -> Path | None:
    """The built site's folder (``$MARSSCENE_SITE``, else ``docs/_build/html``), or None."""
    site = Path(os.environ.get("MARSSCENE_SITE", ROOT / "docs" / "_build" / "html"))
    return site if (site / "index.html").is_file() else None
