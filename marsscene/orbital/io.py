"""An orbital map's files in a scene folder: ``orbital/dem.tif``, ``orbital/ortho.tif`` and
``orbital/orbital.json`` (the grids, the frame and the model's parameters).

GeoTIFFs through :func:`marsscene.dem.io_write.write_geotiff` (north-up, each post at its
pixel's centre, the scene frame's CRS and projected origin where it has one; scene metres and no
CRS for a procedural scene), read back through the DEM reader. Bytes are reproducible.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.orbital.grid import OrbitalMap
from marsscene.orbital.model import OrbitalModel

__all__ = ["ORBITAL_DIR", "read_orbital_map", "write_orbital_map"]

ORBITAL_DIR = "orbital"
_DEM, _ORTHO, _META = "dem.tif", "ortho.tif", "orbital.json"


def _meta(omap: OrbitalMap) -> dict[str, Any]:
    doc: dict[str, Any] = {
        "source": omap.source, "seed": omap.seed, "stage": "orbital",
        "dem": {"file": _DEM, "shape_rows_cols": list(omap.shape), "cell_m": omap.cell_m,
                "origin_xy_m": list(omap.origin_xy_m), "band": "elevation_m",
                "z": "scene z: (elevation - datum) * z_scale"},
        "crs_wkt": omap.crs_wkt,
        "origin_projected_xy_m": (list(omap.origin_projected_xy_m)
                                  if omap.origin_projected_xy_m is not None else None),
        "model": omap.model.to_dict() if omap.source == "procedural" else None,
    }
    if omap.image is not None:
        assert omap.image_pixel_m is not None and omap.image_origin_xy_m is not None
        doc["ortho"] = {"file": _ORTHO, "shape_rows_cols": list(omap.image.shape),
                        "pixel_m": omap.image_pixel_m,
                        "origin_xy_m": list(omap.image_origin_xy_m), "band": "reflectance"}
    return doc


def write_orbital_map(omap: OrbitalMap, scene_dir: str | os.PathLike[str]) -> Path:
    """Write ``omap`` into ``SCENE_DIR/orbital/``; returns that folder."""
    from marsscene.dem.io_write import write_geotiff

    out = Path(scene_dir) / ORBITAL_DIR
    out.mkdir(parents=True, exist_ok=True)
    crs, proj = omap.crs_wkt or None, omap.origin_projected_xy_m
    nodata = float("nan") if np.isnan(omap.dem_m).any() else None
    write_geotiff(out / _DEM, {"elevation_m": omap.dem_m}, origin_xy_m=omap.origin_xy_m,
                  cell_m=omap.cell_m, nodata=nodata, crs_wkt=crs, origin_projected_xy_m=proj)
    if omap.image is not None:
        assert omap.image_pixel_m is not None and omap.image_origin_xy_m is not None
        write_geotiff(out / _ORTHO, {"reflectance": omap.image},
                      origin_xy_m=omap.image_origin_xy_m, cell_m=omap.image_pixel_m,
                      crs_wkt=crs, origin_projected_xy_m=proj)
    (out / _META).write_text(json.dumps(_meta(omap), indent=2, sort_keys=True) + "\n",
                             encoding="utf-8")
    return out


def read_orbital_map(scene_dir: str | os.PathLike[str]) -> OrbitalMap:
    """The orbital map :func:`write_orbital_map` wrote into ``scene_dir``."""
    from marsscene.dem.io import read_dem

    folder = Path(scene_dir) / ORBITAL_DIR
    doc = json.loads((folder / _META).read_text(encoding="utf-8"))
    dem = read_dem(folder / _DEM).elevation_m[::-1]
    image = px = origin = None
    if "ortho" in doc:
        image = read_dem(folder / _ORTHO).elevation_m[::-1]
        px, origin = float(doc["ortho"]["pixel_m"]), tuple(doc["ortho"]["origin_xy_m"])
    kw = {k: v for k, v in (doc["model"] or {}).items() if k in OrbitalModel.__dataclass_fields__}
    if doc["model"] and "image_shading" not in kw:
        kw["image_shading"] = "none"  # written before the image was shaded
    model = OrbitalModel(**kw)
    proj = doc["origin_projected_xy_m"]
    return OrbitalMap(np.ascontiguousarray(dem, dtype=np.float32), float(doc["dem"]["cell_m"]),
                      tuple(doc["dem"]["origin_xy_m"]), doc["source"], model, int(doc["seed"]),
                      image=None if image is None else np.ascontiguousarray(image, np.float32),
                      image_pixel_m=px, image_origin_xy_m=origin, crs_wkt=doc["crs_wkt"],
                      origin_projected_xy_m=tuple(proj) if proj is not None else None)
