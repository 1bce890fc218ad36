"""Ray casting against a :class:`Heightfield` for the LiDAR: exact and fast.

:class:`TerrainCaster` intersects rays with the terrain's triangulated surface (two triangles
per cell, the surface MuJoCo collides with and renders), the catalogue rocks and the static
geoms through Intel Embree (``embreex``, the only importer of it), all in ONE scene: one cast
per scan (~20 ms for 128 x 1024 rays on one core; ``embreex`` releases the GIL while it casts).
The scene covers a disc of ``range + margin`` around a centre and is rebuilt when the sensor has
moved ``margin`` from it, so memory stays bounded on kilometre-scale terrains.

Without ``embreex`` it falls back to :func:`ray_heightfield`, a vectorised numpy march that
brackets the first crossing and refines it by bisection on the bilinear surface (millimetres,
but ~25x slower). Both are exact in the world frame: no error pattern that moves with the
sensor (a coarse march with linear interpolation between samples made one, 0.1 m at the 95th
percentile at 20-55 m, which scan matchers lock on to).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.rock_mesh import (
    SMALL_ROCK_M,
    SMALL_ROCK_REACH_M,
    rock_mesh,
)
from marsscene.terrain.heightfield import Heightfield

__all__ = ["TerrainCaster", "embree_available", "grid_mesh", "ray_heightfield"]

log = logging.getLogger("marsscene")

_CHUNK = 24
_GROW_M = 8.0  # the march step is one post out to 8 m, then grows linearly with range
_BISECT = 14  # bisection steps of the bracket (step / 2^14: sub-millimetre)
_MARGIN_M = 50.0


def embree_available() -> bool:
    try:
        import embreex  # noqa: F401
    except ImportError:
        return False
    return True


class TerrainCaster:
    """First hits of rays on a heightfield and, with Embree, on the scene's catalogue rocks
    (``rocks``: (N, 6) id, x, y, z of the base, diameter, height + burial in m, the rocks that
    are not MuJoCo geoms) and on ``static`` triangles (the MuJoCo world geoms,
    :func:`~marsscene.sensors.rock_mesh.static_geom_mesh`). Without ``embreex`` only the
    terrain is cast (numpy march).

    The Embree scene holds the terrain and the rocks of at least ``SMALL_ROCK_M`` within
    ``range + margin`` of its centre, and the smaller rocks within ``SMALL_ROCK_REACH_M +
    margin`` (so every one within ``SMALL_ROCK_REACH_M`` of the sensor)."""

    def __init__(self, hf: Heightfield, range_max_m: float, *,
                 rocks: NDArray[np.float64] | None = None,
                 static: tuple[NDArray[np.float32], NDArray[np.int32]] | None = None,
                 margin_m: float = _MARGIN_M, use_embree: bool | None = None):
        self.hf = hf
        self.half_m = float(range_max_m) + margin_m
        self.margin_m = margin_m
        self.embree = embree_available() if use_embree is None else use_embree
        self.rocks = rocks if rocks is not None else np.zeros((0, 6))
        big = self.rocks[:, 4] >= SMALL_ROCK_M
        self._big, self._small = self.rocks[big], self.rocks[~big]
        self.static = static if static is not None else (
            np.zeros((0, 3), dtype=np.float32), np.zeros((0, 3), dtype=np.int32))
        self._scene: Any = None
        self._centre = np.array([np.inf, np.inf])

    def _window(self, centre_xy: NDArray[np.float64]) -> None:
        hf, h = self.hf, self.half_m
        lo_r, lo_c = hf.rowcol_of(centre_xy[0] - h, centre_xy[1] - h)
        hi_r, hi_c = hf.rowcol_of(centre_xy[0] + h, centre_xy[1] + h)
        rows, cols = hf.shape
        r0, c0 = max(int(np.floor(lo_r)), 0), max(int(np.floor(lo_c)), 0)
        r1, c1 = min(int(np.ceil(hi_r)) + 1, rows), min(int(np.ceil(hi_c)) + 1, cols)
        self._centre = np.asarray(centre_xy, dtype=np.float64)
        self._scene = None
        if r1 - r0 < 2 or c1 - c0 < 2:
            return
        verts, faces = grid_mesh(hf, r0, r1, c0, c1, disc=(self._centre, h))
        big = _inside(self._big, centre_xy, h)
        small = _inside(self._small, centre_xy, SMALL_ROCK_REACH_M + self.margin_m)
        others = [rock_mesh(self._big[big], detailed=True),
                  rock_mesh(self._small[small], detailed=False), self.static]
        self._scene = _embree_scene([(verts, faces), *others])
        log.debug("lidar window %d x %d posts, %d rocks at (%.1f, %.1f)", r1 - r0, c1 - c0,
                  int(big.sum() + small.sum()), *centre_xy)

    def cast(self, origins: NDArray[np.float64], dirs: NDArray[np.float64],
             range_m: tuple[float, float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Distance to the terrain or a rock along unit rays (``inf``: no hit in range) and
        the surface normal at each hit (zeros where none).

        ``origins`` is (3,) for a common origin or (N, 3) per ray; ``dirs`` is (N, 3).
        """
        dirs = np.asarray(dirs, dtype=np.float64)
        if not self.embree:
            origins = np.broadcast_to(np.asarray(origins, dtype=np.float64), dirs.shape)
            return ray_heightfield(self.hf, origins, dirs, range_m)
        n = len(dirs)
        dist, normal = np.full(n, np.inf), np.zeros((n, 3))
        idx, t_m, n_hit = self.cast_hits(origins, dirs, range_m)
        dist[idx], normal[idx] = t_m, n_hit
        return dist, normal

    def cast_hits(self, origins: NDArray[np.floating[Any]], dirs: NDArray[np.floating[Any]],
                  range_m: tuple[float, float]
                  ) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]]:
        """Embree only: the rays that hit within ``range_m``, their distances and unit surface
        normals (:meth:`cast` without the full-size arrays; float32 input is used as is)."""
        d32 = np.ascontiguousarray(dirs, dtype=np.float32)
        o = np.asarray(origins, dtype=np.float32)
        n = len(d32)
        if n == 0:
            return np.zeros(0, np.intp), np.zeros(0), np.zeros((0, 3))
        ends = o.reshape(-1, 3)[[0, -1]].astype(np.float64)
        if not np.all(np.hypot(*(ends[:, :2] - self._centre).T) <= self.margin_m):
            self._window(ends[0, :2])
        if self._scene is None:
            return np.zeros(0, np.intp), np.zeros(0), np.zeros((0, 3))
        o32 = o if o.ndim == 2 else np.broadcast_to(o, d32.shape)  # embreex reads strides
        tfar = np.full(len(d32), np.float32(range_m[1] + 1.0), dtype=np.float32)
        res = self._scene.run(o32, d32, tfar, output=1)
        t_m = res["tfar"]  # a miss keeps its tfar, beyond the range
        hit = np.flatnonzero((t_m >= range_m[0]) & (t_m <= range_m[1]))
        ng = res["Ng"][hit].astype(np.float64)
        ng /= np.maximum(np.sqrt(np.einsum("ij,ij->i", ng, ng)), 1e-12)[:, None]
        return hit, t_m[hit].astype(np.float64), ng


def grid_mesh(hf: Heightfield, r0: int, r1: int, c0: int, c1: int, *,
              disc: tuple[NDArray[np.float64], float] | None = None
              ) -> tuple[NDArray[np.float32], NDArray[np.int32]]:
    """Posts ``[r0, r1) x [c0, c1)`` as two triangles per cell (float32 vertices); with
    ``disc`` (centre xy, radius in m) only the cells that reach into the disc, and the posts
    they use."""
    z = hf.z_m[r0:r1, c0:c1]
    n_r, n_c = z.shape
    x = hf.origin_xy_m[0] + (c0 + np.arange(n_c)) * hf.cell_size_m
    y = hf.origin_xy_m[1] + (r0 + np.arange(n_r)) * hf.cell_size_m
    verts = np.zeros((n_r, n_c, 3), dtype=np.float32)
    verts[..., 0], verts[..., 1], verts[..., 2] = x[None, :], y[:, None], z
    idx = np.arange(n_r * n_c, dtype=np.int32).reshape(n_r, n_c)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    if disc is None:
        faces = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3),
                                np.stack([a, d, c], -1).reshape(-1, 3)])
        return verts.reshape(-1, 3), faces
    (cx, cy), radius = disc
    gx = np.maximum(np.maximum(x[:-1] - cx, cx - x[1:]), 0.0)  # cell to centre, per axis
    gy = np.maximum(np.maximum(y[:-1] - cy, cy - y[1:]), 0.0)
    keep = gy[:, None] ** 2 + gx[None, :] ** 2 <= radius**2
    quads = np.stack([a[keep], b[keep], c[keep], d[keep]], -1)
    faces = np.concatenate([quads[:, [0, 1, 3]], quads[:, [0, 3, 2]]])
    used = np.zeros(n_r * n_c, dtype=bool)
    used[quads.ravel()] = True
    new = np.cumsum(used, dtype=np.int32) - 1
    return verts.reshape(-1, 3)[used], new[faces]


def _inside(rocks: NDArray[np.float64], centre_xy: NDArray[np.float64], radius_m: float
            ) -> NDArray[np.bool_]:
    """The rocks that may reach within ``radius_m`` of ``centre_xy`` (their centre within the
    radius plus their diameter: a jittered rock stays well inside one diameter)."""
    return np.asarray(np.hypot(rocks[:, 1] - centre_xy[0], rocks[:, 2] - centre_xy[1])
                      <= radius_m + rocks[:, 4])


def _embree_scene(meshes: list[tuple[NDArray[np.float32], NDArray[np.int32]]]) -> Any:
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    for verts, faces in meshes:
        if len(faces):
            TriangleMesh(scene, np.ascontiguousarray(verts, dtype=np.float32),
                         np.ascontiguousarray(faces, dtype=np.int32))
    return scene


def _bisect(hf: Heightfield, o: NDArray[np.float64], d: NDArray[np.float64],
            ta: NDArray[np.float64], tb: NDArray[np.float64]) -> NDArray[np.float64]:
    """The crossing inside brackets ``[ta, tb]`` (above at ``ta``, below at ``tb``)."""
    for _ in range(_BISECT):
        tm = 0.5 * (ta + tb)
        p = o + d * tm[:, None]
        below = p[:, 2] <= hf.sample(p[:, 0], p[:, 1])
        tb = np.where(below, tm, tb)
        ta = np.where(below, ta, tm)
    return 0.5 * (ta + tb)


def ray_heightfield(
    hf: Heightfield,
    origin_m: NDArray[np.float64],
    dirs: NDArray[np.float64],
    range_m: tuple[float, float],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance to the bilinear terrain along unit rays (``inf`` where there is no hit in range).

    A vectorised march (one post per step out to 8 m, growing linearly beyond) brackets the
    first crossing; bisection refines it to below a millimetre. ``origin_m`` is (3,) or (N, 3).

    Returns
    -------
    dist_m : ndarray of shape (N,)
    normal : ndarray of shape (N, 3)
        Upward surface normal at the hit (zeros where there is no hit).
    """
    dirs = np.asarray(dirs, dtype=np.float64)
    n = len(dirs)
    origins = np.broadcast_to(np.asarray(origin_m, dtype=np.float64), (n, 3))
    dist = np.full(n, np.inf)
    normal = np.zeros((n, 3))
    if n == 0:
        return dist, normal
    step = hf.cell_size_m
    k = int(np.ceil(range_m[1] / hf.cell_size_m)) + 1
    (x0, y0, x1, y1), (rows, cols) = hf.bounds_xy_m, hf.shape
    r_lo, c_lo = hf.rowcol_of(origins[:, 0].min(), origins[:, 1].min())
    r_hi, c_hi = hf.rowcol_of(origins[:, 0].max(), origins[:, 1].max())
    win = hf.z_m[max(int(r_lo) - k, 0):min(int(r_hi) + k + 2, rows),
                 max(int(c_lo) - k, 0):min(int(c_hi) + k + 2, cols)]
    z_top = float(win.max()) if win.size else float(hf.z_m.max())
    t0 = float(range_m[0])
    p0 = origins + t0 * dirs
    f_prev = p0[:, 2] - hf.sample(p0[:, 0], p0[:, 1])
    active = np.flatnonzero(f_prev > 0)  # rays starting under the ground see nothing
    f_prev = f_prev[active]
    while len(active) and t0 < range_m[1]:
        h = step * max(1.0, t0 / _GROW_M)  # coarser far away (angular spacing grows too)
        ts = t0 + h * np.arange(1, _CHUNK + 1)
        ts = ts[ts <= range_m[1] + h]
        d, o = dirs[active], origins[active]
        p = o[:, None, :] + d[:, None, :] * ts[None, :, None]
        f = p[..., 2] - hf.sample(p[..., 0], p[..., 1])
        px, py = p[..., 0], p[..., 1]
        below = (f <= 0) & (px >= x0) & (px <= x1) & (py >= y0) & (py <= y1)
        hit = below.any(axis=1)
        kk = np.argmax(below, axis=1)
        rows_hit = np.flatnonzero(hit)
        if len(rows_hit):
            kh = kk[rows_hit]
            ids = active[rows_hit]
            tb = ts[kh]
            ta = np.where(kh > 0, ts[np.maximum(kh - 1, 0)], ts[0] - h)
            t_hit = _bisect(hf, origins[ids], dirs[ids], ta, tb)
            dist[ids] = t_hit
            q = origins[ids] + dirs[ids] * t_hit[:, None]
            normal[ids] = hf.normal(q[:, 0], q[:, 1])
        last = p[:, -1, :]
        outside = (last[:, 0] < x0) | (last[:, 0] > x1) | (last[:, 1] < y0) | (last[:, 1] > y1)
        above = (last[:, 2] > z_top) & (d[:, 2] >= 0)
        keep = ~hit & ~outside & ~above
        active, f_prev = active[keep], f[keep, -1]
        t0 = float(ts[-1])
    dist[dist > range_m[1]] = np.inf
    return dist, normal
