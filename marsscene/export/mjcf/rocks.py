"""Rocks in MJCF: contact-relevant rocks as mesh geoms."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

__all__ = ["add_rocks"]


def add_rocks(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add rock geoms (nothing when the stage is disabled)."""
    if scene.rocks is None:
        return
