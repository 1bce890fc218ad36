"""Soil as part of the world: which soil lies where (:class:`SoilMap`), authored with the scene
from its terrain and craters (``[soil]``, :class:`SoilConfig`), written beside it and read by
the rover's wheel--soil model (:mod:`marsscene.sim.wheel_soil`)."""

from marsscene.soil.author import author_soil_map
from marsscene.soil.config import SoilConfig
from marsscene.soil.map import SOIL_DIR, SoilMap, read_soil_map, write_soil_map

__all__ = ["SOIL_DIR", "SoilConfig", "SoilMap", "author_soil_map", "read_soil_map",
           "write_soil_map"]
