"""Rock stage configuration (``[rocks]`` table)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene.errors import ConfigError

__all__ = ["RockConfig"]


@dataclass(frozen=True, slots=True, kw_only=True)
class RockConfig:
    """Rock population parameters."""

    enabled: bool = True
    """Sample and place rocks."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"rocks.enabled must be true or false; got {self.enabled!r}")
