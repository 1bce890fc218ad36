"""``marsscene build`` options of the lighting stage and how they map onto the config."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["apply", "options"]


def options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate the build command with this stage's options."""
    return func


def apply(cfg: Any, values: dict[str, Any]) -> Any:
    """Return cfg with this stage's command-line values applied."""
    return cfg
