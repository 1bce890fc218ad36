"""Where rocks go: intensity maps (crater ejecta, rock-field masks) and point processes.

Positions are drawn from a piecewise-constant intensity on a *placement grid* (at most
``MAX_GRID_CELLS`` cells, never finer than the terrain posts), so a million rocks cost one
``searchsorted``. The ejecta weighting follows the architecture of synthterrain
(``rock/__init__.py: crater_probability_map``; NeoGeographyToolkit/synthterrain): rocky rims and
an ejecta blanket decaying as ``exp(-(r/R - 1) / 0.7)`` out to a few radii, a nearly rock-free
interior, faded with crater age by ``(1 - age / fade)^3``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.heightfield import Heightfield

if TYPE_CHECKING:
    from marsscene.craters.table import CraterTable

__all__ = [
    "MAX_GRID_CELLS",
    "PlacementGrid",
    "ejecta_profile",
    "ejecta_weight",
    "placement_grid",
    "point_in_polygon",
    "sample_cells",
    "thomas_offsets",
]

MAX_GRID_CELLS = 512 * 512
#: Relative rock density inside a crater's rim (fraction of the rim value; synthterrain uses 0.05).
INTERIOR_LEVEL = 0.05
#: Inner edge of the rocky rim band, in crater radii.
RIM_INNER_RADII = 0.8
#: e-folding distance of the ejecta blanket's rock density, in crater radii (synthterrain 0.7).
EJECTA_DECAY_RADII = 0.7


@dataclass(frozen=True, slots=True)
class PlacementGrid:
    """A regular grid of cells covering the terrain footprint (x east, y north; in m)."""

    x0_m: float
    y0_m: float
    dx_m: float
    dy_m: float
    nx: int
    ny: int

    @property
    def cell_area_m2(self) -> float:
        return self.dx_m * self.dy_m

    def centers(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Cell-centre coordinates, each of shape ``(ny * nx,)`` (row-major, row 0 south)."""
        xc = self.x0_m + (np.arange(self.nx) + 0.5) * self.dx_m
        yc = self.y0_m + (np.arange(self.ny) + 0.5) * self.dy_m
        xx, yy = np.meshgrid(xc, yc)
        return xx.ravel(), yy.ravel()


def placement_grid(hf: Heightfield, *, max_cells: int = MAX_GRID_CELLS) -> PlacementGrid:
    """The placement grid of a heightfield: cells >= one post, at most ``max_cells`` cells."""
    x0, y0, x1, y1 = hf.bounds_xy_m
    w, h = x1 - x0, y1 - y0
    cell = max(hf.cell_size_m, float(np.sqrt(w * h / max_cells)))
    nx = max(1, int(np.ceil(w / cell - 1e-9)))
    ny = max(1, int(np.ceil(h / cell - 1e-9)))
    while nx * ny > max_cells:
        cell *= 1.01
        nx = max(1, int(np.ceil(w / cell - 1e-9)))
        ny = max(1, int(np.ceil(h / cell - 1e-9)))
    return PlacementGrid(x0, y0, w / nx, h / ny, nx, ny)


def ejecta_profile(rho: NDArray[np.float64], *, extent_radii: float) -> NDArray[np.float64]:
    """Relative rock density at ``rho = r / R`` crater radii from a fresh crater's centre.

    1 on the rim band ``[0.8, 1]``, ``exp(-(rho - 1) / 0.7)`` on the ejecta blanket out to
    ``extent_radii``, 0.05 inside, 0 beyond.
    """
    rho = np.asarray(rho, dtype=np.float64)
    out = np.where(rho < RIM_INNER_RADII, INTERIOR_LEVEL, 1.0)
    blanket = rho > 1.0
    out = np.where(blanket, np.exp(-(rho - 1.0) / EJECTA_DECAY_RADII), out)
    return np.where(rho > extent_radii, 0.0, out)


def ejecta_weight(
    x_m: NDArray[np.float64],
    y_m: NDArray[np.float64],
    craters: CraterTable,
    *,
    extent_radii: float,
    fade_ga: float,
    min_radius_m: float = 0.0,
) -> NDArray[np.float64]:
    """Crater-ejecta rock enhancement at points, in ``[0, 1]`` (sum over craters, clipped).

    Parameters
    ----------
    x_m, y_m : ndarray of shape (P,)
        Points (in m).
    craters : CraterTable
    extent_radii : float
        Outer edge of the ejecta blanket (in crater radii).
    fade_ga : float
        Age at which a crater's enhancement has faded to 0 (in Ga).
    min_radius_m : float
        Craters smaller than this are ignored (below the grid resolution).

    Returns
    -------
    ndarray of shape (P,)
    """
    out = np.zeros(len(x_m))
    if len(craters) == 0 or len(x_m) == 0:
        return out
    radius = 0.5 * craters.diameter_m
    fade = np.clip(1.0 - craters.age_ga / fade_ga, 0.0, 1.0) ** 3
    keep = np.flatnonzero((radius >= min_radius_m) & (fade > 0) & (radius > 0))
    if keep.size == 0:
        return out
    from scipy.spatial import cKDTree  # imported on use: scipy.spatial is slow to import

    points = cKDTree(np.column_stack([x_m, y_m]))
    # group craters by power-of-two influence radius so each query uses a tight max distance
    reach = extent_radii * radius[keep]
    klass = np.floor(np.log2(reach)).astype(np.int64)
    for c in np.unique(klass):  # a handful of size classes, not a loop per crater
        idx = keep[klass == c]
        tree = cKDTree(craters.center_xy_m[idx])
        pairs = points.sparse_distance_matrix(
            tree, float(extent_radii * radius[idx].max()), output_type="ndarray"
        )
        if len(pairs) == 0:
            continue
        j = idx[pairs["j"]]
        val = ejecta_profile(pairs["v"] / radius[j], extent_radii=extent_radii) * fade[j]
        out += np.bincount(pairs["i"], weights=val, minlength=len(x_m))
    return np.minimum(out, 1.0)


def point_in_polygon(
    x_m: NDArray[np.float64], y_m: NDArray[np.float64], polygon_xy_m: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Even-odd point-in-polygon test, vectorised over points (loops over the few edges)."""
    poly = np.asarray(polygon_xy_m, dtype=np.float64)
    inside = np.zeros(len(x_m), dtype=bool)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        crosses = (a[1] > y_m) != (b[1] > y_m)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a[0] + (y_m - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        inside ^= crosses & (x_m < x_cross)
    return inside


def sample_cells(
    n: int,
    grid: PlacementGrid,
    cells: NDArray[np.int64],
    weights: NDArray[np.float64],
    *,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Draw ``n`` points from a piecewise-constant intensity over some cells of a grid.

    Parameters
    ----------
    n : int
    grid : PlacementGrid
    cells : ndarray of shape (C,), int
        Flat cell indices (row-major) that may receive points.
    weights : ndarray of shape (C,)
        Non-negative relative intensity of each cell.
    rng : numpy.random.Generator

    Returns
    -------
    x_m, y_m : ndarray of shape (n,)
    """
    cdf = np.cumsum(weights, dtype=np.float64)
    # sorted uniforms: points come out in row-major cell order (the set of points has the same
    # distribution), which makes the later terrain look-ups cache-friendly
    pick = np.searchsorted(cdf, np.sort(rng.random(n)) * cdf[-1], side="right")
    cell = cells[np.minimum(pick, len(cells) - 1)]
    row, col = np.divmod(cell, grid.nx)
    jitter = rng.random((2, n))
    x = grid.x0_m + (col + jitter[0]) * grid.dx_m
    y = grid.y0_m + (row + jitter[1]) * grid.dy_m
    return x, y


def thomas_offsets(
    n: int,
    parents_xy_m: NDArray[np.float64],
    *,
    sigma_m: float,
    bounds_xy_m: tuple[float, float, float, float],
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Thomas-process offspring: each of ``n`` points joins a random parent with a Gaussian
    offset (sd ``sigma_m``), mirrored back into the footprint at its edges.

    Assigning a Poisson number of points uniformly to ``P`` parents gives each parent an
    independent Poisson number of children (Poisson splitting), i.e. a Thomas process.
    """
    parent = rng.integers(0, len(parents_xy_m), size=n)
    off = rng.normal(0.0, sigma_m, size=(n, 2))
    x = parents_xy_m[parent, 0] + off[:, 0]
    y = parents_xy_m[parent, 1] + off[:, 1]
    x0, y0, x1, y1 = bounds_xy_m
    return _reflect(x, x0, x1), _reflect(y, y0, y1)


def _reflect(v: NDArray[np.float64], lo: float, hi: float) -> NDArray[np.float64]:
    span = hi - lo
    t = np.mod(v - lo, 2.0 * span)
    return lo + np.where(t > span, 2.0 * span - t, t)
