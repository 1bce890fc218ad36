"""Turn a north-up :class:`~marsscene.dem.DEM` into a scene-frame :class:`Heightfield`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from marsscene.dem.model import DEM
from marsscene.errors import ConfigError
from marsscene.terrain.config import TerrainConfig
from marsscene.terrain.heightfield import Heightfield

__all__ = ["GeoFrame", "footprint_projected_m", "heightfield_from_dem", "prepare_dem"]


@dataclass(frozen=True)
class GeoFrame:
    """How the scene frame sits on Mars (recorded in the manifest).

    ``z_scene = (elevation - datum_m) * z_scale``; the scene origin (0, 0) is the centre of the
    terrain footprint at projected ``origin_projected_xy_m`` in ``crs_wkt`` (planetocentric east
    longitude / latitude ``origin_lonlat_deg``), so scene ``x = x_proj - origin_x`` (east),
    ``y = y_proj - origin_y`` (north). On grids whose north is not true north (polar
    stereographic) ``grid_convergence_deg`` is the angle from true north to grid +y there.
    """

    datum_m: float
    origin_projected_xy_m: tuple[float, float] | None
    origin_lonlat_deg: tuple[float, float] | None
    crs_wkt: str
    z_scale: float = 1.0
    grid_convergence_deg: float = 0.0


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
    convergence = 0.0
    if dem.crs_wkt and dem.center_lonlat_deg is not None:
        from marsscene.dem.crs import grid_convergence_deg

        convergence = round(grid_convergence_deg(dem.crs_wkt, *dem.center_lonlat_deg), 9)
    frame = GeoFrame(
        datum_m=datum_m,
        origin_projected_xy_m=dem.center_xy() if dem.crs_wkt else None,
        origin_lonlat_deg=dem.center_lonlat_deg,
        crs_wkt=dem.crs_wkt,
        z_scale=z_scale,
        grid_convergence_deg=convergence,
    )
    return hf, frame


def footprint_projected_m(hf: Heightfield, frame: GeoFrame) -> tuple[float, float, float, float]:
    """The terrain footprint (outer posts) in the DEM's projected metres."""
    if frame.origin_projected_xy_m is None:
        raise ConfigError("the terrain has no projected origin (procedural or CRS-less DEM)")
    ox, oy = frame.origin_projected_xy_m
    x0, y0, x1, y1 = hf.bounds_xy_m
    return (x0 + ox, y0 + oy, x1 + ox, y1 + oy)


def prepare_dem(dem: DEM, cfg: TerrainConfig, *, default_post_m: float | None) -> tuple[
        DEM, float, list[str], dict[str, object]]:
    """Fill missing posts, detrend and coarsen a DEM as ``cfg`` asks (pure).

    Returns the DEM, the target post spacing (finer targets are left to the caller's detail /
    upsampling step), notes for the manifest and summary values.
    """
    from marsscene.dem import ops

    notes: list[str] = []
    summary: dict[str, object] = {"dem_shape_rows_cols": list(dem.shape),
                                  "dem_post_m": dem.post_m}
    if dem.metadata.get("PRODUCT_ID"):
        summary["dem_product_id"] = dem.product_id
    if "window_rows_cols" in dem.metadata:
        summary["dem_window_rows_cols"] = list(dem.metadata["window_rows_cols"])
    if cfg.fill_nodata:
        dem, n_filled = ops.fill_nodata(dem, max_missing_fraction=cfg.max_missing_fraction)
        if n_filled:
            notes.append(f"filled {n_filled} missing DEM posts by Laplace inpainting")
        summary["dem_filled_posts"] = n_filled
    elif 1.0 - dem.valid_fraction > cfg.max_missing_fraction:
        raise ConfigError(f"{(1 - dem.valid_fraction) * 100:.1f} % of the DEM posts are missing "
                          f"(terrain.max_missing_fraction = {cfg.max_missing_fraction})")
    if cfg.detrend:
        dem = ops.detrend(dem)
        notes.append("removed the DEM's best-fit plane (terrain.detrend)")
    post_m = cfg.post_m if cfg.post_m is not None else (default_post_m or dem.post_m)
    if post_m > dem.post_m * (1 + 1e-9):
        dem = ops.resample(dem, post_m, method=cfg.resampling)
        notes.append(f"resampled the DEM to {post_m:g} m ({dem.metadata['resampling']})")
    return dem, post_m, notes, summary
