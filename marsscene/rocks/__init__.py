"""Rocks: Golombek–Huertas size-frequency, placement, prototypes and collision parts."""

from __future__ import annotations

from marsscene.rocks.config import RockConfig as RockConfig
from marsscene.rocks.table import RockTable as RockTable

__all__ = ["RockConfig", "RockTable"]
