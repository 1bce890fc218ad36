"""Lighting: Mars24 sun position, Beer's-law sun, dusty-sky diffuse light and visibility."""

from __future__ import annotations

from marsscene.lighting.config import LightingConfig as LightingConfig
from marsscene.lighting.model import Lighting as Lighting

__all__ = ["Lighting", "LightingConfig"]
