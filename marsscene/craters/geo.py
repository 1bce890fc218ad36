"""Scene metres <-> planetocentric lon/lat by a local equirectangular approximation.

``x = R cos(lat0) (lon - lon0)``, ``y = R (lat - lat0)`` (angles in radians, ``R`` =
:data:`marsscene.units.MARS_RADIUS_M`) about the scene origin's ``(lon0, lat0)``. Over a few km
the error against the DEM's own projection is below ~1e-3 relative (it ignores the map
projection's scale variation), ample for crater catalogues and resurfacing polygons.

On a polar stereographic DEM the scene's +y is grid north, which differs from true north by the
grid convergence ``γ`` (:attr:`marsscene.terrain.GeoFrame.grid_convergence_deg`, the angle from
true north to grid +y): a scene direction of azimuth ``B`` has true azimuth ``B + γ``, so scene
``(x, y)`` are rotated to true ``(east, north)`` first.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.units import MARS_RADIUS_M

__all__ = ["lonlat_to_xy_m", "xy_to_lonlat_deg"]


def xy_to_lonlat_deg(
    x_m: ArrayLike,
    y_m: ArrayLike,
    *,
    origin_lonlat_deg: tuple[float, float],
    grid_convergence_deg: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Scene ``(x east, y north)`` (in m) to ``(lon east, lat)`` (in degrees)."""
    lon0, lat0 = origin_lonlat_deg
    xs = np.asarray(x_m, dtype=np.float64)
    ys = np.asarray(y_m, dtype=np.float64)
    g = np.radians(grid_convergence_deg)
    x = xs * np.cos(g) + ys * np.sin(g)  # true east
    y = -xs * np.sin(g) + ys * np.cos(g)  # true north
    lat = lat0 + np.degrees(y / MARS_RADIUS_M)
    lon = lon0 + np.degrees(x / (MARS_RADIUS_M * np.cos(np.radians(lat0))))
    return lon, lat


def lonlat_to_xy_m(
    lon_deg: ArrayLike,
    lat_deg: ArrayLike,
    *,
    origin_lonlat_deg: tuple[float, float],
    grid_convergence_deg: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(lon east, lat)`` (in degrees) to scene ``(x east, y north)`` (in m)."""
    lon0, lat0 = origin_lonlat_deg
    dlon = (np.asarray(lon_deg, dtype=np.float64) - lon0 + 180.0) % 360.0 - 180.0
    east = np.radians(dlon) * MARS_RADIUS_M * np.cos(np.radians(lat0))
    north = np.radians(np.asarray(lat_deg, dtype=np.float64) - lat0) * MARS_RADIUS_M
    g = np.radians(grid_convergence_deg)
    return east * np.cos(g) - north * np.sin(g), east * np.sin(g) + north * np.cos(g)
