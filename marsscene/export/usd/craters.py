"""Craters in USD."""

from __future__ import annotations

from typing import Any

__all__ = ["author_craters"]


def author_craters(stage: Any, scene: Any, assets: dict[str, bytes]) -> None:
    """Author the scene's craters (nothing when the stage is disabled)."""
    if scene.craters is None:
        return
