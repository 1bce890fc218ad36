"""Rocks in USD."""

from __future__ import annotations

from typing import Any

__all__ = ["author_rocks"]


def author_rocks(stage: Any, scene: Any, assets: dict[str, bytes]) -> None:
    """Author the scene's rocks (nothing when the stage is disabled)."""
    if scene.rocks is None:
        return
