"""Rock shadows on the ground at a low sun, exact and soft: baked into the ground's sun layer.

MuJoCo's shadow map (+-20 m, 3072 texels a side, binary per pixel) stretches its texels by
1 / sin(elevation) along the ground: 15 cm steps at 5 deg, 37 cm at 2 deg, so a rock's long
shadow ends in blocks. Below :data:`BAKED_BELOW_DEG` the camera therefore bakes the rocks'
shadows into the ground's sun layer, as it does the terrain's
(:mod:`marsscene.sensors.camera_shadow`), and the rocks cast nothing into the map (the rover
still does).

Each rock is the ellipsoid the camera draws (its diameter and height above its buried base;
:mod:`marsscene.sensors.camera_rocks`; the drawn icosphere's vertices are jittered by about
22 %, so a shadow's outline follows the mean shape, not each facet). Per ray of a grid whose
rows run along the sun's azimuth (``step_m`` apart, across and along), the rocks' top surfaces
lifted by ``u tan(elevation)`` (``u`` along the ray, away from the sun) are rasterised and
their running maximum is taken (``np.maximum.accumulate``): the height a point must reach to
see the sun's centre over every rock upstream, and the distance to that rock. A receiver at
the rendered ground's height then gets the visible fraction of the sun's disc
(:func:`marsscene.terrain.horizon.sun_visibility`: a penumbra of 0.6 cm per metre to the rock).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import map_coordinates

from marsscene.terrain.horizon import NO_OCCLUDER_M, SUN_RADIUS_RAD, sun_visibility

__all__ = ["BAKED_BELOW_DEG", "rock_visibility"]

#: Below this sun elevation (deg) rock shadows are baked: the map's texels are then longer than
#: 6.3 cm along the sun, 4x the near ground's 1.6 cm shadow texels, and shadows longer than 4.7x
#: the rocks' heights. Above it (the default scene's 13 deg, the benchmarks' 30-50 deg) the map
#: draws them, as before.
BAKED_BELOW_DEG = 12.0
#: Longest rock shadow considered (m): a 2 m rock at 2 deg casts 57 m.
MAX_SHADOW_M = 80.0
_ROWS = 512


def rock_visibility(rocks: NDArray[np.float64], sun_direction_enu: Any, xy_m: NDArray[Any],
                    z_m: NDArray[Any], *, step_m: float,
                    sun_radius_rad: float = SUN_RADIUS_RAD) -> NDArray[np.float32]:
    """Visible fraction of the sun's disc over the rocks at ground points.

    Parameters
    ----------
    rocks : ndarray of shape (N, 6)
        Catalogue rows: id, x, y, z of the buried base, diameter, height + burial (m).
    sun_direction_enu : (3,) unit vector toward the sun (above the horizon)
    xy_m : ndarray of shape (..., 2)
        Receivers' x, y (m).
    z_m : ndarray of shape (...)
        Receivers' heights: the rendered ground's (m).
    step_m : float
        Grid spacing across and along the sun's azimuth (m): the shadows' outline resolution.
    sun_radius_rad : float

    Returns
    -------
    ndarray of shape (...), float32
        1 where no rock shades the point, down to 0 in a rock's umbra.
    """
    s = np.asarray(sun_direction_enu, dtype=np.float64)
    rho = float(math.hypot(s[0], s[1]))
    shape = np.shape(z_m)
    out = np.ones(shape, dtype=np.float32)
    if len(rocks) == 0 or s[2] <= 0.0 or rho < 1e-9:
        return out
    tan_e = float(s[2]) / rho
    e_u = -s[:2] / rho  # along the shadows, away from the sun
    e_v = np.array([-e_u[1], e_u[0]])
    p = np.asarray(xy_m, dtype=np.float64).reshape(-1, 2)
    z = np.asarray(z_m, dtype=np.float64).ravel()
    u_p, v_p = p @ e_u, p @ e_v
    reach = min((rocks[:, 5].max()) / tan_e, MAX_SHADOW_M)
    ru, rv = rocks[:, 1:3] @ e_u, rocks[:, 1:3] @ e_v
    half = rocks[:, 4] / 2.0
    keep = ((ru + half >= u_p.min() - reach) & (ru - half <= u_p.max())
            & (rv + half >= v_p.min()) & (rv - half <= v_p.max()))
    if not keep.any():
        return out
    rk, ru, rv, half = rocks[keep], ru[keep], rv[keep], half[keep]
    u0 = float(min(u_p.min() - reach, (ru - half).min())) - step_m
    v0 = float(v_p.min()) - step_m
    n_u = math.ceil(float(u_p.max() - u0) / step_m) + 3
    n_v = math.ceil(float(v_p.max() - v0) / step_m) + 3
    lift = _rasterise(rk, ru - u0, rv - v0, half, step_m, n_v, n_u, tan_e)
    top = np.empty_like(lift)
    occluder = np.empty_like(lift)
    j = np.arange(n_u, dtype=np.float32)
    for a in range(0, n_v, _ROWS):  # rays are independent: blocks of rows bound the memory
        blk = lift[a : a + _ROWS]
        run = np.maximum.accumulate(blk, axis=1)
        last = np.maximum.accumulate(np.where(blk >= run, j, -1.0), axis=1)
        top[a : a + _ROWS, 1:] = run[:, :-1]  # strictly upstream of each cell
        top[a : a + _ROWS, 0] = -np.inf
        occluder[a : a + _ROWS, 1:] = last[:, :-1]
        occluder[a : a + _ROWS, 0] = -1.0
    ju, iv = (u_p - u0) / step_m, (v_p - v0) / step_m
    # bilinear on the lifted surface where all four neighbours are finite, else nearest
    finite = np.where(np.isfinite(top), top, -1e9)
    h = map_coordinates(finite, [iv, ju], order=1, mode="nearest", output=np.float64)
    h_near = map_coordinates(top, [np.rint(iv), np.rint(ju)], order=0, mode="nearest")
    h = np.where(h < -1e8, h_near, h)
    occ = map_coordinates(occluder, [np.rint(iv), np.rint(ju)], order=0, mode="nearest")
    seen = np.isfinite(h) & (occ >= 0.0)
    depth = np.where(seen, h - (u_p - u0) * tan_e - z, -1.0)
    dist = np.where(seen, np.maximum((ju - occ) * step_m, step_m), NO_OCCLUDER_M)
    vis = sun_visibility(depth, dist, sun_radius_rad=sun_radius_rad, softness_m=0.25 * step_m
                         * tan_e)
    return vis.reshape(shape)


def _rasterise(rk: NDArray[np.float64], ru: NDArray[np.float64], rv: NDArray[np.float64],
               half: NDArray[np.float64], step_m: float, n_v: int, n_u: int, tan_e: float
               ) -> NDArray[np.float32]:
    """The rocks' top surfaces lifted by ``u tan(e)`` on the (v, u) grid (-inf elsewhere)."""
    lift = np.full((n_v, n_u), -np.inf, dtype=np.float32)
    cells = np.ceil(half / step_m).astype(np.int64) + 1  # half-width in cells
    width = 2 * cells + 1
    count = width * width
    rock = np.repeat(np.arange(len(rk)), count)
    first = np.repeat(np.cumsum(count) - count, count)
    k = np.arange(int(count.sum())) - first
    w = width[rock]
    cu = np.floor(ru / step_m).astype(np.int64)[rock] + k % w - cells[rock]
    cv = np.floor(rv / step_m).astype(np.int64)[rock] + k // w - cells[rock]
    du, dv = cu * step_m - ru[rock], cv * step_m - rv[rock]
    r2 = (du * du + dv * dv) / np.maximum(half[rock] ** 2, 1e-12)
    inside = (r2 < 1.0) & (cu >= 0) & (cu < n_u) & (cv >= 0) & (cv < n_v)
    rock, cu, cv, r2 = rock[inside], cu[inside], cv[inside], r2[inside]
    c = rk[rock, 5] / 2.0
    z_top = rk[rock, 3] + c + c * np.sqrt(1.0 - r2)
    np.maximum.at(lift.reshape(-1), cv * n_u + cu,
                  (z_top + cu * step_m * tan_e).astype(np.float32))
    return lift
