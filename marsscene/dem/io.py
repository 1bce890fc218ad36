"""Read DEM rasters with rasterio/GDAL (the only module that imports rasterio).

GeoTIFF/COG, ISIS3 cubes and PDS3 ``.IMG`` are all opened through GDAL's drivers.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.dem.model import DEM
from marsscene.errors import CRSError, DEMReadError

__all__ = ["read_dem"]


def _center_lonlat(crs_wkt: str, x: float, y: float) -> tuple[float, float] | None:
    from pyproj import CRS, Transformer

    crs = CRS.from_wkt(crs_wkt)
    geo = crs.geodetic_crs
    if geo is None:
        return None
    lon, lat = Transformer.from_crs(crs, geo, always_xy=True).transform(x, y)
    return (float(lon) % 360.0, float(lat))


def read_dem(path: str | os.PathLike[str], *, band: int = 1) -> DEM:
    """Read an elevation raster.

    Parameters
    ----------
    path : path-like
        A raster GDAL can open (GeoTIFF, ISIS3 ``.cub``, PDS3 ``.IMG``/``.LBL``).
    band : int
        1-based band holding elevation.

    Returns
    -------
    DEM
        Missing posts (GDAL nodata) are NaN.

    Raises
    ------
    DEMReadError
        The file does not exist or is not a raster GDAL can read.
    CRSError
        The raster's CRS is geographic (degrees) where projected metres are needed.
    """
    import rasterio
    from rasterio.errors import RasterioError

    p = Path(path)
    if not p.exists():
        raise DEMReadError(f"DEM file not found: {p}")
    try:
        with rasterio.open(p) as ds:
            if not 1 <= band <= ds.count:
                raise DEMReadError(f"{p}: band {band} does not exist (file has {ds.count})")
            data = ds.read(band, masked=True).astype(np.float32)
            a, b, c, d, e, f = (float(v) for v in tuple(ds.transform)[:6])
            transform = (a, b, c, d, e, f)
            crs_wkt = ds.crs.to_wkt() if ds.crs else ""
            is_geographic = bool(ds.crs and ds.crs.is_geographic)
            tags: dict[str, Any] = dict(ds.tags())
            driver = ds.driver
    except RasterioError as err:
        raise DEMReadError(f"{p}: not a readable raster ({err})") from None
    if is_geographic:
        raise CRSError(
            f"{p}: CRS is geographic (degrees); marsscene needs a projected CRS in metres"
        )
    elevation = np.ma.filled(data, np.nan).astype(np.float32)
    dem = DEM(
        elevation_m=elevation,
        transform=transform,
        crs_wkt=crs_wkt,
        source_path=str(p),
        metadata={"driver": driver, **tags},
    )
    center = _center_lonlat(crs_wkt, *dem.center_xy()) if crs_wkt else None
    return DEM(
        elevation_m=dem.elevation_m,
        transform=dem.transform,
        crs_wkt=crs_wkt,
        source_path=str(p),
        metadata=dem.metadata,
        center_lonlat_deg=center,
    )
