"""Craters catalogue written beside the scene (CSV)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["write_crater_catalog"]


def write_crater_catalog(scene: Any, out_dir: Path) -> list[Path]:
    """Write the crater catalogue; nothing when the stage is disabled."""
    if scene.craters is None:
        return []
    return []
