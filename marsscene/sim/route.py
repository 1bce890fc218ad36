"""Routes: author a smooth, arc-length-resampled path from waypoints that avoids steep slopes
and large rocks, and convert routes to and from TUM trajectories.

Blocked cells (slope above ``max_slope_deg`` or within ``clearance_m`` of an obstacle taller
than ``max_obstacle_height_m``) are marked on a planning grid; a straight leg that crosses one is
replaced by the shortest 8-connected path through free cells (Dijkstra,
``scipy.sparse.csgraph``). The polyline is then smoothed with a Gaussian along its arc length and
resampled every ``spacing_m``.
"""

from __future__ import annotations

import itertools
import logging
import math
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse
from scipy.ndimage import (
    binary_dilation,
    distance_transform_edt,
    gaussian_filter1d,
    label,
    maximum_filter,
)
from scipy.sparse.csgraph import dijkstra

from marsscene._validate import check_range
from marsscene.errors import ConfigError, MarsSceneWarning, RuntimeSimError
from marsscene.runs.tum import Trajectory
from marsscene.terrain.heightfield import Heightfield

log = logging.getLogger("marsscene")

__all__ = [
    "MAX_SLOPE_DEG",
    "Obstacles",
    "Route",
    "RouteWarning",
    "author_route",
    "check_waypoints",
    "resample_xy",
    "traversable_grid",
]

_MAX_NODES = 250_000
#: Route authoring's default slope limit in degrees (``DriveOptions.max_slope_deg``, the
#: benchmarks' routes and the navigation task read it from here).
MAX_SLOPE_DEG = 20.0


class RouteWarning(MarsSceneWarning):
    """The authored route still touches a blocked cell (after smoothing)."""


@dataclass(frozen=True)
class Obstacles:
    """Obstacles as discs: centre (N, 2) in m, radius (N,) in m, exposed height (N,) in m."""

    xy_m: NDArray[np.float64]
    radius_m: NDArray[np.float64]
    height_m: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Route:
    """A path as points about ``spacing`` m apart: ``xy_m`` (N, 2), cumulative arc length
    ``s_m``."""

    xy_m: NDArray[np.float64]

    @property
    def s_m(self) -> NDArray[np.float64]:
        seg = np.linalg.norm(np.diff(self.xy_m, axis=0), axis=1)
        return np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def length_m(self) -> float:
        return float(self.s_m[-1])

    def to_trajectory(
        self, hf: Heightfield, *, speed_m_s: float = 0.5, height_m: float = 0.0
    ) -> Trajectory:
        """Route as TUM poses: stamps at ``speed_m_s``, z on the terrain (+height), yaw along it."""
        xy = self.xy_m
        d = np.gradient(xy, axis=0)
        yaw = np.arctan2(d[:, 1], d[:, 0])
        z = hf.sample(xy[:, 0], xy[:, 1]) + height_m
        q = np.column_stack([np.zeros((len(xy), 2)), np.sin(yaw / 2), np.cos(yaw / 2)])
        return Trajectory(self.s_m / speed_m_s, np.column_stack([xy, z]), q)

    @classmethod
    def from_trajectory(cls, traj: Trajectory) -> Route:
        return cls(traj.xyz_m[:, :2].copy())


def check_waypoints(value: object, key: str = "waypoints") -> NDArray[np.float64]:
    """Waypoints as an array (K, 2) in m: at least two finite ``[x, y]`` pairs of numbers, or
    a one-line :class:`ConfigError` naming ``key``.

    Examples
    --------
    >>> check_waypoints([[0, 0], [5, 2]]).shape
    (2, 2)
    >>> try:
    ...     check_waypoints([[0, 0]], "drive.waypoints")
    ... except ConfigError as err:
    ...     print(err)
    drive.waypoints = [[0, 0]]; need at least 2 [x, y] pairs in m
    """
    def number(v: object) -> bool:
        return isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool)

    pairs = list(value) if isinstance(value, list | tuple | np.ndarray) else []
    ok = len(pairs) >= 2 and all(
        isinstance(p, list | tuple | np.ndarray) and len(p) == 2 and all(map(number, p))
        for p in pairs)
    wp = np.asarray(pairs, dtype=np.float64) if ok else np.zeros((0, 2))
    if not ok or not np.isfinite(wp).all():
        shown = [list(p) if isinstance(p, tuple) else p for p in pairs] if pairs else value
        raise ConfigError(f"{key} = {shown!r}; need at least 2 [x, y] pairs in m")
    return wp


def resample_xy(xy: ArrayLike, spacing_m: float) -> NDArray[np.float64]:
    """Resample a polyline (N, 2) at equal arc-length steps (last point kept)."""
    p = np.asarray(xy, dtype=np.float64)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9])
    p = p[keep]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    if s[-1] == 0.0:
        return p[:1].copy()
    n = max(math.ceil(s[-1] / spacing_m), 1)
    t = np.linspace(0.0, s[-1], n + 1)
    return np.column_stack([np.interp(t, s, p[:, 0]), np.interp(t, s, p[:, 1])])


def _blocked_grid(
    hf: Heightfield,
    cell_m: float,
    max_slope_deg: float,
    obstacles: Obstacles | None,
    max_h: float,
    clearance_m: float,
    inflation_m: float,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], float, tuple[float, float]]:
    step = max(1, round(cell_m / hf.cell_size_m))
    slope = maximum_filter(hf.slope_deg(), size=step)[::step, ::step]
    blocked = slope > max_slope_deg
    rows, cols = blocked.shape
    cell = hf.cell_size_m * step
    if inflation_m > 0:
        k = math.ceil(inflation_m / cell)
        yy, xx = np.mgrid[-k : k + 1, -k : k + 1]
        steep = blocked
        blocked = binary_dilation(blocked, structure=(xx**2 + yy**2) <= k * k)
    else:
        steep = blocked.copy()
    ox, oy = hf.origin_xy_m
    if obstacles is not None and len(obstacles.radius_m):
        big = obstacles.height_m > max_h
        xs = ox + np.arange(cols) * cell
        ys = oy + np.arange(rows) * cell
        for (cx, cy), r in zip(obstacles.xy_m[big], obstacles.radius_m[big], strict=True):
            rr = r + clearance_m  # loop over the few tall obstacles only
            c0, c1 = np.searchsorted(xs, [cx - rr - 1, cx + rr + 1])
            r0, r1 = np.searchsorted(ys, [cy - rr - 1, cy + rr + 1])
            gx, gy = np.meshgrid(xs[c0:c1], ys[r0:r1])
            d2 = (gx - cx) ** 2 + (gy - cy) ** 2
            blocked[r0:r1, c0:c1] |= d2 <= (rr + 0.5 * cell + 0.25) ** 2  # planning margin
            steep[r0:r1, c0:c1] |= d2 <= rr * rr
    return blocked, steep, cell, (ox, oy)


def _grid_path(
    blocked: NDArray[np.bool_], start: tuple[int, int], goal: tuple[int, int]
) -> NDArray[np.int64] | None:
    rows, cols = blocked.shape
    idx = np.arange(rows * cols).reshape(rows, cols)
    free = ~blocked
    src, dst, w = [], [], []
    for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
        r0, r1 = max(0, -dr), rows - max(0, dr)
        c0, c1 = max(0, -dc), cols - max(0, dc)
        a = idx[r0:r1, c0:c1]
        b = idx[r0 + dr : r1 + dr, c0 + dc : c1 + dc]
        ok = free[r0:r1, c0:c1] & free[r0 + dr : r1 + dr, c0 + dc : c1 + dc]
        src.append(a[ok])
        dst.append(b[ok])
        w.append(np.full(int(ok.sum()), math.hypot(dr, dc)))
    g = sparse.coo_matrix(
        (np.concatenate(w), (np.concatenate(src), np.concatenate(dst))),
        shape=(rows * cols, rows * cols),
    ).tocsr()
    s, t = idx[start], idx[goal]
    dist, pred = dijkstra(g, directed=False, indices=s, return_predecessors=True)
    if not np.isfinite(dist[t]):
        return None
    path = [t]
    while path[-1] != s:  # walks the path's own nodes, not the grid
        path.append(pred[path[-1]])
    nodes = np.array(path[::-1])
    return np.column_stack([nodes // cols, nodes % cols])


def _clear(blocked: NDArray[np.bool_], a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
    n = int(np.ceil(2 * np.abs(b - a).max())) + 2
    t = np.linspace(0.0, 1.0, n)[:, None]
    rc = np.round(a + t * (b - a)).astype(int)
    return not blocked[rc[:, 0], rc[:, 1]].any()


def _inside(rc: tuple[int, int], shape: tuple[int, ...]) -> tuple[int, int]:
    return min(max(rc[0], 0), shape[0] - 1), min(max(rc[1], 0), shape[1] - 1)


def _escape(grid: NDArray[np.bool_], start: tuple[int, int],
            nearest_free: NDArray[np.intp]) -> bool:
    """Open the straight cells from ``start`` to the nearest free cell of ``grid`` (in place):
    a waypoint inside an obstacle's clearance or an inflated steep patch leaves it by the
    shortest way. True if something was opened."""
    r, c = start
    tr, tc = int(nearest_free[0][r, c]), int(nearest_free[1][r, c])
    if (tr, tc) == (r, c):
        return False
    n = max(abs(tr - r), abs(tc - c)) + 1
    grid[np.rint(np.linspace(r, tr, n)).astype(int), np.rint(np.linspace(c, tc, n)).astype(int)] \
        = False
    return True


def _shortcut(blocked: NDArray[np.bool_], nodes: NDArray[np.int64]) -> NDArray[np.int64]:
    """Line-of-sight string pulling of a grid path (removes 8-connected zig-zags)."""
    p = nodes.astype(np.float64)
    keep = [0]
    i = 0
    while i < len(p) - 1:  # loops over the path's own nodes only
        j = len(p) - 1
        while j > i + 1 and not _clear(blocked, p[i], p[j]):
            j -= 1
        keep.append(j)
        i = j
    return nodes[keep]


def traversable_grid(
    hf: Heightfield,
    *,
    cell_m: float = 0.5,
    max_slope_deg: float = MAX_SLOPE_DEG,
    obstacles: Obstacles | None = None,
    max_obstacle_height_m: float = 0.3,
    clearance_m: float = 1.5,
    inflation_m: float = 1.25,
) -> tuple[NDArray[np.bool_], float, tuple[float, float]]:
    """Where :func:`author_route` may plan: ``(free (rows, cols), cell_m, origin_xy_m)``.

    A cell is free when no slope above ``max_slope_deg`` lies within ``inflation_m`` and no
    obstacle taller than ``max_obstacle_height_m`` within ``clearance_m`` of its edge (the
    route planner's own rule); cell ``(i, j)`` is centred at ``origin + (j, i) * cell_m``. Two
    points are joined by a route exactly when they lie in one 8-connected component of free
    cells.
    """
    plan, _, cell, origin = _blocked_grid(hf, cell_m, max_slope_deg, obstacles,
                                          max_obstacle_height_m, clearance_m, inflation_m)
    return ~plan, cell, origin


def author_route(
    waypoints_xy_m: ArrayLike,
    hf: Heightfield,
    *,
    spacing_m: float = 0.1,
    smooth_m: float = 1.0,
    max_slope_deg: float = MAX_SLOPE_DEG,
    obstacles: Obstacles | None = None,
    max_obstacle_height_m: float = 0.3,
    clearance_m: float = 1.5,
    inflation_m: float = 1.25,
    margin_m: float = 2.0,
) -> Route:
    """Author a drivable route through waypoints.

    Parameters
    ----------
    waypoints_xy_m : array of shape (K, 2)
        Points to visit in order (in m, scene frame). Must lie ``margin_m`` inside the terrain.
    hf : Heightfield
        The scene terrain (e.g. ``RoverSim.heightfield``).
    spacing_m : float
        Arc-length step of the result (in m).
    smooth_m : float
        Gaussian smoothing length along the path (in m); rounds corners.
    max_slope_deg, obstacles, max_obstacle_height_m, clearance_m
        What to avoid (slopes over the limit; obstacles taller than the limit, kept
        ``clearance_m`` away from their edge).
    inflation_m : float
        Planned paths keep this distance from steep cells (about the rover's half width), so
        the wheels, not just the centre line, stay on gentle ground.

    Returns
    -------
    Route
    """
    check_range("spacing_m", spacing_m, 0.01, 10.0)
    check_range("smooth_m", smooth_m, 0.0, 100.0)
    check_range("max_slope_deg", max_slope_deg, 0.0, 90.0, lo_open=True)
    wp = check_waypoints(waypoints_xy_m)
    x0, y0, x1, y1 = hf.bounds_xy_m
    bad = ~(
        (wp[:, 0] >= x0 + margin_m)
        & (wp[:, 0] <= x1 - margin_m)
        & (wp[:, 1] >= y0 + margin_m)
        & (wp[:, 1] <= y1 - margin_m)
    )
    if bad.any():
        i = int(np.argmax(bad))
        raise RuntimeSimError(
            f"waypoint {i} at ({wp[i, 0]:.2f}, {wp[i, 1]:.2f}) m is outside the terrain "
            f"x [{x0 + margin_m:.2f}, {x1 - margin_m:.2f}], y [{y0 + margin_m:.2f}, "
            f"{y1 - margin_m:.2f}] m (footprint minus a {margin_m} m margin)"
        )
    cell_m = max(hf.cell_size_m, math.sqrt(hf.area_m2 / _MAX_NODES), 0.25)
    plan, blocked, cell, (ox, oy) = _blocked_grid(
        hf, cell_m, max_slope_deg, obstacles, max_obstacle_height_m, clearance_m, inflation_m
    )
    rc = lambda p: (round((p[1] - oy) / cell), round((p[0] - ox) / cell))  # noqa: E731
    nearest_free = distance_transform_edt(plan, return_distances=False, return_indices=True)
    parts, n_parts = label(~plan, structure=np.ones((3, 3), dtype=bool))
    # a waypoint in a pocket of free ground walled in by rocks or slopes leaves it for the
    # largest connected free area (the nearest free cell alone may be in that pocket)
    main = parts == int(np.argmax(np.bincount(parts.ravel())[1:])) + 1 if n_parts > 1 else ~plan
    nearest_main = distance_transform_edt(~main, return_distances=False, return_indices=True)
    escaped = np.zeros_like(plan)  # cells opened to leave a blocked waypoint
    pieces = [wp[:1]]
    for a, b in itertools.pairwise(wp):
        leg = resample_xy(np.vstack([a, b]), cell / 2)
        r = np.clip(np.round((leg[:, 1] - oy) / cell).astype(int), 0, blocked.shape[0] - 1)
        c = np.clip(np.round((leg[:, 0] - ox) / cell).astype(int), 0, blocked.shape[1] - 1)
        if not plan[r, c].any():
            pieces.append(leg[1:])
            continue
        grid = plan.copy()
        ra, rb = _inside(rc(a), plan.shape), _inside(rc(b), plan.shape)
        apart = parts[ra] == 0 or parts[ra] != parts[rb]  # not one free area: meet in the main
        for end in (a, b):
            if _escape(grid, _inside(rc(end), plan.shape), nearest_main if apart else nearest_free):
                log.info("route: waypoint (%.1f, %.1f) m lies in a blocked area; the route "
                         "leaves it by the shortest way", end[0], end[1])
        escaped |= plan & ~grid
        nodes = _grid_path(grid, rc(a), rc(b))
        if nodes is not None:
            nodes = _shortcut(grid, nodes)
        if nodes is None:
            raise RuntimeSimError(
                f"no route from ({a[0]:.1f}, {a[1]:.1f}) to ({b[0]:.1f}, {b[1]:.1f}) m avoids "
                f"slopes > {max_slope_deg} deg and rocks > {max_obstacle_height_m} m"
            )
        pts = np.column_stack([ox + nodes[:, 1] * cell, oy + nodes[:, 0] * cell])
        pts[0], pts[-1] = a, b
        pieces.append(resample_xy(pts, cell / 2)[1:])
    dense = resample_xy(np.vstack(pieces), min(spacing_m, 0.05))
    if smooth_m > 0 and len(dense) > 3:
        sigma = smooth_m / 0.05
        pad = int(4 * sigma) + 1
        ext = np.vstack([np.repeat(dense[:1], pad, 0), dense, np.repeat(dense[-1:], pad, 0)])
        dense = gaussian_filter1d(ext, sigma, axis=0, mode="nearest")[pad:-pad]
        dense[0], dense[-1] = wp[0], wp[-1]
    xy = resample_xy(dense, spacing_m)
    r = np.clip(np.round((xy[:, 1] - oy) / cell).astype(int), 0, blocked.shape[0] - 1)
    c = np.clip(np.round((xy[:, 0] - ox) / cell).astype(int), 0, blocked.shape[1] - 1)
    if escaped.any():  # smoothing may round the corner where the escape meets the detour
        escaped = binary_dilation(escaped, iterations=max(1, math.ceil(smooth_m / cell)))
    touched = blocked[r, c] & ~escaped[r, c]
    if touched.any():
        warnings.warn(
            f"the smoothed route touches {int(touched.sum())} blocked cells; "
            "reduce smooth_m or add waypoints",
            RouteWarning,
            stacklevel=2,
        )
    return Route(xy)
