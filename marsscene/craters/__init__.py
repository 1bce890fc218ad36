"""Craters: Mars production/chronology functions, populations, profiles and stamping."""

from __future__ import annotations

from marsscene.craters.config import CraterConfig as CraterConfig
from marsscene.craters.table import CraterTable as CraterTable

__all__ = ["CraterConfig", "CraterTable"]
