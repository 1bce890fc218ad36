"""The level-of-detail stages of :func:`marsscene.build_scene` (``terrain.lod = true``).

Pipeline order, as :mod:`marsscene.pipeline` calls them:

1. :func:`lod_world` — the coarse terrain over the whole footprint (procedural fBm + landform, or
   the DEM at its own posts), the focus square and its tiles, and the detail model;
2. :func:`lod_craters` — one crater table for the footprint (the focus square samples its own
   craters, :func:`~marsscene.terrain.lod.merge_craters`) stamped on the coarse grid;
3. :func:`focus_heightfield` — the focus square at full resolution, tile by tile
   (:func:`~marsscene.terrain.tiles.tile_terrain`);
4. :func:`focus_rocks` — rocks per tile, each tile from its own random stream, and
   :func:`outer_rocks` (rocks of at least the cut-off outside the focus,
   :mod:`marsscene.rocks.budget`); a one-grid scene whose rocks need two levels gets its rock
   focus square from :func:`rock_focus`.

:func:`build_tile` builds one focus tile (terrain and rocks) alone; it equals the same tile of a
full build (tested), which is what makes tiles independent of each other.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from marsscene._threads import worth_a_thread
from marsscene.craters import sample_craters, stamp_craters
from marsscene.craters.config import CraterConfig
from marsscene.craters.population import PopulationStats
from marsscene.craters.table import CraterTable
from marsscene.errors import ConfigError
from marsscene.landforms import add_landform, default_size_m
from marsscene.rocks import place_rocks
from marsscene.rocks.config import RockConfig
from marsscene.rocks.table import RockTable
from marsscene.seeding import stage_key, stage_rng, tile_rng
from marsscene.terrain import resample, synthesize
from marsscene.terrain.config import TerrainConfig
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import (
    TAPER_POSTS,
    FocusPlan,
    concat_tables,
    merge_craters,
    plan_focus,
)
from marsscene.terrain.tiles import FocusTiling, TileDetail, detail_rms_m, tile_terrain

__all__ = ["LodWorld", "focus_heightfield", "focus_rocks", "focus_window", "lod_craters",
           "lod_world", "outer_rocks", "rock_focus"]

log = logging.getLogger("marsscene")

_TILE_THREADS = 2  # focus tiles whose rocks are placed at a time


@dataclass(frozen=True, eq=False)
class LodWorld:
    """What every focus tile is built from: the coarse terrain (before craters), the focus
    square, its tiling, the detail model and the base grid the focus is interpolated from
    (the coarse grid itself, or a DEM at its own posts under a coarser outer level)."""

    coarse: Heightfield
    plan: FocusPlan
    tiling: FocusTiling
    detail: TileDetail
    base: Heightfield


def _procedural_coarse(tcfg: TerrainConfig, seed: int) -> Heightfield:
    size = tcfg.effective_size_m
    lf_size = tcfg.landform_size_m if tcfg.landform_size_m is not None else \
        default_size_m(tcfg.landform, min(size))
    coarse = synthesize(size, tcfg.post_m if tcfg.post_m is not None else 1.0, hurst=tcfg.hurst,
                        rms_height_m=tcfg.rms_height_m, rms_slope_deg=tcfg.rms_slope_deg,
                        rng=stage_rng(seed, "terrain"))
    return add_landform(coarse, tcfg.landform, size_m=lf_size, depth_m=tcfg.landform_depth_m)


def _snap_dem(hf: Heightfield, fine_post_m: float, notes: list[str]) -> Heightfield:
    """The DEM heightfield at a whole multiple of the focus posts (resampled only if needed)."""
    ratio = max(1, round(hf.cell_size_m / fine_post_m))
    post = ratio * fine_post_m
    if abs(post - hf.cell_size_m) <= 1e-9 * post:
        return hf
    notes.append(f"terrain: the DEM's {hf.cell_size_m:g} m posts resampled to {post:g} m "
                 f"(a whole multiple of terrain.focus_post_m) for the outer terrain")
    return resample(hf, post_m=post)


def _average_to(base: Heightfield, post_m: float, notes: list[str]) -> Heightfield:
    """The outer level of a DEM: ``base`` averaged over ``post_m`` boxes centred on every
    ``post_m / base post``-th post (so the outer posts are base posts)."""
    import numpy as np
    from scipy.ndimage import uniform_filter

    f = round(post_m / base.cell_size_m)
    if f < 2:
        return base
    z = uniform_filter(base.z_m.astype(np.float64), size=f | 1, mode="nearest")[::f, ::f]
    notes.append(f"terrain: outer level = the DEM averaged to {f * base.cell_size_m:g} m posts; "
                 f"the focus square keeps the DEM's {base.cell_size_m:g} m posts")
    return Heightfield(z.astype(np.float32), f * base.cell_size_m, base.origin_xy_m)


def _plan(coarse: Heightfield, tcfg: TerrainConfig, notes: list[str], *,
          fine_post_m: float | None = None) -> FocusPlan:
    fine = tcfg.focus_post_m if fine_post_m is None else fine_post_m
    try:
        return plan_focus(coarse, center_xy_m=tcfg.focus_xy_m, size_m=tcfg.focus_size_m,
                          fine_post_m=fine)
    except ConfigError:
        if tcfg.focus_xy_m is not None:
            raise
    # the default focus (centred) does not fit: use the largest centred square that does
    side_m = (min(coarse.shape) - 6) * coarse.cell_size_m
    plan = plan_focus(coarse, center_xy_m=None, size_m=side_m, fine_post_m=fine)
    side = plan.cells * plan.coarse_post_m
    notes.append(f"terrain: the {tcfg.focus_size_m:g} m focus square does not fit the "
                 f"footprint; using the central {side:g} m")
    return plan


def rock_focus(hf: Heightfield, tcfg: TerrainConfig, notes: list[str]) -> FocusTiling | None:
    """The focus square of a one-grid scene's rocks (``terrain.focus_xy_m``,
    ``terrain.focus_size_m``) on ``hf``'s own posts, cut into ``terrain.tile_m`` tiles as a
    level-of-detail focus is; ``None`` for a footprint too small to hold one."""
    if min(hf.shape) < 2 * TAPER_POSTS + 7:
        return None
    plan = _plan(hf, tcfg, notes, fine_post_m=hf.cell_size_m)
    return FocusTiling.of(plan, tcfg.tile_m)


def focus_window(hf: Heightfield, plan: FocusPlan) -> Heightfield:
    """The focus square of a one-grid heightfield (a view: ``plan`` on ``hf``'s posts)."""
    n = plan.cells
    return Heightfield(hf.z_m[plan.row0:plan.row0 + n + 1, plan.col0:plan.col0 + n + 1],
                       hf.cell_size_m, plan.bounds_xy_m[:2])


def _check_focus_posts(plan: FocusPlan) -> None:
    """The focus square is held whole (MuJoCo compiles it into one hfield): refuse one that
    would not fit the memory plan of a single grid."""
    from marsscene.errors import MemoryBudgetError
    from marsscene.terrain.synth import MAX_POSTS

    n = plan.cells * plan.ratio + 1
    if n * n > MAX_POSTS:
        side = plan.cells * plan.coarse_post_m
        raise MemoryBudgetError(
            f"a {side:g} m focus square at {plan.fine_post_m:g} m posts has {n * n:,} posts; "
            f"the limit is {MAX_POSTS:,}: shrink terrain.focus_size_m (--focus-size-m) or "
            "raise terrain.focus_post_m (--focus-post-m)")


def lod_world(tcfg: TerrainConfig, seed: int, *, dem_hf: Heightfield | None = None,
              notes: list[str] | None = None,
              base_reader: Callable[[FocusPlan], Heightfield] | None = None) -> LodWorld:
    """Stage 1: the coarse terrain, the focus plan, the tiles and the detail model.

    ``base_reader`` (a DTM read averaged: :mod:`marsscene.pipeline.dem_lod`) reads the focus
    window at the DTM's posts once the plan is known; ``dem_hf`` is then the outer level.
    """
    notes = notes if notes is not None else []
    if dem_hf is None:
        base = coarse = _procedural_coarse(tcfg, seed)
    elif base_reader is not None:
        coarse = dem_hf
    else:
        base = _snap_dem(dem_hf, tcfg.focus_post_m, notes)
        outer_post = tcfg.post_m if tcfg.post_m is not None else base.cell_size_m
        coarse = _average_to(base, outer_post, notes)
    plan = _plan(coarse, tcfg, notes)
    _check_focus_posts(plan)
    if base_reader is not None:
        base = base_reader(plan)
    if dem_hf is not None and not tcfg.detail:
        rms = 0.0
    elif tcfg.detail_rms_m is not None:
        rms = tcfg.detail_rms_m
    else:
        rms = detail_rms_m(base, plan, tcfg.hurst)
    detail = TileDetail(rms, tcfg.hurst, stage_key(seed, "terrain_detail_lod"))
    return LodWorld(coarse, plan, FocusTiling.of(plan, tcfg.tile_m), detail, base)


def lod_craters(world: LodWorld, ccfg: CraterConfig, seed: int
                ) -> tuple[Heightfield, CraterTable, PopulationStats]:
    """Stage 2: one crater table for the footprint, and the coarse grid with it stamped."""
    coarse = world.coarse
    focus, _ = sample_craters(world.plan.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters_focus"),
                              heightfield=coarse)
    outer, stats = sample_craters(coarse.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters"),
                                  heightfield=coarse)
    table = merge_craters(focus, outer, world.plan.bounds_xy_m, ejecta_reach=ccfg.ejecta_reach,
                          axis_ratio_min=ccfg.axis_ratio_min)
    return stamp_craters(coarse, table, profile_kwargs=ccfg.profile_kwargs()), table, stats


def focus_heightfield(world: LodWorld, craters: CraterTable | None,
                      ccfg: CraterConfig | None) -> Heightfield:
    """Stage 3: the focus square at full resolution, assembled from its tiles."""
    import numpy as np

    plan, tiling = world.plan, world.tiling
    n = plan.cells * plan.ratio + 1
    z = np.zeros((n, n), dtype=np.float32)
    for row in range(tiling.count):
        for col in range(tiling.count):  # a few tiles: each call is vectorised
            tile = tile_terrain(world.coarse, tiling, row, col, detail=world.detail,
                                craters=craters, ccfg=ccfg, stamp=stamp_craters,
                                base=world.base)
            z[tiling.posts(row), tiling.posts(col)] = tile.z_m
            log.info("[terrain] tile %d/%d", row * tiling.count + col + 1, tiling.count ** 2)
    return Heightfield._owning(z, plan.fine_post_m, plan.bounds_xy_m[:2])


def _tile_window(hf: Heightfield, tiling: FocusTiling, row: int, col: int) -> Heightfield:
    x0, y0 = hf.origin_xy_m
    rs, cs = tiling.posts(row), tiling.posts(col)
    origin = (x0 + cs.start * hf.cell_size_m, y0 + rs.start * hf.cell_size_m)
    return Heightfield(hf.z_m[rs, cs], hf.cell_size_m, origin)


def focus_rocks(hf: Heightfield, tiling: FocusTiling, craters: CraterTable, rcfg: RockConfig,
                seed: int, *, tiles: list[tuple[int, int]] | None = None) -> RockTable:
    """Stage 4: rocks of the focus square, placed tile by tile from per-tile streams."""
    tiles = tiles if tiles is not None else [(r, c) for r in range(tiling.count)
                                             for c in range(tiling.count)]

    def one(cell: tuple[int, int]) -> RockTable:
        r, c = cell
        return place_rocks(_tile_window(hf, tiling, r, c), craters, rcfg,
                           rng=tile_rng(seed, "rocks_tile", r, c))

    # per-tile streams: the same rocks on any number of threads
    threads = _TILE_THREADS if len(tiles) > 1 and worth_a_thread(hf.z_m.size) else 1
    with ThreadPoolExecutor(max_workers=threads,
                            thread_name_prefix="marsscene-focus-rocks") as pool:
        parts = list(pool.map(one, tiles))
    return parts[0] if len(parts) == 1 else concat_tables(*parts)


def outer_rocks(rocks: RockTable, terrain: Heightfield,
                focus_bounds_xy_m: tuple[float, float, float, float], craters: CraterTable,
                rcfg: RockConfig, seed: int, *, d_min_m: float) -> RockTable:
    """Add rocks of at least ``d_min_m`` (the cut-off, :mod:`marsscene.rocks.budget`) on
    ``terrain`` outside the focus square."""
    if d_min_m >= rcfg.d_max_m:
        return rocks
    cfg = dataclasses.replace(rcfg, d_min_m=d_min_m)
    far = place_rocks(terrain, craters, cfg, rng=stage_rng(seed, "rocks_outer"))
    x0, y0, x1, y1 = focus_bounds_xy_m
    x, y = far.position_xyz_m[:, 0], far.position_xyz_m[:, 1]
    result: RockTable = concat_tables(rocks, far.take(~((x >= x0) & (x <= x1) & (y >= y0)
                                                        & (y <= y1))))
    return result
