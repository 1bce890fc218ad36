"""Read a DEM averaged to a coarser post spacing, strip by strip.

The outer level of a level-of-detail scene over a whole HiRISE DTM (often 6 x 20 km at 1 m,
larger than memory once worked on) needs only an average every few posts. This reader takes
the raster (or its crop window) in strips of rows with rasterio windows and reduces each strip
at once, so memory is bounded by one strip plus the output: output post ``j`` is the mean of the
valid posts in the ``(f | 1) x (f | 1)`` box centred on input post ``j * f`` (an odd box, so
the output posts are input posts and a finer window of the same raster lines up with them).
Boxes with no valid post are missing (NaN), like the posts of :func:`marsscene.dem.io.read_dem`.
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import NDArray

from marsscene.dem.io import missing_mask, open_source, read_window, select_band
from marsscene.dem.model import DEM
from marsscene.dem.ops import Crop, PixelWindow, _center_lonlat, crop_window, window_transform

__all__ = ["read_dem_averaged"]

#: Input posts read per strip (about 64 MB of float64 work arrays).
STRIP_POSTS = 8_000_000


def _box_sums(v: NDArray[np.float64], centres: NDArray[np.int64], half: int,
              axis: int) -> NDArray[np.float64]:
    """Sums of ``v`` over ``[c - half, c + half]`` (clipped) along ``axis`` for each centre."""
    n = v.shape[axis]
    pad = [(0, 0)] * v.ndim
    pad[axis] = (1, 0)
    cum = np.pad(np.cumsum(v, axis=axis), pad)
    lo = np.clip(centres - half, 0, n)
    hi = np.clip(centres + half + 1, 0, n)
    return np.asarray(np.take(cum, hi, axis=axis) - np.take(cum, lo, axis=axis))


def read_dem_averaged(path: str | os.PathLike[str], *, factor: int, band: int | None = None,
                      crop: Crop | None = None, strip_posts: int = STRIP_POSTS) -> DEM:
    """The DEM (or its ``crop``) averaged to ``factor`` times its post spacing.

    Parameters
    ----------
    path : path-like
        Any raster :func:`marsscene.dem.io.read_dem` reads.
    factor : int
        Output posts are every ``factor``-th input post (>= 1).
    band, crop
        As for :func:`~marsscene.dem.io.read_dem`.
    strip_posts : int
        Input posts read at a time.
    """
    src = open_source(path)
    b = select_band(src, band)
    rows, cols = src.shape
    win = crop_window(src.transform, src.shape, src.crs_wkt, crop) if crop is not None else \
        PixelWindow(0, 0, rows, cols)
    half = (factor | 1) // 2
    out_rows, out_cols = (win.rows - 1) // factor + 1, (win.cols - 1) // factor + 1
    col_centres = np.arange(out_cols, dtype=np.int64) * factor
    out = np.full((out_rows, out_cols), np.nan, dtype=np.float32)
    chunk = max(1, strip_posts // max(win.cols * factor, 1))  # output rows per strip
    for o0 in range(0, out_rows, chunk):  # strips of rows: memory bounded by one strip
        o1 = min(o0 + chunk, out_rows)
        n0, n1 = max(o0 * factor - half, 0), min((o1 - 1) * factor + half + 1, win.rows)
        raw = read_window(src, b, PixelWindow(win.row_off + n0, win.col_off, n1 - n0,
                                              win.cols))
        z = raw.astype(np.float64) * src.scale + src.offset
        valid = ~missing_mask(raw, src)
        z[~valid] = 0.0
        centres = np.arange(o0, o1, dtype=np.int64) * factor - n0
        s = _box_sums(_box_sums(z, centres, half, 0), col_centres, half, 1)
        c = _box_sums(_box_sums(valid.astype(np.float64), centres, half, 0), col_centres, half,
                      1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[o0:o1] = np.where(c > 0, s / np.maximum(c, 1.0), np.nan)
    a, bb, cx, d, e, fy = window_transform(src.transform, win)
    # output pixel j's centre is input pixel j * factor's centre
    transform = (a * factor, bb, cx + a * 0.5 * (1 - factor), d, e * factor,
                 fy + e * 0.5 * (1 - factor))
    meta = {"driver": src.driver, "band": b, **src.metadata,
            "window_rows_cols": [win.row_off, win.col_off, win.rows, win.cols],
            "averaged_factor": factor}
    dem = DEM(elevation_m=out, transform=transform, crs_wkt=src.crs_wkt,
              source_path=str(src.source_path), metadata=meta)
    return dem.replace(center_lonlat_deg=_center_lonlat(dem))
