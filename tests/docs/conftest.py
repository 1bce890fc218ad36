"""The built documentation site (``docs/_build/html``, or ``$MARSSCENE_SITE``) for the site tests.

``.ci/run`` builds the site before the tests and sets ``MARSSCENE_REQUIRE_SITE=1``, so a missing
site fails there; elsewhere the site tests skip when no site was built
(``python -m sphinx -W --keep-going -b html docs docs/_build/html``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.docs.site_util import built_site


@pytest.fixture(scope="session")
def site_dir() -> Path:
    site = built_site()
    if site is None:
        if os.environ.get("MARSSCENE_REQUIRE_SITE") == "1":
            pytest.fail("MARSSCENE_REQUIRE_SITE=1 but no built site (docs/_build/html/index.html)")
        pytest.skip("no built documentation site: python -m sphinx -b html docs docs/_build/html")
    return site
