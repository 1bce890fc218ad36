"""``place_rocks``: sample a Golombek–Huertas rock population and set it on the terrain.

Steps (all vectorised; no loop per rock):

1. Intensity over a placement grid: uniform, crater-ejecta weighted, normalised to mean 1 so the
   scene-mean abundance stays ``k``; ``k`` may vary in space (rock-field polygon or raster).
2. For each distinct ``k``: Poisson count ``A [N(>d_min) - N(>d_max)]``, positions from the
   intensity (Thomas clusters when ``placement = "clustered"``), inverse-CDF diameters.
3. Rocks where the slope across their footprint exceeds ``max_slope_deg`` are removed
   (thinning a Poisson process).
4. Exposed height ``h = ratio * D``, burial ``b = h f / (1 - f)`` for buried fraction ``f``,
   horizontal elongation, random yaw, up axis = surface normal clamped to ``max_tilt_deg`` plus
   a small random tilt; base centre at ``surface(x, y) - b``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from marsscene._validate import plain
from marsscene.errors import ConfigError
from marsscene.rocks.budget import gib
from marsscene.rocks.config import RockConfig
from marsscene.rocks.placement import (
    PlacementGrid,
    ejecta_weight,
    placement_grid,
    point_in_polygon,
    sample_cells,
    thomas_offsets,
)
from marsscene.rocks.sfd import cumulative_number_density_per_m2, sample_diameters
from marsscene.rocks.table import RockTable
from marsscene.terrain.heightfield import Heightfield

if TYPE_CHECKING:
    from marsscene.craters.table import CraterTable

__all__ = ["intensity_map", "k_per_cell", "orientations", "place_rocks", "prototype_indices"]


def intensity_map(
    hf: Heightfield, craters: CraterTable, cfg: RockConfig, grid: PlacementGrid
) -> NDArray[np.float64]:
    """Relative rock intensity per grid cell, shape ``(ny * nx,)``, mean 1.

    ``1 + (ejecta_boost - 1) * E`` with ``E`` the crater-ejecta enhancement for
    ``placement = "ejecta"``; all ones otherwise.
    """
    w = np.ones(grid.nx * grid.ny)
    if cfg.placement == "ejecta" and len(craters) and cfg.ejecta_boost > 1.0:
        xc, yc = grid.centers()
        e = ejecta_weight(
            xc, yc, craters, extent_radii=cfg.ejecta_extent_radii, fade_ga=cfg.ejecta_fade_ga,
            min_radius_m=0.5 * max(grid.dx_m, grid.dy_m),
        )
        w = 1.0 + (cfg.ejecta_boost - 1.0) * e
    return w / w.mean()


def k_per_cell(
    hf: Heightfield, cfg: RockConfig, grid: PlacementGrid, k_map: NDArray[np.floating] | None
) -> NDArray[np.float64]:
    """Rock abundance ``k`` of every grid cell, shape ``(ny * nx,)``.

    ``k_map`` (one value per terrain post, shape ``hf.shape``) wins over the rock-field polygon;
    values are rounded to 0.001 so that a few distinct populations are sampled.
    """
    xc, yc = grid.centers()
    k = np.full(xc.shape, cfg.k)
    if k_map is not None:
        km = np.asarray(k_map, dtype=np.float64)
        if km.shape != hf.shape:
            raise ConfigError(f"k_map has shape {km.shape}; expected the heightfield's {hf.shape}")
        if not (np.isfinite(km).all() and km.min() > 0.0 and km.max() <= 0.9):
            raise ConfigError(
                f"k_map values must be in (0, 0.9]; got [{plain(km.min())!r}, {plain(km.max())!r}]"
            )
        r, c = hf.rowcol_of(xc, yc)
        k = km[np.rint(r).astype(np.int64), np.rint(c).astype(np.int64)]
    elif cfg.field_polygon_xy_m is not None:
        inside = point_in_polygon(xc, yc, np.asarray(cfg.field_polygon_xy_m))
        k = np.where(inside, cfg.field_k, k)
    return np.round(k, 3)


def _expected(area_w_m2: NDArray[np.float64], k_values: NDArray[np.float64],
              cfg: RockConfig) -> NDArray[np.float64]:
    dens = np.array([
        np.subtract(*cumulative_number_density_per_m2([cfg.d_min_m, cfg.d_max_m], k=float(kv)))
        for kv in k_values  # one per distinct k (a few), not per rock
    ])
    return area_w_m2 * dens


def place_rocks(
    hf: Heightfield,
    craters: CraterTable,
    cfg: RockConfig,
    *,
    rng: np.random.Generator,
    k_map: NDArray[np.floating] | None = None,
) -> RockTable:
    """Sample a rock population and place it on the terrain.

    Diameters follow the Golombek–Huertas model for the abundance ``cfg.k`` (:doc:`/science/rocks`);
    positions follow ``cfg.placement`` (near fresh craters by default) and rocks on slopes
    steeper than ``cfg.max_slope_deg`` are thinned away. :func:`marsscene.build_scene` calls
    it with the scene's terrain and craters.

    Parameters
    ----------
    hf : Heightfield
        Terrain (craters already stamped).
    craters : CraterTable
        Craters for ejecta weighting (may be empty).
    cfg : RockConfig
        Abundance, diameter range, placement, shapes.
    rng : numpy.random.Generator
        The rock stage's stream (``stage_rng(seed, "rocks")`` in a build).
    k_map : ndarray of shape (rows, cols), optional
        Spatially varying abundance per terrain post (overrides ``cfg.k`` and the polygon).

    Returns
    -------
    RockTable
        With ``scale_xyz_m`` = (long axis, short axis, total height) of each rock (in m).

    Raises
    ------
    ConfigError
        If the expected count exceeds ``cfg.max_rocks`` (lower ``d_min_m`` needs an override).

    Examples
    --------
    Rocks at 10 % abundance on flat ground 10 m x 10 m, with no craters:

    >>> import numpy as np
    >>> from marsscene.craters import CraterTable
    >>> from marsscene.rocks import RockConfig, place_rocks
    >>> from marsscene.terrain import Heightfield
    >>> hf = Heightfield(np.zeros((41, 41), np.float32), cell_size_m=0.25,
    ...                  origin_xy_m=(-5.0, -5.0))
    >>> rocks = place_rocks(hf, CraterTable.empty(), RockConfig(k=0.1),
    ...                     rng=np.random.default_rng(7))
    >>> len(rocks), bool(rocks.diameter_m.min() >= RockConfig().d_min_m)
    (191, True)
    >>> rocks.position_xyz_m.shape
    (191, 3)
    """
    grid = placement_grid(hf)
    weight = intensity_map(hf, craters, cfg, grid)
    kcell = k_per_cell(hf, cfg, grid, k_map)
    k_values, k_index = np.unique(kcell, return_inverse=True)
    area_w = np.asarray(
        np.bincount(k_index, weights=weight, minlength=len(k_values)) * grid.cell_area_m2,
        dtype=np.float64,
    )
    lam = _expected(area_w, np.asarray(k_values, dtype=np.float64), cfg)
    if lam.sum() > cfg.max_rocks:
        raise ConfigError(
            f"rocks: about {lam.sum():.3g} rocks expected with d_min_m = {cfg.d_min_m} on "
            f"{hf.area_m2:.3g} m^2 (~{gib(lam.sum()):.2g} GiB while "
            f"placing), above rocks.max_rocks = {cfg.max_rocks}; raise d_min_m or set "
            "rocks.max_rocks explicitly"
        )
    counts = rng.poisson(lam)
    xs, ys, ds = [], [], []
    for i, kv in enumerate(k_values):  # one population per distinct k
        cells = np.flatnonzero(k_index == i)
        n = int(counts[i])
        if cfg.placement == "clustered":
            n_par = max(1, int(rng.poisson(max(n / cfg.rocks_per_cluster, 1e-9))))
            px, py = sample_cells(n_par, grid, cells, weight[cells], rng=rng)
            x, y = thomas_offsets(n, np.column_stack([px, py]), sigma_m=cfg.cluster_radius_m,
                                  bounds_xy_m=hf.bounds_xy_m, rng=rng)
        else:
            x, y = sample_cells(n, grid, cells, weight[cells], rng=rng)
        xs.append(x)
        ys.append(y)
        ds.append(sample_diameters(n, k=float(kv), d_min_m=cfg.d_min_m, d_max_m=cfg.d_max_m,
                                   rng=rng))
    x, y, d = np.concatenate(xs), np.concatenate(ys), np.concatenate(ds)
    gx, gy = footprint_gradient(hf, x, y, d, baseline_m=cfg.slope_baseline_m)
    ok = np.hypot(gx, gy) <= np.tan(np.radians(cfg.max_slope_deg))
    x, y, d, gx, gy = x[ok], y[ok], d[ok], gx[ok], gy[ok]
    return _dress(hf, x, y, d, gx, gy, cfg, rng=rng)


def footprint_gradient(
    hf: Heightfield,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    d: NDArray[np.float64],
    *,
    baseline_m: float = 1.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Surface gradient under each rock: central differences of the bilinear surface over a
    baseline of ``max(D, baseline_m, 2 posts)`` (the plane a rock rests on; post-scale
    roughness neither tilts nor rejects it)."""
    h = 0.5 * np.maximum(np.maximum(d, baseline_m), 2.0 * hf.cell_size_m)
    x0, y0, x1, y1 = hf.bounds_xy_m
    xp, xm = np.minimum(x + h, x1), np.maximum(x - h, x0)  # one-sided at the edges
    yp, ym = np.minimum(y + h, y1), np.maximum(y - h, y0)
    gx = (hf.sample(xp, y) - hf.sample(xm, y)) / (xp - xm)
    gy = (hf.sample(x, yp) - hf.sample(x, ym)) / (yp - ym)
    return gx, gy


def _uniform(rng: np.random.Generator, lo_hi: tuple[float, float], n: int) -> NDArray[np.float64]:
    lo, hi = lo_hi
    return lo + (hi - lo) * rng.random(n)


def _dress(
    hf: Heightfield,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    d: NDArray[np.float64],
    gx: NDArray[np.float64],
    gy: NDArray[np.float64],
    cfg: RockConfig,
    *,
    rng: np.random.Generator,
) -> RockTable:
    n = len(d)
    height = _uniform(rng, cfg.range_of("height_ratio"), n) * d
    frac = _uniform(rng, cfg.range_of("burial_fraction"), n)
    burial = height * frac / (1.0 - frac)
    elong = np.sqrt(_uniform(rng, cfg.range_of("aspect_ratio"), n))
    yaw = rng.random(n) * 2.0 * np.pi
    jitter = rng.normal(0.0, np.radians(cfg.tilt_jitter_deg) / np.sqrt(2.0), size=(n, 2))
    quat = orientations(gx, gy, yaw, jitter, max_tilt_rad=np.radians(cfg.max_tilt_deg))
    z = hf.sample(x, y) - burial
    scale = np.column_stack([d * elong, d / elong, height + burial])
    proto = prototype_indices(d, cfg, rng=rng)
    return RockTable(
        np.column_stack([x, y, z]), d, height, burial, quat, proto, scale_xyz_m=scale
    )


def prototype_indices(
    diameter_m: NDArray[np.float64], cfg: RockConfig, *, rng: np.random.Generator
) -> NDArray[np.int64]:
    """Prototype of each rock: uniform among the prototypes of its size class.

    Prototype ``p`` belongs to size class ``p % n_classes`` (classes split at
    ``cfg.size_classes_m``); with fewer prototypes than classes the largest classes share the
    last prototype.
    """
    n_classes = len(cfg.size_classes_m) + 1
    klass = np.searchsorted(np.asarray(cfg.size_classes_m), diameter_m, side="right")
    klass = np.minimum(klass, cfg.prototypes - 1)
    members = np.bincount(np.arange(cfg.prototypes) % n_classes, minlength=n_classes)
    pick = np.floor(rng.random(len(diameter_m)) * members[klass]).astype(np.int64)
    return np.asarray(klass + n_classes * pick, dtype=np.int64)


def orientations(
    gx: NDArray[np.float64],
    gy: NDArray[np.float64],
    yaw_rad: NDArray[np.float64],
    jitter_rad: NDArray[np.float64],
    *,
    max_tilt_rad: float,
) -> NDArray[np.float64]:
    """Quaternions ``(w, x, y, z)``: yaw about the rock's axis, then tilt of +z onto the
    surface normal (gradient ``gx, gy``) plus ``jitter_rad`` (N, 2), clamped to
    ``max_tilt_rad``.
    """
    # tilt vector: direction of the up axis' horizontal lean, magnitude = tilt angle; the
    # normal leans downhill, along -(gx, gy), by atan|g| (direction cosines by division, not
    # by atan2 + cos/sin: 1e6 rocks)
    slope = np.hypot(gx, gy)
    lean = np.divide(np.arctan(slope), slope, out=np.ones_like(slope), where=slope > 0)
    tx = -gx * lean + jitter_rad[:, 0]
    ty = -gy * lean + jitter_rad[:, 1]
    tilt = np.hypot(tx, ty)
    cos_phi = np.divide(tx, tilt, out=np.ones_like(tilt), where=tilt > 0)
    sin_phi = np.divide(ty, tilt, out=np.zeros_like(tilt), where=tilt > 0)
    half = 0.5 * np.minimum(tilt, max_tilt_rad)
    sin_half = np.sin(half)
    # q_tilt * q_yaw with q_tilt = (cos h, -sin p sin h, cos p sin h, 0) (the rotation taking
    # +z to (sin t cos p, sin t sin p, cos t), axis (-sin p, cos p, 0)) and
    # q_yaw = (cos y/2, 0, 0, sin y/2): the Hamilton product without its zero terms, written
    # column by column into one (n, 4) array
    cw, tx, ty = np.cos(half), -sin_phi * sin_half, cos_phi * sin_half
    hy = 0.5 * np.asarray(yaw_rad, dtype=np.float64)
    yw, yz = np.cos(hy), np.sin(hy)
    q = np.zeros((cw.size, 4))
    np.multiply(cw, yw, out=q[:, 0])
    np.add(tx * yw, ty * yz, out=q[:, 1])
    np.subtract(ty * yw, tx * yz, out=q[:, 2])
    np.multiply(cw, yz, out=q[:, 3])
    return q
