"""Lighting in USD."""

from __future__ import annotations

from typing import Any

__all__ = ["author_lighting"]


def author_lighting(stage: Any, scene: Any, assets: dict[str, bytes]) -> None:
    """Author the scene's lighting (nothing when the stage is disabled)."""
    if scene.lighting is None:
        return
