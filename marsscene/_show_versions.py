"""``show_versions()`` for bug reports (cf. rasterio/pyproj ``_show_versions``)."""

from __future__ import annotations

import platform

from marsscene.export.manifest import package_versions

__all__ = ["show_versions"]


def show_versions() -> str:
    """Return (and print nothing) a report of the platform and dependency versions."""
    lines = [f"platform: {platform.platform()}"]
    lines += [f"{k}: {v}" for k, v in package_versions().items()]
    return "\n".join(lines)
