"""DEM ingest: the :class:`DEM` value object, readers (``io``) and pure operations (``ops``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from marsscene.dem.model import DEM as DEM

if TYPE_CHECKING:
    from marsscene.dem.io import read_dem as read_dem

__all__ = ["DEM", "read_dem"]


def __getattr__(name: str) -> Any:  # lazy: rasterio loads only when a DEM is read
    if name == "read_dem":
        from marsscene.dem.io import read_dem

        return read_dem
    raise AttributeError(name)
