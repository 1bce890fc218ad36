"""Turn a north-up :class:`~marsscene.dem.DEM` into a scene-frame :class:`Heightfield`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from marsscene.dem.model import DEM
from marsscene.errors import ConfigError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["GeoFrame", "heightfield_from_dem"]


@dataclass(frozen=True)
class GeoFrame:
    """How the scene frame sits on Mars (recorded in the manifest).

    ``z_scene = (elevation - datum_m) * z_scale``; the scene origin (0, 0) is the centre of the
    terrain footprint at projected ``origin_projected_xy_m`` in ``crs_wkt``.
    """

    datum_m: float
    origin_projected_xy_m: tuple[float, float] | None
    origin_lonlat_deg: tuple[float, float] | None
    crs_wkt: str
    z_scale: float = 1.0


def _fill_nearest(z: np.ndarray) -> np.ndarray:
    missing = ~np.isfinite(z)
    if not missing.any():
        return z
    if missing.all():
        raise ConfigError("the DEM has no valid posts")
    idx = ndimage.distance_transform_edt(missing, return_distances=False, return_indices=True)
    return z[tuple(idx)]


def heightfield_from_dem(dem: DEM, *, z_scale: float = 1.0) -> tuple[Heightfield, GeoFrame]:
    """Centre a DEM on the scene origin, subtract a datum and flip to south-up rows.

    The datum is the median valid elevation rounded to 1 cm, so a real DEM sits near z = 0.
    Missing posts must be filled before (``dem.ops.fill_nodata``); any left are filled with the
    nearest valid post.
    """
    z = dem.elevation_m.astype(np.float64)
    valid = np.isfinite(z)
    if not valid.any():
        raise ConfigError(f"DEM {dem.source_path or '<memory>'} has no valid posts")
    datum_m = round(float(np.median(z[valid])), 2)
    z = _fill_nearest(z)
    z_scene = ((z - datum_m) * z_scale)[::-1, :]
    hf = Heightfield.centered(z_scene.astype(np.float32), dem.post_m)
    frame = GeoFrame(
        datum_m=datum_m,
        origin_projected_xy_m=dem.center_xy() if dem.crs_wkt else None,
        origin_lonlat_deg=dem.center_lonlat_deg,
        crs_wkt=dem.crs_wkt,
        z_scale=z_scale,
    )
    return hf, frame
