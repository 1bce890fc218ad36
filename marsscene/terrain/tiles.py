"""Focus tiles of a level-of-detail terrain, each a function of the world and its index alone.

The focus square (:class:`~marsscene.terrain.lod.FocusPlan`) is cut into square tiles of
``terrain.tile_m`` (snapped to whole coarse cells). A tile's fine surface is

    z = cubic(coarse) + detail(x, y) + craters, tapered to the coarse surface at the focus border

* ``cubic(coarse)``: Keys (1981) cubic convolution of the **coarse** posts (doi:10.1109/
  TASSP.1981.1163711; a = -1/2): local (4 x 4 posts), exact at the coarse posts, so the coarse
  grid carries every wavelength it resolves and the fine terrain agrees with it;
* ``detail``: :func:`marsscene.terrain.lattice.fractal_detail`, a pure function of position that
  continues the coarse spectrum below its Nyquist wavelength;
* ``craters``: the scene's one crater table stamped on the tile grown by a **halo** that holds
  the whole footprint of every crater reaching the tile (the stamp fits a plane to the old
  surface over each crater's box, so the halo makes a straddling crater's plane the same from
  both sides); the halo is cropped away.

A tile therefore does not depend on which other tiles are built: ``build_tile`` (in
:mod:`marsscene.pipeline.lod`) of one tile equals the same window of a full build. Neighbouring
tiles share their border posts; they agree to float precision except where a chain of
overlapping craters reaches past a halo (measured in the tests).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lattice import fractal_detail, octave_cells_m
from marsscene.terrain.lod import FocusPlan, reaches_box, taper_detail
from marsscene.terrain.synth import continued_detail_rms

__all__ = ["FocusTiling", "TileDetail", "cubic_upsample", "tile_terrain"]


@dataclass(frozen=True, slots=True)
class FocusTiling:
    """The focus square cut into ``count x count`` tiles of ``tile_cells`` coarse cells."""

    plan: FocusPlan
    tile_cells: int

    @classmethod
    def of(cls, plan: FocusPlan, tile_m: float) -> FocusTiling:
        return cls(plan, max(1, min(plan.cells, round(tile_m / plan.coarse_post_m))))

    @property
    def count(self) -> int:
        """Tiles per side."""
        return math.ceil(self.plan.cells / self.tile_cells)

    def cells(self, i: int) -> tuple[int, int]:
        """First and last coarse post of tile row / column ``i`` (focus-relative)."""
        a = i * self.tile_cells
        return a, min(a + self.tile_cells, self.plan.cells)

    def posts(self, i: int) -> slice:
        """Fine posts of tile row / column ``i`` in the focus grid (border posts shared)."""
        a, b = self.cells(i)
        k = self.plan.ratio
        return slice(a * k, b * k + 1)

    def bounds_xy_m(self, row: int, col: int) -> tuple[float, float, float, float]:
        x0, y0 = self.plan.bounds_xy_m[:2]
        pc = self.plan.coarse_post_m
        (r0, r1), (c0, c1) = self.cells(row), self.cells(col)
        return (x0 + c0 * pc, y0 + r0 * pc, x0 + c1 * pc, y0 + r1 * pc)


@dataclass(frozen=True, slots=True)
class TileDetail:
    """The sub-coarse-post detail model of a scene (global, so every tile uses the same)."""

    rms_m: float
    hurst: float
    key: int


def _keys_weights(k: int) -> NDArray[np.float64]:
    """(k, 4) Keys cubic-convolution weights of posts i-1 .. i+2 for the k phases t = p / k."""
    a = -0.5
    t = np.arange(k) / k

    def w(s: NDArray[np.float64]) -> NDArray[np.float64]:
        s = np.abs(s)
        inner = (a + 2) * s**3 - (a + 3) * s**2 + 1
        outer = a * s**3 - 5 * a * s**2 + 8 * a * s - 4 * a
        return np.where(s <= 1, inner, np.where(s < 2, outer, 0.0))

    return np.stack([w(1 + t), w(t), w(1 - t), w(2 - t)], axis=1)


def _upsample_rows(zc: NDArray[np.float64], k: int) -> NDArray[np.float64]:
    """Rows ``1 .. n+1`` of ``zc`` (one margin row before, one after) at ``k`` x density."""
    n = zc.shape[0] - 3
    w = _keys_weights(k)
    out = np.zeros((n * k + 1, *zc.shape[1:]))
    for p in range(k):  # one vectorised pass per phase
        out[p:n * k:k] = (w[p, 0] * zc[0:n] + w[p, 1] * zc[1:n + 1] + w[p, 2] * zc[2:n + 2]
                          + w[p, 3] * zc[3:n + 3])
    out[n * k] = zc[n + 1]
    return out


def cubic_upsample(zc: NDArray[Any], k: int) -> NDArray[np.float64]:
    """Keys cubic convolution of a coarse window with a one-post margin on each side (and a
    second one after), ``k`` fine posts per coarse cell; exact at the coarse posts."""
    z = _upsample_rows(np.asarray(zc, dtype=np.float64), k)
    return _upsample_rows(z.T, k).T


def _halo_m(craters: Any, bounds: tuple[float, float, float, float],
            ccfg: Any) -> tuple[float, float, float, float]:
    """Metres to grow the tile by on its west, south, east and north sides so that the whole
    footprint of every crater reaching the tile lies in the window."""
    if craters is None or len(craters) == 0:
        return (0.0, 0.0, 0.0, 0.0)
    reach = ccfg.ejecta_reach * craters.diameter_m / 2.0 / np.sqrt(ccfg.axis_ratio_min)
    hit = reaches_box(craters.center_xy_m, reach, bounds)
    if not hit.any():
        return (0.0, 0.0, 0.0, 0.0)
    cx, cy, r = craters.center_xy_m[hit, 0], craters.center_xy_m[hit, 1], reach[hit]
    x0, y0, x1, y1 = bounds
    past = [x0 - (cx - r), y0 - (cy - r), (cx + r) - x1, (cy + r) - y1]
    west, south, east, north = (max(float(v.max()), 0.0) for v in past)
    return west, south, east, north


def _base_range(origin_m: float, post_m: float, n: int, lo_m: float, hi_m: float
                ) -> tuple[int, int]:
    """Base posts covering [lo_m, hi_m] and two more on each side (the stamp's low-pass at the
    footprint edge), kept where the cubic has its margin posts."""
    i0 = int(np.floor((lo_m - origin_m) / post_m + 1e-9)) - 2
    i1 = int(np.ceil((hi_m - origin_m) / post_m - 1e-9)) + 2
    return max(i0, 1), min(i1, n - 2)


def tile_terrain(coarse: Heightfield, tiling: FocusTiling, row: int, col: int, *,
                 detail: TileDetail, craters: Any = None, ccfg: Any = None,
                 stamp: Callable[..., Heightfield] | None = None,
                 base: Heightfield | None = None) -> Heightfield:
    """The full-resolution surface of focus tile ``(row, col)`` (see the module docstring).

    ``base`` is the grid the tile is interpolated from (default ``coarse``; a DEM at its own
    posts when the outer level is coarser): its posts lie on the fine lattice, a whole number of
    fine posts apart. ``stamp`` stamps ``craters`` into a heightfield
    (:func:`marsscene.craters.stamp_craters`, passed in by the pipeline: terrain does not import
    the crater stage).
    """
    if craters is not None and len(craters) and stamp is None:
        raise ValueError("tile_terrain: craters given without a stamp function")
    plan, k = tiling.plan, tiling.plan.ratio
    pf = plan.fine_post_m
    base = base if base is not None else coarse
    pb, kb = base.cell_size_m, round(base.cell_size_m / pf)
    bounds = tiling.bounds_xy_m(row, col)
    west, south, east, north = _halo_m(craters, bounds, ccfg)
    (bx0, by0), (rows_b, cols_b) = base.origin_xy_m, base.shape
    ar0, ar1 = _base_range(by0, pb, rows_b, bounds[1] - south, bounds[3] + north)
    ac0, ac1 = _base_range(bx0, pb, cols_b, bounds[0] - west, bounds[2] + east)
    z = cubic_upsample(base.z_m[ar0 - 1:ar1 + 2, ac0 - 1:ac1 + 2], kb)
    x0, y0 = plan.bounds_xy_m[:2]
    fr0 = round((by0 + ar0 * pb - y0) / pf)  # focus-relative fine index of the window start
    fc0 = round((bx0 + ac0 * pb - x0) / pf)
    xs = np.asarray(x0 + (fc0 + np.arange(z.shape[1])) * pf, dtype=np.float64)
    ys = np.asarray(y0 + (fr0 + np.arange(z.shape[0])) * pf, dtype=np.float64)
    z += fractal_detail(xs, ys, cells_m=octave_cells_m(pb, pf), hurst=detail.hurst,
                        rms_m=detail.rms_m, key=detail.key)
    hf = Heightfield(z.astype(np.float32), pf, (float(xs[0]), float(ys[0])))
    if craters is not None and len(craters):
        assert stamp is not None
        hf = stamp(hf, craters, profile_kwargs=ccfg.profile_kwargs())
    # crop the halo away, then fade the detail to the coarse surface at the focus border
    (r0, r1), (c0, c1) = tiling.cells(row), tiling.cells(col)
    rs, cs = slice(r0 * k - fr0, r1 * k - fr0 + 1), slice(c0 * k - fc0, c1 * k - fc0 + 1)
    tile = Heightfield(hf.z_m[rs, cs], pf, (x0 + c0 * k * pf, y0 + r0 * k * pf))
    return taper_detail(tile, plan, origin_posts=(r0 * k, c0 * k))


def detail_rms_m(base: Heightfield, plan: FocusPlan, hurst: float) -> float:
    """RMS of the detail below the base grid's posts that continues its spectrum, measured on
    its posts over the focus square."""
    (bx0, by0), pb = base.origin_xy_m, base.cell_size_m
    x0, y0, x1, y1 = plan.bounds_xy_m
    c0, c1 = (round((v - bx0) / pb) for v in (x0, x1))
    r0, r1 = (round((v - by0) / pb) for v in (y0, y1))
    window = Heightfield(base.z_m[r0:r1 + 1, c0:c1 + 1], pb, (x0, y0))
    return continued_detail_rms(window, plan.fine_post_m, hurst)
