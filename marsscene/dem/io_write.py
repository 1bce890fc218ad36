"""Write georeferenced rasters (GeoTIFF) of scene grids with rasterio: the layers a scene derives
from its terrain (traversability, the orbital map) in the scene's own projected CRS.

A scene grid is a :class:`~marsscene.terrain.heightfield.Heightfield`-like array: rows run south
to north (row 0 at the south edge, ``origin_xy_m`` the scene x, y of post (0, 0)), posts
``cell_m`` apart. GeoTIFF rows run north to south with pixel-is-area corners, so the writer
flips the rows and puts each post at the centre of its pixel (the convention the DEM reader
follows, :doc:`/science/dem`). Scene x, y become projected metres by adding the frame's
``origin_projected_xy_m``; a scene without a geographic frame (a procedural one) is written in
scene metres with no CRS. Bytes are reproducible: no timestamps, deflate with a fixed level.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError

__all__ = ["scene_grid_transform", "write_geotiff"]


def scene_grid_transform(origin_xy_m: Sequence[float], cell_m: float, rows: int,
                         origin_projected_xy_m: Sequence[float] | None = None) -> object:
    """The ``affine.Affine`` of a south-up scene grid written north-up (post = pixel centre)."""
    from affine import Affine

    x0, y0 = float(origin_xy_m[0]), float(origin_xy_m[1])
    if origin_projected_xy_m is not None:
        x0 += float(origin_projected_xy_m[0])
        y0 += float(origin_projected_xy_m[1])
    top = y0 + (rows - 1) * cell_m + 0.5 * cell_m  # north edge of the northern row of pixels
    return Affine(cell_m, 0.0, x0 - 0.5 * cell_m, 0.0, -cell_m, top)


def write_geotiff(path: str | os.PathLike[str], layers: Mapping[str, NDArray[np.generic]], *,
                  origin_xy_m: Sequence[float], cell_m: float, crs_wkt: str | None = None,
                  origin_projected_xy_m: Sequence[float] | None = None,
                  nodata: float | None = None) -> Path:
    """Write ``layers`` (name -> (rows, cols) south-up scene grid, one dtype) as one band each,
    named by the band descriptions, to a GeoTIFF at ``path``; returns the path.

    ``crs_wkt`` and ``origin_projected_xy_m`` (the scene frame's) georeference it; without them
    the raster is in scene metres with no CRS.
    """
    import rasterio

    if not layers:
        raise ConfigError(f"{path}: no layers to write")
    arrays = [np.asarray(a) for a in layers.values()]
    shape, dtype = arrays[0].shape, arrays[0].dtype
    if len(shape) != 2 or any(a.shape != shape or a.dtype != dtype for a in arrays):
        raise ConfigError(f"{path}: layers must share one 2-D shape and dtype, got "
                          f"{[(a.shape, str(a.dtype)) for a in arrays]}")
    transform = scene_grid_transform(origin_xy_m, cell_m, shape[0],
                                     origin_projected_xy_m if crs_wkt else None)
    out = Path(path)
    profile = {"driver": "GTiff", "height": shape[0], "width": shape[1], "count": len(arrays),
               "dtype": dtype.name, "transform": transform, "compress": "deflate",
               "zlevel": 6, "predictor": 2 if dtype.kind in "iu" else 1}
    if crs_wkt:
        profile["crs"] = rasterio.crs.CRS.from_user_input(crs_wkt)  # WKT or PROJ
    if nodata is not None:
        profile["nodata"] = nodata
    with rasterio.Env(GDAL_TIFF_INTERNAL_MASK=True), rasterio.open(out, "w", **profile) as ds:
        for band, (name, array) in enumerate(zip(layers, arrays, strict=True), start=1):
            ds.write(np.ascontiguousarray(array[::-1]), band)
            ds.set_band_description(band, name)
    return out
