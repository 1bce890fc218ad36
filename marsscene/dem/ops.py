"""Pure operations on :class:`~marsscene.dem.DEM`: crop, rescale, nodata fill, detrend.

Every function returns a new DEM and never modifies its input. Crops are computed as pixel
windows from the DEM's transform (:func:`crop_window`), so :mod:`marsscene.dem.io` can read just
that window from a large file and :func:`crop` can cut an in-memory DEM identically.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from marsscene._validate import check_choice, check_range
from marsscene.dem.crs import lonlat_to_xy, xy_to_lonlat
from marsscene.dem.fill import detrend, fill_nodata
from marsscene.dem.model import DEM
from marsscene.dem.resample import RESAMPLING, resample_separable
from marsscene.errors import ConfigError, CRSError, MarsSceneWarning, MemoryBudgetError

__all__ = [
    "AutoCropWarning",
    "Crop",
    "CropClippedWarning",
    "PixelWindow",
    "check_memory",
    "crop",
    "crop_window",
    "detrend",
    "estimate_bytes",
    "fill_nodata",
    "resample",
]

#: Working bytes per source post (read buffer, mask, float64 copies) and per output post
#: (float32 grid, spline/detail work arrays, normals, mesh vertices, faces and exporter buffers).
BYTES_PER_SOURCE_POST = 24
BYTES_PER_OUTPUT_POST = 160


class CropClippedWarning(MarsSceneWarning):
    """A requested crop extends past the DEM and was clipped to it."""


class AutoCropWarning(MarsSceneWarning):
    """No crop was given and the whole DEM would not fit in memory: a centred crop was taken."""


@dataclass(frozen=True, slots=True)
class PixelWindow:
    """A pixel window ``rows x cols`` whose upper-left pixel is ``(row_off, col_off)``."""

    row_off: int
    col_off: int
    rows: int
    cols: int


@dataclass(frozen=True, slots=True, kw_only=True)
class Crop:
    """What part of a DEM to keep: one of ``pixels``, ``bounds_xy_m`` or ``center_lonlat_deg``.

    ``pixels = (row_off, col_off, rows, cols)``; ``bounds_xy_m = (x_min, y_min, x_max, y_max)`` in
    the DEM's projected metres (posts whose centres fall inside are kept);
    ``center_lonlat_deg = (east lon, lat)`` with ``size_m = (width, height)``: the post nearest
    the centre and ``round(size / post) + 1`` posts across.
    """

    pixels: tuple[int, int, int, int] | None = None
    bounds_xy_m: tuple[float, float, float, float] | None = None
    center_lonlat_deg: tuple[float, float] | None = None
    size_m: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        given = [k for k in ("pixels", "bounds_xy_m", "center_lonlat_deg")
                 if getattr(self, k) is not None]
        if len(given) != 1:
            raise ConfigError(f"a crop needs exactly one of pixels, bounds_xy_m, "
                              f"center_lonlat_deg; got {given or 'none'}")
        if self.center_lonlat_deg is not None:
            if self.size_m is None:
                raise ConfigError("a lon/lat crop needs size_m = (width, height) in metres")
            for v in self.size_m:
                check_range("crop size_m", v, 0.0, 1e6, lo_open=True)
            check_range("crop latitude", self.center_lonlat_deg[1], -90.0, 90.0)
        if self.pixels is not None and (min(self.pixels[2:]) < 2 or min(self.pixels[:2]) < 0):
            raise ConfigError(f"crop pixels = {self.pixels}: need row_off, col_off >= 0 "
                              "and rows, cols >= 2")


def crop_window(
    transform: tuple[float, ...], shape: tuple[int, int], crs_wkt: str, spec: Crop
) -> PixelWindow:
    """The pixel window of ``spec`` in a raster with this transform and shape.

    Raises
    ------
    ConfigError
        The crop lies outside the DEM or keeps fewer than 2 x 2 posts.
    CRSError
        A lon/lat crop on a raster without a projected metric CRS.
    """
    a, _, c, _, e, f = transform
    n_rows, n_cols = shape
    if spec.pixels is not None:
        r0, c0, nr, nc = spec.pixels
        r1, c1 = r0 + nr, c0 + nc
        what = f"pixel window {spec.pixels}"
    elif spec.bounds_xy_m is not None:
        x0, y0, x1, y1 = spec.bounds_xy_m
        if not (x1 > x0 and y1 > y0):
            raise ConfigError(f"crop bounds_xy_m = {spec.bounds_xy_m}: need x_min < x_max, "
                              "y_min < y_max")
        c0 = int(np.ceil((x0 - c) / a - 0.5 - 1e-9))
        c1 = int(np.floor((x1 - c) / a - 0.5 + 1e-9)) + 1
        r0 = int(np.ceil((y1 - f) / e - 0.5 - 1e-9))
        r1 = int(np.floor((y0 - f) / e - 0.5 + 1e-9)) + 1
        what = f"bounds {spec.bounds_xy_m} m"
    else:
        assert spec.center_lonlat_deg is not None and spec.size_m is not None
        lon, lat = spec.center_lonlat_deg
        if not crs_wkt:
            raise CRSError(
                "the DEM has no geo-reference (no CRS), so a lon/lat crop cannot be placed; "
                "crop by pixels or projected metres instead"
            )
        x, y = lonlat_to_xy(crs_wkt, lon, lat)
        cc = int(np.floor((float(x) - c) / a))
        rc = int(np.floor((float(y) - f) / e))
        nc = round(spec.size_m[0] / a) + 1
        nr = round(spec.size_m[1] / -e) + 1
        c0, r0 = cc - nc // 2, rc - nr // 2
        c1, r1 = c0 + nc, r0 + nr
        what = f"lon/lat ({lon}, {lat}) x {spec.size_m} m"
    cr0, cc0, cr1, cc1 = max(r0, 0), max(c0, 0), min(r1, n_rows), min(c1, n_cols)
    if cr1 - cr0 < 2 or cc1 - cc0 < 2:
        xmin, ymax = c, f
        raise ConfigError(
            f"crop {what} lies outside the DEM ({n_rows} x {n_cols} posts, x {xmin:.1f}.."
            f"{xmin + a * n_cols:.1f} m, y {ymax + e * n_rows:.1f}..{ymax:.1f} m)"
        )
    if (cr0, cc0, cr1, cc1) != (r0, c0, r1, c1):
        warnings.warn(f"crop {what} extends past the DEM; clipped to rows {cr0}..{cr1 - 1}, "
                      f"cols {cc0}..{cc1 - 1}", CropClippedWarning, stacklevel=2)
    return PixelWindow(cr0, cc0, cr1 - cr0, cc1 - cc0)


def window_transform(transform: tuple[float, ...], win: PixelWindow) -> tuple[float, ...]:
    """Transform of a window's upper-left corner."""
    a, b, c, d, e, f = transform
    return (a, b, c + a * win.col_off, d, e, f + e * win.row_off)


def _center_lonlat(dem: DEM) -> tuple[float, float] | None:
    if not dem.crs_wkt:
        return None
    try:
        lon, lat = xy_to_lonlat(dem.crs_wkt, *dem.center_xy())
    except Exception:  # a CRS without a usable inverse: no centre
        return None
    return (float(lon), float(lat))


def crop(dem: DEM, spec: Crop) -> DEM:
    """Cut a DEM (and keep its ortho untouched) to a :class:`Crop`."""
    win = crop_window(dem.transform, dem.shape, dem.crs_wkt, spec)
    z = dem.elevation_m[win.row_off:win.row_off + win.rows, win.col_off:win.col_off + win.cols]
    out = dem.replace(elevation_m=z.copy(), transform=window_transform(dem.transform, win))
    return out.replace(center_lonlat_deg=_center_lonlat(out))


def estimate_bytes(source_posts: int, output_posts: int) -> int:
    """Rough peak bytes of a build reading ``source_posts`` and producing ``output_posts``."""
    return source_posts * BYTES_PER_SOURCE_POST + output_posts * BYTES_PER_OUTPUT_POST


def check_memory(source_posts: int, output_posts: int, max_bytes: float, what: str) -> None:
    """Raise :class:`MemoryBudgetError` if :func:`estimate_bytes` exceeds ``max_bytes``."""
    need = estimate_bytes(source_posts, output_posts)
    if need > max_bytes:
        raise MemoryBudgetError(
            f"{what}: {source_posts:,} source posts -> {output_posts:,} output posts needs "
            f"about {need / 1e9:.1f} GB, over the {max_bytes / 1e9:.1f} GB budget "
            "(terrain.max_memory_gb): crop smaller (--crop-lonlat/--size-m, --crop-px), use a "
            "coarser --post-m, or keep the crop with a level-of-detail terrain (--lod: the DEM "
            "at its own posts outside a --focus-size-m square detailed to 0.25 m, read "
            "averaged strip by strip)"
        )


def resample(
    dem: DEM,
    post_m: float,
    *,
    method: str | None = None,
    xy_scale: float = 1.0,
    z_scale: float = 1.0,
) -> DEM:
    """Resample to ``post_m`` over the same footprint (outer post centres kept).

    Parameters
    ----------
    dem : DEM
        Missing posts must be filled first (NaN spreads).
    post_m : float
        Target post spacing (in m, in the source CRS before ``xy_scale``).
    method : {"bilinear", "cubic", "area"}, optional
        Default: ``"area"`` when downsampling, ``"bilinear"`` otherwise.
    xy_scale, z_scale : float
        Horizontal scale about the raster centre and vertical scale of elevations (the CRS is
        then nominal; both are recorded in ``metadata``).
    """
    check_range("post_m", post_m, 0.0, 1e4, lo_open=True)
    check_range("xy_scale", xy_scale, 0.0, 1e3, lo_open=True)
    check_range("z_scale", z_scale, 0.0, 1e3, lo_open=True)
    src = dem.post_m
    method = method or ("area" if post_m > src * (1 + 1e-9) else "bilinear")
    check_choice("resampling", method, RESAMPLING)
    rows, cols = dem.shape
    n_cols = int(np.floor((cols - 1) * src / post_m + 1e-9)) + 1
    n_rows = int(np.floor((rows - 1) * src / post_m + 1e-9)) + 1
    step = post_m / src
    z = resample_separable(
        dem.elevation_m, np.arange(n_rows, dtype=np.float64) * step,
        np.arange(n_cols, dtype=np.float64) * step,
        method=method, scale_rows=step, scale_cols=step,
    )
    x0, _, _, y1 = dem.post_bounds_xy_m
    cx, cy = dem.center_xy()
    new_post = post_m * xy_scale
    c = cx + (x0 - cx) * xy_scale - new_post / 2.0
    f = cy + (y1 - cy) * xy_scale + new_post / 2.0
    if z_scale != 1.0:
        z = z * np.float32(z_scale)
    meta = {**dem.metadata, "resampling": method}
    if xy_scale != 1.0 or z_scale != 1.0:
        meta.update(xy_scale=xy_scale, z_scale_applied=z_scale)
    out = dem.replace(elevation_m=z, transform=(new_post, 0.0, c, 0.0, -new_post, f),
                      metadata=meta)
    if xy_scale == 1.0:  # the footprint may shrink by < 1 post: keep the centre lon/lat true
        out = out.replace(center_lonlat_deg=_center_lonlat(out))
    return out
