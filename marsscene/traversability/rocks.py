"""Rocks on the map's grid: each rock's exposed height over the posts its footprint covers."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.errors import ConfigError

__all__ = ["rasterise_rocks"]


def rasterise_rocks(xy_m: ArrayLike, diameter_m: ArrayLike, height_m: ArrayLike, *,
                    shape: tuple[int, int], origin_xy_m: tuple[float, float],
                    cell_m: float) -> NDArray[np.float64]:
    """The tallest rock's exposed height (m) at each post of a grid (rows south to north).

    A rock (a disc of its diameter) covers the posts within half its diameter of its centre,
    and always its nearest post (a pebble between posts is not lost). Rocks off the grid are
    dropped. Vectorised over rocks, one pass per footprint size in posts.
    """
    xy = np.asarray(xy_m, dtype=np.float64).reshape(-1, 2)
    d = np.asarray(diameter_m, dtype=np.float64).ravel()
    h = np.asarray(height_m, dtype=np.float64).ravel()
    if not len(xy) == len(d) == len(h):
        raise ConfigError(f"rocks: {len(xy)} positions, {len(d)} diameters, {len(h)} heights")
    if not (np.isfinite(xy).all() and np.isfinite(d).all() and np.isfinite(h).all()):
        raise ConfigError("rocks: positions, diameters and heights must be finite")
    rows, cols = shape
    out = np.zeros(rows * cols)
    col_f = (xy[:, 0] - origin_xy_m[0]) / cell_m
    row_f = (xy[:, 1] - origin_xy_m[1]) / cell_m
    r0, c0 = np.rint(row_f).astype(np.intp), np.rint(col_f).astype(np.intp)
    reach = np.floor(0.5 * d / cell_m + 0.5).astype(np.intp)  # posts each side to test
    for k in np.unique(reach).tolist():
        sel = np.flatnonzero(reach == k)
        off = np.arange(-k, k + 1)
        dr, dc = (a.ravel() for a in np.meshgrid(off, off, indexing="ij"))
        rr, cc = r0[sel, None] + dr, c0[sel, None] + dc
        dist = np.hypot(rr - row_f[sel, None], cc - col_f[sel, None]) * cell_m
        hit = (dist <= 0.5 * d[sel, None]) | ((dr == 0) & (dc == 0))
        hit &= (rr >= 0) & (rr < rows) & (cc >= 0) & (cc < cols)
        np.maximum.at(out, (rr * cols + cc)[hit], np.broadcast_to(h[sel, None], hit.shape)[hit])
    return out.reshape(rows, cols)
