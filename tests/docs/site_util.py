"""Where the built documentation site is, and the ``site_dir`` fixture of the site tests.

``.ci/run`` builds the site before the tests and sets ``MARSSCENE_REQUIRE_SITE=1``, so a missing
site fails there; elsewhere the site tests skip when no site was built
(``python -m sphinx -W --keep-going -b html docs docs/_build/html``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def built_site() -> Path | None:
    """The built site's folder (``$MARSSCENE_SITE``, else ``docs/_build/html``), or None."""
    site = Path(os.environ.get("MARSSCENE_SITE", ROOT / "docs" / "_build" / "html"))
    return site if (site / "index.html").is_file() else None


@pytest.fixture(scope="session")
def site_dir() -> Path:
    """The built site; skips without one (fails with ``MARSSCENE_REQUIRE_SITE=1``)."""
    site = built_site()
    if site is None:
        if os.environ.get("MARSSCENE_REQUIRE_SITE") == "1":
            pytest.fail("MARSSCENE_REQUIRE_SITE=1 but no built site (docs/_build/html/index.html)")
        pytest.skip("no built documentation site: python -m sphinx -b html docs docs/_build/html")
    return site
