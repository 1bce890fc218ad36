"""Turn a north-up :class:`~marsscene.dem.DEM` into a scene-frame :class:`Heightfield`."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from marsscene.dem.model import DEM
from marsscene.errors import ConfigError
from marsscene.terrain.config import TerrainConfig
from marsscene.terrain.heightfield import Heightfield

if TYPE_CHECKING:
    from marsscene.dem.ops import Crop

__all__ = [
    "AUTO_CROP_M",
    "GeoFrame",
    "fill_nearest",
    "footprint_projected_m",
    "heightfield_from_dem",
    "plan_crop",
    "prepare_dem",
]


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


def fill_nearest(z: np.ndarray) -> np.ndarray:
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
    z = fill_nearest(z)
    z_scene = ((z - datum_m) * z_scale)[::-1, :]
    hf = Heightfield.centered(z_scene.astype(np.float32), dem.post_m)
    convergence = 0.0
    if dem.crs_wkt and dem.center_lonlat_deg is not None:
        from marsscene.dem.crs import grid_convergence_deg

        convergence = round(grid_convergence_deg(dem.crs_wkt, *dem.center_lonlat_deg), 9) + 0.0
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


#: Side of the centred square crop taken when no crop is configured and the whole DEM would not
#: fit in the memory budget (in m; the MarsLab reference scenes are 0.5-3.6 km).
AUTO_CROP_M = 1000.0


def plan_crop(cfg: TerrainConfig, transform: tuple[float, ...], shape: tuple[int, int], *,
              default_post_m: float | None) -> Crop | None:
    """The DEM crop the config asks for, or ``None`` for the whole DEM.

    ``crop_px`` / ``crop_bounds_m`` / ``crop_lonlat`` (+ ``size_m``) as given; ``size_m`` alone
    crops that footprint around the DEM's centre. With no crop and a whole DEM whose estimated
    build memory exceeds ``max_memory_gb``, a centred ``AUTO_CROP_M`` square is taken with an
    :class:`~marsscene.dem.ops.AutoCropWarning` (a full HiRISE DTM is ~6000 x 20000 posts).
    """
    from marsscene.dem import ops

    if cfg.crop_px is not None:
        return ops.Crop(pixels=cfg.crop_px)
    if cfg.crop_bounds_m is not None:
        return ops.Crop(bounds_xy_m=cfg.crop_bounds_m)
    if cfg.crop_lonlat is not None:
        return ops.Crop(center_lonlat_deg=cfg.crop_lonlat, size_m=cfg.size_m)
    rows, cols = shape
    post = abs(transform[0])
    size = cfg.size_m
    if size is None:
        target = cfg.post_m or default_post_m or post
        need = ops.estimate_bytes(rows * cols, int(rows * cols * (post / target) ** 2))
        if need <= cfg.max_memory_gb * 1e9 or max(rows, cols) * post <= AUTO_CROP_M:
            return None  # fits, or cropping cannot help (read_dem then refuses with the estimate)
        size = (AUTO_CROP_M, AUTO_CROP_M)
        warnings.warn(
            f"the whole {rows} x {cols} DEM would need about {need / 1e9:.1f} GB "
            f"(terrain.max_memory_gb = {cfg.max_memory_gb}); building the centred "
            f"{AUTO_CROP_M:g} m x {AUTO_CROP_M:g} m crop instead (set size_m / crop_lonlat / "
            "crop_px to choose)", ops.AutoCropWarning, stacklevel=3)
    n_cols = min(round(size[0] / post) + 1, cols)
    n_rows = min(round(size[1] / abs(transform[4])) + 1, rows)
    return ops.Crop(pixels=(rows // 2 - n_rows // 2, cols // 2 - n_cols // 2, n_rows, n_cols))


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
        win = dem.metadata["window_rows_cols"]
        notes.append(f"read DEM window rows {win[0]}..{win[0] + win[2] - 1}, "
                     f"cols {win[1]}..{win[1] + win[3] - 1}")
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
    finer = post_m < dem.post_m * (1 - 1e-9)
    if post_m > dem.post_m * (1 + 1e-9) or (finer and not cfg.detail and cfg.resampling):
        dem = ops.resample(dem, post_m, method=cfg.resampling)
        notes.append(f"resampled the DEM to {post_m:g} m ({dem.metadata['resampling']})")
    return dem, post_m, notes, summary
