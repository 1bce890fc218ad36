"""Terrain: the :class:`Heightfield`, procedural synthesis, sub-DEM detail and meshing."""

from __future__ import annotations

from marsscene.terrain.config import TerrainConfig as TerrainConfig
from marsscene.terrain.from_dem import GeoFrame as GeoFrame
from marsscene.terrain.from_dem import heightfield_from_dem as heightfield_from_dem
from marsscene.terrain.heightfield import Heightfield as Heightfield
from marsscene.terrain.synth import add_detail as add_detail
from marsscene.terrain.synth import fbm_surface as fbm_surface
from marsscene.terrain.synth import measure_hurst as measure_hurst
from marsscene.terrain.synth import resample as resample
from marsscene.terrain.synth import synthesize as synthesize

__all__ = [
    "GeoFrame",
    "Heightfield",
    "TerrainConfig",
    "add_detail",
    "fbm_surface",
    "heightfield_from_dem",
    "measure_hurst",
    "resample",
    "synthesize",
]
