"""Terrain shadows toward the sun over a whole :class:`Heightfield` (pure numpy/scipy).

A renderer's shadow map covers tens of metres; at a low sun the terrain casts shadows from
hundreds. This module computes them once per heightfield and sun direction:

* the **shadow surface** ``h(x, y)``: the height a point above ``(x, y)`` must reach to see the
  sun's centre over the terrain. With ``u`` the distance along the sun's azimuth *away* from the
  sun and ``e`` the sun's elevation, ``h(u) = max_{u' < u} (z(u') + u' tan e) - u tan e``: a
  running maximum along each ray;
* it is computed on a grid rotated so that its rows are those rays (the terrain resampled
  bilinearly once, at the posts' spacing), where the running maximum is one
  ``np.maximum.accumulate`` per block of rows, then resampled back to the posts;
* :attr:`SunShadow.depth_m` is ``h - z`` at every post (> 0: shadowed, by that many metres) and
  :attr:`SunShadow.distance_m` the horizontal distance to the occluder that sets ``h``.

:func:`sun_visibility` turns depth and distance into the visible fraction of the sun's disc
(angular radius :data:`SUN_RADIUS_RAD`, 0.175 deg at Mars' mean distance of 1.524 AU): the
fraction of a uniform disc above a straight horizon, whose offset from the disc's centre is
``depth / distance`` (rad). The terrain beyond the heightfield's edge casts nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import map_coordinates

from marsscene.terrain.heightfield import Heightfield

__all__ = ["SUN_RADIUS_RAD", "SunShadow", "shadow_with_outer", "sun_shadow", "sun_visibility"]

#: Angular radius of the sun seen from Mars at its mean distance (0.533 deg / 2 / 1.524 AU).
SUN_RADIUS_RAD = math.radians(0.533 / 2.0 / 1.524)
#: Depths are stored clipped to +-this (m); beyond it a point is fully lit or fully shadowed.
DEPTH_CLIP_M = 100.0
#: ``distance_m`` where nothing along the ray toward the sun rises above it (m).
NO_OCCLUDER_M = 1.0e6
#: Smallest penumbra half-height (m): the posts' interpolation error, so that edges cast by an
#: occluder a few posts away are not aliased to one texel.
EDGE_SOFTNESS_M = 0.01
_ROW_BLOCK = 256


def sun_visibility(depth_m: ArrayLike, distance_m: ArrayLike, *,
                   sun_radius_rad: float = SUN_RADIUS_RAD,
                   softness_m: float = EDGE_SOFTNESS_M) -> NDArray[np.float32]:
    """Visible fraction of the sun's disc (0..1) at shadow depth and occluder distance (m).

    The occluding horizon is a straight edge ``depth / distance`` (rad) above the disc's centre
    (its height offset widened by ``softness_m``, for sampling); the visible part is the
    circular segment above that edge, ``(acos(t) - t sqrt(1 - t^2)) / pi``, with ``t`` the
    edge's offset in disc radii (-1: all visible, +1: none).
    """
    d = np.asarray(depth_m, dtype=np.float32)
    dist = np.asarray(distance_m, dtype=np.float32)
    half = dist * np.float32(math.tan(sun_radius_rad))
    t = np.clip(d / (half + np.float32(softness_m)), -1.0, 1.0)
    out = (np.arccos(t) - t * np.sqrt(1.0 - t * t)) * np.float32(1.0 / math.pi)
    return np.where(dist >= NO_OCCLUDER_M, np.float32(1.0), out).astype(np.float32)


@dataclass(frozen=True, eq=False)
class SunShadow:
    """Terrain shadows of one heightfield for one sun direction (see the module doc).

    Parameters
    ----------
    heightfield : Heightfield
    sun_direction_enu : tuple of float
        Unit vector toward the sun (x east, y north, z up).
    depth_m : ndarray of shape (rows, cols), float32
        Height of the shadow surface above each post (in m; > 0 shadowed), clipped to
        +-``DEPTH_CLIP_M``.
    distance_m : ndarray of shape (rows, cols), float32
        Horizontal distance from each post to the occluder that sets the shadow surface (in m;
        ``NO_OCCLUDER_M`` where none).
    sun_radius_rad : float
        Angular radius of the sun's disc (rad), for the penumbra.
    """

    heightfield: Heightfield
    sun_direction_enu: tuple[float, float, float]
    depth_m: NDArray[np.float32]
    distance_m: NDArray[np.float32]
    sun_radius_rad: float = SUN_RADIUS_RAD

    def visibility(self) -> NDArray[np.float32]:
        """Visible fraction of the sun's disc at every post, shape ``(rows, cols)``."""
        return sun_visibility(self.depth_m, self.distance_m, sun_radius_rad=self.sun_radius_rad)

    def visibility_at(self, x: ArrayLike, y: ArrayLike, z: ArrayLike) -> NDArray[np.float32]:
        """Visible fraction of the sun's disc at world points (x, y, z in m), e.g. on rocks.

        The shadow surface is interpolated bilinearly between posts; points outside the
        footprint take the nearest edge's values.
        """
        hf = self.heightfield
        r, c = hf.rowcol_of(x, y)
        coords = np.stack([np.asarray(r, dtype=np.float64).ravel(),
                           np.asarray(c, dtype=np.float64).ravel()])
        depth = map_coordinates(self.depth_m, coords, order=1, mode="nearest")
        dist = map_coordinates(self.distance_m, coords, order=0, mode="nearest")
        above = np.asarray(z, dtype=np.float64).ravel() - hf.sample(x, y).ravel()
        vis = sun_visibility(depth - above, dist, sun_radius_rad=self.sun_radius_rad)
        return vis.reshape(np.shape(np.asarray(x)))


def sun_shadow(hf: Heightfield, sun_direction_enu: tuple[float, float, float], *,
               sun_radius_rad: float = SUN_RADIUS_RAD) -> SunShadow:
    """Shadow depth and occluder distance at every post of ``hf`` for a sun direction.

    Cost: two bilinear resamplings of the grid and one running maximum per rotated row
    (about 0.5 s for 2 M posts on one core); memory about 40 bytes per post, in blocks.
    """
    s = np.asarray(sun_direction_enu, dtype=np.float64)
    s = s / max(float(np.linalg.norm(s)), 1e-12)
    rows, cols = hf.shape
    rho = float(math.hypot(s[0], s[1]))
    sun = (float(s[0]), float(s[1]), float(s[2]))
    if rho < 1e-9:  # sun at the zenith (or nadir): no cast shadows
        depth = np.full((rows, cols), -DEPTH_CLIP_M if s[2] > 0 else DEPTH_CLIP_M, np.float32)
        return SunShadow(hf, sun, depth, np.full((rows, cols), NO_OCCLUDER_M, np.float32),
                         sun_radius_rad)
    tan_e = float(s[2]) / rho
    e_u = np.array([-s[0], -s[1]]) / rho  # along the rays, away from the sun
    e_v = np.array([-e_u[1], e_u[0]])
    step = hf.cell_size_m
    x0, y0, x1, y1 = hf.bounds_xy_m
    corners = np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]])
    u_min, v_min = float((corners @ e_u).min()), float((corners @ e_v).min())
    n_u = math.ceil((float((corners @ e_u).max()) - u_min) / step) + 2
    n_v = math.ceil((float((corners @ e_v).max()) - v_min) / step) + 2
    floor_m = float(hf.z_m.min()) - DEPTH_CLIP_M
    surface = np.zeros((n_v, n_u), dtype=np.float32)
    occluder = np.zeros((n_v, n_u), dtype=np.float32)
    j = np.arange(n_u, dtype=np.float64)
    for a in range(0, n_v, _ROW_BLOCK):
        v = v_min + np.arange(a, min(a + _ROW_BLOCK, n_v), dtype=np.float64)[:, None] * step
        u = u_min + j[None, :] * step
        r, c = hf.rowcol_of(u * e_u[0] + v * e_v[0], u * e_u[1] + v * e_v[1])
        inside = (r >= -1e-6) & (r <= rows - 1 + 1e-6) & (c >= -1e-6) & (c <= cols - 1 + 1e-6)
        z = map_coordinates(hf.z_m, [r, c], order=1, mode="nearest", output=np.float64)
        lift = np.where(inside, z + j * (tan_e * step), -np.inf)
        top = np.maximum.accumulate(lift, axis=1)
        h = np.full(lift.shape, -np.inf)
        h[:, 1:] = top[:, :-1] - j[1:] * (tan_e * step)
        last = np.maximum.accumulate(np.where(lift >= top, j, 0.0), axis=1)
        dist = np.full(lift.shape, NO_OCCLUDER_M)
        dist[:, 1:] = (j[1:] - last[:, :-1]) * step
        none = ~np.isfinite(h)
        surface[a : a + len(v)] = np.where(none, floor_m, h)
        occluder[a : a + len(v)] = np.where(none, NO_OCCLUDER_M, dist)
    depth = np.zeros((rows, cols), dtype=np.float32)
    distance = np.zeros((rows, cols), dtype=np.float32)
    xs, ys = hf.grid_xy()
    for a in range(0, rows, _ROW_BLOCK):
        yy = ys[a : a + _ROW_BLOCK, None]
        ju = ((xs[None, :] * e_u[0] + yy * e_u[1]) - u_min) / step
        iv = ((xs[None, :] * e_v[0] + yy * e_v[1]) - v_min) / step
        h_back = map_coordinates(surface, [iv, ju], order=1, mode="nearest", output=np.float64)
        z_post = hf.z_m[a : a + _ROW_BLOCK].astype(np.float64)
        depth[a : a + len(yy)] = np.clip(h_back - z_post, -DEPTH_CLIP_M, DEPTH_CLIP_M)
        distance[a : a + len(yy)] = map_coordinates(occluder, [iv, ju], order=0, mode="nearest")
    return SunShadow(hf, sun, depth, distance, sun_radius_rad)


def shadow_with_outer(focus: SunShadow, outer: SunShadow) -> SunShadow:
    """``focus``'s shadows with those the coarse outer terrain of a level-of-detail scene
    casts into it (e.g. canyon walls beyond the focus square at a low sun).

    The outer terrain's shadow surface (height above which a point sees the sun's centre over
    the outer terrain, bilinear between its posts) is compared with the focus's at every focus
    post; the higher one sets the depth and the occluder distance. Both must be computed for
    the same sun direction. Focus posts inside the outer grid's lowered focus square see the
    outer terrain around it only.
    """
    if not np.allclose(focus.sun_direction_enu, outer.sun_direction_enu):
        raise ValueError("focus and outer shadows are for different sun directions")
    hf, ohf = focus.heightfield, outer.heightfield
    depth = focus.depth_m.copy()
    distance = focus.distance_m.copy()
    xs, ys = hf.grid_xy()
    for a in range(0, hf.shape[0], _ROW_BLOCK):
        yy = np.broadcast_to(ys[a : a + _ROW_BLOCK, None], (min(_ROW_BLOCK, len(ys) - a),
                                                           len(xs)))
        xx = np.broadcast_to(xs[None, :], yy.shape)
        r, c = ohf.rowcol_of(xx, yy)
        z_outer = map_coordinates(ohf.z_m, [r, c], order=1, mode="nearest", output=np.float64)
        h_outer = z_outer + map_coordinates(outer.depth_m, [r, c], order=1, mode="nearest",
                                            output=np.float64)
        z = hf.z_m[a : a + len(yy)].astype(np.float64)
        higher = h_outer > z + depth[a : a + len(yy)]
        d_outer = np.clip(h_outer - z, -DEPTH_CLIP_M, DEPTH_CLIP_M)
        depth[a : a + len(yy)] = np.where(higher, d_outer, depth[a : a + len(yy)])
        near = map_coordinates(outer.distance_m, [r, c], order=0, mode="nearest")
        distance[a : a + len(yy)] = np.where(higher, near, distance[a : a + len(yy)])
    return SunShadow(hf, focus.sun_direction_enu, depth, distance, focus.sun_radius_rad)
