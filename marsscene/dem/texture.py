"""Co-register an orthoimage to a terrain footprint and make the draped RGB texture (pure).

A texture with ``st`` in [0, 1] over the footprint puts texture coordinate 0 on the **outer
edge** of its first pixel and 1 on the outer edge of its last (UsdUVTexture, MuJoCo), so the
texture grid's pixel *edges* must coincide with the footprint bounds (the outer terrain posts):
pixel ``(i, j)`` of a ``H x W`` texture covers
``x in [x0 + j w/W, x0 + (j+1) w/W]``, ``y in [y1 - (i+1) h/H, y1 - i h/H]`` (row 0 north).
Its centre is mapped into the ortho through the ortho's own transform
(:meth:`Ortho.rowcol_of`) and resampled there — co-registration goes through both transforms,
never through pixel counts.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.dem.crs import crs_from_wkt, proj_params
from marsscene.dem.model import Ortho
from marsscene.dem.resample import resample_separable
from marsscene.errors import ConfigError, CRSError

__all__ = ["same_crs", "texture_grid", "texture_rgb"]


def same_crs(a_wkt: str, b_wkt: str) -> bool:
    """True when two CRSs are the same (pyproj equality, or equal PROJ parameters)."""
    if not a_wkt or not b_wkt:
        return True
    a, b = crs_from_wkt(a_wkt), crs_from_wkt(b_wkt)
    if a.equals(b, ignore_axis_order=True):
        return True
    pa, pb = proj_params(a_wkt), proj_params(b_wkt)
    keys = set(pa) | set(pb)
    for k in keys - {"no_defs", "type", "units", "x_0", "y_0", "lat_0"}:
        va, vb = pa.get(k), pb.get(k)
        if isinstance(va, float | int) and isinstance(vb, float | int):
            if not np.isclose(va, vb, rtol=1e-9, atol=1e-7):
                return False
        elif va != vb:
            return False
    return True


def texture_grid(
    bounds_xy_m: tuple[float, float, float, float], pixel_m: float, max_px: int
) -> tuple[int, int]:
    """Texture ``(rows, cols)``: ``pixel_m`` resolution, at most ``max_px`` on a side."""
    x0, y0, x1, y1 = bounds_xy_m
    w, h = x1 - x0, y1 - y0
    px = max(pixel_m, max(w, h) / max_px)
    return max(round(h / px), 2), max(round(w / px), 2)


def texture_rgb(
    ortho: Ortho,
    bounds_xy_m: tuple[float, float, float, float],
    *,
    crs_wkt: str = "",
    max_px: int = 4096,
    percentiles: tuple[float, float] = (0.5, 99.5),
) -> NDArray[np.uint8]:
    """The ortho resampled onto the footprint as an sRGB ``uint8`` image, row 0 north.

    Parameters
    ----------
    ortho : Ortho
    bounds_xy_m : (x_min, y_min, x_max, y_max)
        Terrain footprint (outer posts) in the ortho's projected metres.
    crs_wkt : str
        The terrain's CRS; must equal the ortho's.
    max_px : int
        Largest texture side (in pixels).
    percentiles : (lo, hi)
        Linear contrast stretch between these percentiles of the valid values (all bands share
        it, so colour balance is kept). Missing pixels take the valid mean.

    Returns
    -------
    ndarray of shape (rows, cols, 3), uint8
    """
    if crs_wkt and ortho.crs_wkt and not same_crs(crs_wkt, ortho.crs_wkt):
        raise CRSError(
            f"{ortho.source_path}: the orthoimage CRS differs from the DEM's; reproject it "
            "onto the DEM's CRS first (e.g. gdalwarp -t_srs <DEM .prj>)"
        )
    x0, y0, x1, y1 = bounds_xy_m
    if not (x1 > x0 and y1 > y0):
        raise ConfigError(f"texture footprint {bounds_xy_m} is empty")
    ob = ortho.bounds_xy_m
    tol = 0.51 * ortho.pixel_m
    if x0 < ob[0] - tol or y0 < ob[1] - tol or x1 > ob[2] + tol or y1 > ob[3] + tol:
        raise ConfigError(
            f"{ortho.source_path}: the orthoimage (x {ob[0]:.2f}..{ob[2]:.2f}, y {ob[1]:.2f}.."
            f"{ob[3]:.2f} m) does not cover the terrain footprint {bounds_xy_m}"
        )
    rows, cols = texture_grid(bounds_xy_m, ortho.pixel_m, max_px)
    px_x, px_y = (x1 - x0) / cols, (y1 - y0) / rows
    xc = x0 + (np.arange(cols) + 0.5) * px_x
    yc = y1 - (np.arange(rows) + 0.5) * px_y
    u_rows, _ = ortho.rowcol_of(np.zeros(rows), yc)
    _, u_cols = ortho.rowcol_of(xc, np.zeros(cols))
    img = np.array(ortho.image, dtype=np.float32)
    valid = np.isfinite(img)
    if not valid.any():
        raise ConfigError(f"{ortho.source_path}: the orthoimage window has no valid pixels")
    lo, hi = np.percentile(img[valid], percentiles)
    img[~valid] = float(img[valid].mean())
    scale_x, scale_y = px_x / ortho.pixel_m, px_y / abs(ortho.transform[4])
    method = "area" if max(scale_x, scale_y) > 1.0 + 1e-9 else "bilinear"
    out = resample_separable(img, u_rows, u_cols, method=method, scale_rows=scale_y,
                             scale_cols=scale_x)
    span = float(hi - lo) if hi > lo else 1.0
    u8 = np.clip(np.rint((out - lo) / span * 255.0), 0, 255).astype(np.uint8)
    if u8.shape[2] == 1:
        u8 = np.repeat(u8, 3, axis=2)
    return np.ascontiguousarray(u8[:, :, :3])
