"""DEM ingest: the :class:`DEM` / :class:`Ortho` value objects, readers (``io``, ``io_ortho``;
the only rasterio importers, loaded lazily) and pure operations (``ops``, ``crs``, ``texture``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from marsscene._lazy import lazy_attributes
from marsscene.dem.model import DEM as DEM
from marsscene.dem.model import Ortho as Ortho
from marsscene.dem.ops import Crop as Crop

if TYPE_CHECKING:
    from marsscene.dem.io import read_dem as read_dem
    from marsscene.dem.io_ortho import read_ortho as read_ortho

__all__ = ["DEM", "Crop", "Ortho", "read_dem", "read_ortho"]


#: rasterio loads only when a raster is read
__getattr__ = lazy_attributes(__name__, {"read_dem": "marsscene.dem.io",
                                         "read_ortho": "marsscene.dem.io_ortho"})
