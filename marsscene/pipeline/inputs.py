"""Inputs of a build: read (only the needed window of) the DEM and drape the orthoimage.

Called by :func:`marsscene.pipeline.build_scene`; rasterio is imported only when a file is read.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.config import SceneConfig
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError
from marsscene.terrain.config import TerrainConfig
from marsscene.terrain.default import default_dem_path
from marsscene.terrain.from_dem import GeoFrame, footprint_projected_m, plan_crop
from marsscene.terrain.heightfield import Heightfield

__all__ = ["HIRISE_DTM_CITATION", "drape_ortho", "load_inputs"]

HIRISE_DTM_CITATION = (
    "HiRISE stereo DTM (McEwen et al. 2007, doi:10.1029/2005JE002605; Kirk et al. 2008, "
    "doi:10.1029/2007JE003000), NASA/JPL/University of Arizona"
)


def load_inputs(config: SceneConfig, dem: DEM | None) -> tuple[DEM | None, dict[str, str]]:
    """Read (or take) the DEM, reading only the planned crop window (memory checked first)."""
    tcfg = config.terrain
    inputs = {"ortho": tcfg.ortho_path} if tcfg.ortho_path else {}
    if dem is not None:
        spec = plan_crop(tcfg, dem.transform, dem.shape, default_post_m=None)
        if spec is not None:
            from marsscene.dem.ops import crop

            dem = crop(dem, spec)
        return dem, ({"dem": dem.source_path} if dem.source_path else {}) | inputs
    src = tcfg.source
    if src == "procedural":
        return None, {}
    from marsscene.dem.io import open_source, read_dem  # rasterio only when a DEM is read

    path = default_dem_path() if src == "default" else tcfg.dem_path
    if path is None:  # pragma: no cover - TerrainConfig validation forbids it
        raise ConfigError('terrain.source = "dem" needs terrain.dem_path')
    info = open_source(path)
    default_post = 0.25 if src == "default" else None
    spec = plan_crop(tcfg, info.transform, info.shape, default_post_m=default_post)
    target = tcfg.post_m if tcfg.post_m is not None else default_post
    out = read_dem(path, band=tcfg.band, crop=spec, max_bytes=tcfg.max_memory_gb * 1e9,
                   target_post_m=target)
    return out, {"dem": str(path)} | inputs


def drape_ortho(
    tcfg: TerrainConfig,
    dem: DEM,
    hf: Heightfield,
    frame: GeoFrame,
    inputs: dict[str, str],
    notes: list[str],
    summary: dict[str, object],
) -> NDArray[np.uint8] | None:
    """The orthoimage (``tcfg.ortho_path``, else ``dem.ortho``) co-registered to the terrain
    footprint as an RGB texture, row 0 north; ``None`` without one."""
    ortho = dem.ortho
    if not tcfg.ortho_path and ortho is None:
        return None
    from marsscene.dem.texture import texture_grid, texture_rgb

    bounds = footprint_projected_m(hf, frame)
    if tcfg.ortho_path:
        from marsscene.dem.io_ortho import read_ortho  # rasterio

        rows_cols = texture_grid(bounds, 1e-9, tcfg.texture_max_px)
        ortho = read_ortho(tcfg.ortho_path, bounds_xy_m=bounds,
                           pixel_m=(bounds[2] - bounds[0]) / rows_cols[1])
    assert ortho is not None
    if "data_file" in ortho.metadata:  # the JP2 beside a .LBL
        inputs["ortho_data"] = str(ortho.metadata["data_file"])
    rgb = texture_rgb(ortho, bounds, crs_wkt=frame.crs_wkt, max_px=tcfg.texture_max_px)
    summary["texture_shape_rows_cols"] = list(rgb.shape[:2])
    name = ortho.metadata.get("PRODUCT_ID", ortho.source_path)
    notes.append(f"orthoimage {name} co-registered to the terrain footprint")
    return rgb
