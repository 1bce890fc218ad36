"""Fixtures of the site tests: the built documentation site (see ``site_util``)."""

from __future__ import annotations

from tests.docs.site_util import site_dir

__all__ = ["site_dir"]
