"""Authoring a soil map with the scene: the ``[soil]`` rules over the terrain's posts.

In order, each over the last: the ground's soil everywhere; drift patches where a seeded,
smooth random field (correlation length ``patch_m``) is in its top ``patch_fraction``; crater
floors (within ``crater_floor_fraction`` of each crater's radius, where wind-blown sand
collects in small Martian craters); slopes steeper than ``steep_deg``, where loose sand does
not rest (its angle of repose is about 30-35 deg), measured over :data:`SLOPE_SCALE_M`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import ndimage

from marsscene.rover.terramechanics import soil
from marsscene.soil.config import SoilConfig
from marsscene.soil.map import SoilMap
from marsscene.terrain.heightfield import Heightfield

__all__ = ["author_soil_map"]

#: The length (m) over which slopes are measured for the ``steep`` rule (about a wheelbase).
SLOPE_SCALE_M = 2.0
#: Points of the patch field per correlation length (drawn coarse, then interpolated).
_FIELD_POINTS_PER_PATCH = 4


def _patches(shape: tuple[int, int], cell_m: float, patch_m: float, fraction: float,
             rng: np.random.Generator) -> np.ndarray:
    """A boolean mask covering ``fraction`` of the grid in smooth seeded patches."""
    step = max(1, round(patch_m / _FIELD_POINTS_PER_PATCH / cell_m))
    coarse = (shape[0] // step + 2, shape[1] // step + 2)
    field = ndimage.gaussian_filter(rng.standard_normal(coarse), _FIELD_POINTS_PER_PATCH / 2,
                                    mode="wrap")
    rows = np.arange(shape[0]) / step
    cols = np.arange(shape[1]) / step
    fine = ndimage.map_coordinates(field, np.meshgrid(rows, cols, indexing="ij"), order=1)
    return fine > np.quantile(fine, 1.0 - fraction)


def _crater_floors(hf: Heightfield, craters: Any, fraction: float) -> np.ndarray:
    mask = np.zeros(hf.shape, bool)
    if craters is None or fraction <= 0 or not len(craters.diameter_m):
        return mask
    x0, y0 = hf.origin_xy_m
    cell = hf.cell_size_m
    for (cx, cy), d in zip(craters.center_xy_m, craters.diameter_m, strict=True):
        r = fraction * d / 2
        c0, c1 = max(0, int((cx - r - x0) / cell)), min(hf.shape[1], int((cx + r - x0) / cell) + 2)
        r0, r1 = max(0, int((cy - r - y0) / cell)), min(hf.shape[0], int((cy + r - y0) / cell) + 2)
        if c0 >= c1 or r0 >= r1:
            continue
        yy, xx = np.ogrid[r0:r1, c0:c1]
        mask[r0:r1, c0:c1] |= (x0 + xx * cell - cx) ** 2 + (y0 + yy * cell - cy) ** 2 <= r * r
    return mask


def _slope_deg(hf: Heightfield) -> np.ndarray:
    """Slope (deg) at each post over the wheel's scale: the terrain smoothed over
    :data:`SLOPE_SCALE_M` first (post-to-post slopes of sub-metre detail are no place for
    sand to slide off)."""
    cell = hf.cell_size_m
    z = ndimage.gaussian_filter(hf.z_m.astype(np.float64), SLOPE_SCALE_M / cell / 2,
                                mode="nearest")
    gy, gx = np.gradient(z, cell)
    return np.degrees(np.arctan(np.hypot(gx, gy)))


def author_soil_map(config: SoilConfig, hf: Heightfield, craters: Any,
                    rng: np.random.Generator) -> SoilMap:
    """The soil map of a terrain (``craters``: a crater table, or None) by ``config``'s
    rules; ``rng`` draws the patches."""
    names = config.names()
    of = {n: np.uint8(i) for i, n in enumerate(names)}
    index = np.full(hf.shape, of[config.ground], np.uint8)
    if config.patch_fraction > 0:
        index[_patches(hf.shape, hf.cell_size_m, config.patch_m, config.patch_fraction,
                       rng)] = of[config.patches]
    index[_crater_floors(hf, craters, config.crater_floor_fraction)] = of[config.crater_floor]
    index[_slope_deg(hf) > config.steep_deg] = of[config.steep]
    return SoilMap(tuple(soil(n) for n in names), index, hf.bounds_xy_m)
