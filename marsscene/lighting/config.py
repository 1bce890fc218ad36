"""Lighting stage configuration (``[lighting]`` table)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene.errors import ConfigError

__all__ = ["LightingConfig"]


@dataclass(frozen=True, slots=True, kw_only=True)
class LightingConfig:
    """Sun and sky parameters."""

    enabled: bool = True
    """Compute and export sun and sky lights."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"lighting.enabled must be true or false; got {self.enabled!r}")
