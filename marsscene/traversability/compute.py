"""``compute``: the traversability layers of a terrain, its rocks and soil for a rover."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig
from marsscene.soil.map import SoilMap
from marsscene.terrain.heightfield import Heightfield
from marsscene.traversability.config import RoverFootprint, TraversabilityConfig
from marsscene.traversability.geometry import (
    belly_intrusion,
    fit_plane,
    plane_correlator,
    ring_kernel,
    step_height,
)
from marsscene.traversability.rocks import rasterise_rocks
from marsscene.traversability.slip import rigid_slip, soil_slip

__all__ = ["HAZARD_BITS", "LAYERS", "Traversability", "compute", "grid_stride"]

#: The hazard mask's reasons, one bit each (``Traversability.hazard_bits``).
HAZARD_BITS = {"slope": 1, "roughness": 2, "step": 4, "rock": 8, "belly": 16, "slip": 32,
               "edge": 64}
#: The float layers, in the order they are written (GeoTIFF bands).
LAYERS = ("slope_deg", "roughness_m", "step_m", "rock_m", "belly_m", "slip", "cost", "hazard",
          "hazard_bits")


@dataclass(frozen=True, eq=False)
class Traversability:
    """Traversability of every cell for the rover centred there, at any heading.

    Grids share one shape, rows south to north (as :class:`Heightfield`): cell ``[row, col]``
    is at ``x = origin_xy_m[0] + col * cell_m``, ``y = origin_xy_m[1] + row * cell_m``.

    Attributes
    ----------
    slope_deg : ndarray
        Tilt of the plane fitted over the footprint disc.
    roughness_m : ndarray
        RMS residual of that fit.
    step_m : ndarray
        The largest terrain height range over a wheel's diameter where a wheel can stand.
    rock_m : ndarray
        The tallest rock (exposed height) where a wheel can stand.
    belly_m : ndarray
        How far terrain and rocks rise above the wheels' plane under the belly (negative: all
        below it).
    slip : ndarray
        Predicted uphill slip on the cell's soil at ``slope_deg`` (0 on rigid ground).
    cost : ndarray
        Combined cost in [0, 1]: the largest term's value over its limit (1 at a hazard).
    hazard : ndarray of bool
    hazard_bits : ndarray of uint8
        Which limits each hazard exceeds (:data:`HAZARD_BITS`).
    soil_index : ndarray of uint8
        Index into ``soils`` (all 0 and ``soils`` empty on rigid ground).
    limits : dict of str to float
        Each term's limit in its unit (the hazard thresholds).
    """

    cell_m: float
    origin_xy_m: tuple[float, float]
    slope_deg: NDArray[np.float32]
    roughness_m: NDArray[np.float32]
    step_m: NDArray[np.float32]
    rock_m: NDArray[np.float32]
    belly_m: NDArray[np.float32]
    slip: NDArray[np.float32]
    cost: NDArray[np.float32]
    hazard: NDArray[np.bool_]
    hazard_bits: NDArray[np.uint8]
    soil_index: NDArray[np.uint8]
    soils: tuple[str, ...]
    limits: dict[str, float]
    footprint: RoverFootprint

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.cost.shape[0]), int(self.cost.shape[1]))

    def layers(self) -> dict[str, NDArray[np.float32]]:
        """:data:`LAYERS` as float32 grids (hazard as 0/1, the bits as their integer)."""
        return {name: np.asarray(getattr(self, name), dtype=np.float32) for name in LAYERS}


def grid_stride(heightfield: Heightfield, config: TraversabilityConfig) -> int:
    """Posts per cell: the requested spacing in whole posts, else the fewest within budget."""
    post = heightfield.cell_size_m
    if config.cell_m is not None:
        stride = round(config.cell_m / post)
        if stride < 1:
            raise ConfigError(f"traversability cell {config.cell_m} m is finer than the "
                              f"terrain's {post:g} m posts")
        return int(stride)
    rows, cols = heightfield.shape
    return max(1, math.ceil(math.sqrt(rows * cols / config.max_cells)))


def _limits(fp: RoverFootprint, cfg: TraversabilityConfig) -> dict[str, float]:
    step = cfg.step_limit_wheel_diameters * 2.0 * fp.wheel_radius_m
    return {"slope": cfg.max_slope_deg, "roughness": cfg.roughness_limit_clearances
            * fp.belly_clearance_m, "step": step, "rock": step, "belly": fp.belly_clearance_m,
            "slip": cfg.max_slip}


def _slip(slope: NDArray[np.float64], xy: tuple[NDArray[np.float64], NDArray[np.float64]],
          soil: SoilMap | None, fp: RoverFootprint) -> tuple[NDArray[np.float64],
                                                              NDArray[np.uint8]]:
    if soil is None:
        return rigid_slip(slope, fp.friction), np.zeros(slope.shape, np.uint8)
    pts = np.column_stack([xy[0].ravel(), xy[1].ravel()])
    index = soil.at(pts).reshape(slope.shape).astype(np.uint8)
    slip = np.zeros(slope.shape)
    for k in np.unique(index).tolist():
        sel = index == k
        slip[sel] = soil_slip(slope[sel], soil.soils[k], radius_m=fp.wheel_radius_m,
                              width_m=fp.wheel_width_m, weight_n=fp.weight_n)
    return slip, index


def _edge(shape: tuple[int, int], cell_m: float, reach_m: float) -> NDArray[np.bool_]:
    """Cells whose wheel ring leaves the terrain."""
    k = math.ceil(reach_m / cell_m - 1e-9)
    rows, cols = shape
    r, c = np.arange(rows)[:, None], np.arange(cols)[None, :]
    return (r < k) | (r >= rows - k) | (c < k) | (c >= cols - k)


def compute(heightfield: Heightfield, *, rocks_xy_m: ArrayLike | None = None,
            rocks_diameter_m: ArrayLike | None = None, rocks_height_m: ArrayLike | None = None,
            soil: SoilMap | None = None, rover: RoverConfig | None = None,
            config: TraversabilityConfig | None = None) -> Traversability:
    """The traversability layers of ``heightfield`` with its rocks and soil for ``rover``.

    Parameters
    ----------
    heightfield : Heightfield
        The terrain (scene frame). The grid takes every ``stride``-th post
        (:func:`grid_stride`).
    rocks_xy_m, rocks_diameter_m, rocks_height_m : array_like, optional
        Rock centres (N, 2), diameters and exposed heights (a ``RockTable``'s columns).
    soil : SoilMap, optional
        None: rigid ground.
    rover : RoverConfig, optional
    config : TraversabilityConfig, optional

    Examples
    --------
    >>> import numpy as np
    >>> from marsscene.terrain.heightfield import Heightfield
    >>> hf = Heightfield.centered(np.zeros((81, 81), np.float32), 0.25)
    >>> t = compute(hf)
    >>> float(t.slope_deg[40, 40]), bool(t.hazard[40, 40])
    (0.0, False)
    """
    cfg = config if config is not None else TraversabilityConfig()
    fp = RoverFootprint.of(rover)
    stride = grid_stride(heightfield, cfg)
    z = np.asarray(heightfield.z_m[::stride, ::stride], dtype=np.float64)
    cell = heightfield.cell_size_m * stride
    if min(z.shape) < 2:
        raise ConfigError(f"a {cell:g} m grid leaves fewer than 2 x 2 cells of the terrain")
    origin = heightfield.origin_xy_m
    disc = ring_kernel(fp.footprint_radius_m, cell)
    ring = ring_kernel(fp.wheel_outer_m, cell, fp.wheel_inner_m)
    corr = plane_correlator(z, max(disc.shape[0], ring.shape[0]) // 2)
    fit = fit_plane(z, cell, disc, correlator=corr)
    slope, rough = fit.slope_deg, fit.rms_m
    step = step_height(z, cell, fp.wheel_radius_m, ring)
    if rocks_xy_m is None:
        rock_grid = np.zeros_like(z)
    elif rocks_diameter_m is None or rocks_height_m is None:
        raise ConfigError("rocks need rocks_diameter_m and rocks_height_m with rocks_xy_m")
    else:
        rock_grid = rasterise_rocks(rocks_xy_m, rocks_diameter_m, rocks_height_m, shape=z.shape,
                                    origin_xy_m=origin, cell_m=cell)
    from scipy.ndimage import maximum_filter

    rock = maximum_filter(rock_grid, footprint=ring, mode="constant", cval=0.0)
    wheels = fit_plane(z, cell, ring, correlator=corr, residual=False)
    del corr  # the terrain's spectra
    belly = belly_intrusion(z + rock_grid, cell, wheels, fp.belly_radius_m)
    xs = origin[0] + cell * np.arange(z.shape[1])
    ys = origin[1] + cell * np.arange(z.shape[0])
    slip, soil_index = _slip(slope, np.meshgrid(xs, ys), soil, fp)
    return _combine(cell, origin, {"slope": slope, "roughness": rough, "step": step,
                                   "rock": rock, "belly": belly, "slip": slip},
                    _edge(z.shape, cell, fp.wheel_outer_m), soil_index, soil, fp, cfg)


def _combine(cell: float, origin: tuple[float, float], terms: dict[str, NDArray[np.float64]],
             edge: NDArray[np.bool_], soil_index: NDArray[np.uint8], soil: SoilMap | None,
             fp: RoverFootprint, cfg: TraversabilityConfig) -> Traversability:
    """Cost = the largest term over its limit (clipped to [0, 1]); hazard where any reaches
    its limit or the wheel ring leaves the terrain."""
    limits = _limits(fp, cfg)
    bits = np.where(edge, np.uint8(HAZARD_BITS["edge"]), np.uint8(0))
    cost = np.zeros(edge.shape)
    for name, value in terms.items():
        ratio = value / limits[name]
        bits |= np.where(ratio >= 1.0, np.uint8(HAZARD_BITS[name]), np.uint8(0))
        np.maximum(cost, np.clip(ratio, 0.0, 1.0), out=cost)
    hazard = bits > 0
    cost[hazard] = 1.0
    f32 = {name: np.asarray(v, dtype=np.float32) for name, v in terms.items()}
    return Traversability(
        cell_m=cell, origin_xy_m=origin, slope_deg=f32["slope"], roughness_m=f32["roughness"],
        step_m=f32["step"], rock_m=f32["rock"], belly_m=f32["belly"], slip=f32["slip"],
        cost=cost.astype(np.float32), hazard=hazard, hazard_bits=bits, soil_index=soil_index,
        soils=tuple(s.name for s in soil.soils) if soil is not None else (),
        limits=limits, footprint=fp)
