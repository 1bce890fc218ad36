"""DEM ingest: the :class:`DEM` / :class:`Ortho` value objects, readers (``io``, ``io_ortho``;
the only rasterio importers, loaded lazily) and pure operations (``ops``, ``crs``, ``texture``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from marsscene.dem.model import DEM as DEM
from marsscene.dem.model import Ortho as Ortho
from marsscene.dem.ops import Crop as Crop

if TYPE_CHECKING:
    from marsscene.dem.io import read_dem as read_dem
    from marsscene.dem.io_ortho import read_ortho as read_ortho

__all__ = ["DEM", "Crop", "Ortho", "read_dem", "read_ortho"]


def __getattr__(name: str) -> Any:  # lazy: rasterio loads only when a raster is read
    if name == "read_dem":
        from marsscene.dem.io import read_dem

        return read_dem
    if name == "read_ortho":
        from marsscene.dem.io_ortho import read_ortho

        return read_ortho
    raise AttributeError(name)
