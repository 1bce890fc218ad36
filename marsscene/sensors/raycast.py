"""Ray casting against a :class:`Heightfield` by vectorised marching (for the LiDAR).

MuJoCo's ray-hfield test visits every prism under a ray's bounding box, which costs ~3 ms per
50 m ray on a 1389 x 1345 terrain; marching the bilinear surface in numpy in chunks (dropping
rays once they hit, leave the footprint or climb above the highest post) is ~100x faster.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.heightfield import Heightfield

__all__ = ["ray_heightfield"]

_CHUNK = 24
_GROW_M = 8.0  # the march step is one post out to 8 m, then grows linearly with range


def ray_heightfield(
    hf: Heightfield,
    origin_m: NDArray[np.float64],
    dirs: NDArray[np.float64],
    range_m: tuple[float, float],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance to the terrain along unit rays (``inf`` where there is no hit in range).

    Parameters
    ----------
    hf : Heightfield
    origin_m : ndarray of shape (3,)
        Common ray origin (in m, world frame).
    dirs : ndarray of shape (N, 3)
        Unit ray directions (world frame).
    range_m : (min, max)
        Search interval along each ray (in m).

    Returns
    -------
    dist_m : ndarray of shape (N,)
    normal : ndarray of shape (N, 3)
        Upward surface normal at the hit (zeros where there is no hit).
    """
    n = len(dirs)
    dist = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    step = hf.cell_size_m  # near field: one post per sample (posts are the surface's knots)
    # highest post within reach: rays climbing above it can never hit
    r0, c0 = hf.rowcol_of(origin_m[0], origin_m[1])
    k = int(np.ceil(range_m[1] / hf.cell_size_m)) + 1
    rows, cols = hf.shape
    win = hf.z_m[
        max(int(r0) - k, 0) : min(int(r0) + k + 2, rows),
        max(int(c0) - k, 0) : min(int(c0) + k + 2, cols),
    ]
    z_top = float(win.max()) if win.size else float(hf.z_m.max())
    x0, y0, x1, y1 = hf.bounds_xy_m
    active = np.arange(n)
    t0 = float(range_m[0])
    f_prev = (
        origin_m[2]
        + t0 * dirs[:, 2]
        - hf.sample(origin_m[0] + t0 * dirs[:, 0], origin_m[1] + t0 * dirs[:, 1])
    )
    active = active[f_prev > 0]  # rays starting under the ground see nothing
    f_prev = f_prev[f_prev > 0]
    while len(active) and t0 < range_m[1]:
        h = step * max(1.0, t0 / _GROW_M)  # coarser far away (angular spacing grows too)
        ts = t0 + h * np.arange(1, _CHUNK + 1)
        ts = ts[ts <= range_m[1] + h]
        d = dirs[active]
        p = origin_m[None, None, :] + d[:, None, :] * ts[None, :, None]
        f = p[..., 2] - hf.sample(p[..., 0], p[..., 1])
        px, py = p[..., 0], p[..., 1]
        below = (f <= 0) & (px >= x0) & (px <= x1) & (py >= y0) & (py <= y1)
        hit = below.any(axis=1)
        k = np.argmax(below, axis=1)
        hit_rows = np.flatnonzero(hit)
        if len(hit_rows):
            kk = k[hit_rows]
            fa = np.where(kk > 0, f[hit_rows, np.maximum(kk - 1, 0)], f_prev[hit_rows])
            fb = f[hit_rows, kk]
            ta = ts[kk] - h
            t_hit = ta + h * fa / np.maximum(fa - fb, 1e-12)
            ids = active[hit_rows]
            dist[ids] = t_hit
            q = origin_m[None, :] + dirs[ids] * t_hit[:, None]
            normal[ids] = hf.normal(q[:, 0], q[:, 1])
        last = p[:, -1, :]
        outside = (last[:, 0] < x0) | (last[:, 0] > x1) | (last[:, 1] < y0) | (last[:, 1] > y1)
        above = (last[:, 2] > z_top) & (d[:, 2] >= 0)
        keep = ~hit & ~outside & ~above
        active, f_prev = active[keep], f[keep, -1]
        t0 = float(ts[-1])
    dist[dist > range_m[1]] = np.inf
    return dist, normal
