"""Crater stage configuration (``[craters]`` table)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene.errors import ConfigError

__all__ = ["CraterConfig"]


@dataclass(frozen=True, slots=True, kw_only=True)
class CraterConfig:
    """Crater population parameters."""

    enabled: bool = True
    """Generate and stamp craters."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"craters.enabled must be true or false; got {self.enabled!r}")
