"""``build_scene``: the only code that wires the stages together, in pipeline order.

DEM / procedural -> terrain (+ sub-DEM detail) -> craters -> [level of detail: focus tiles]
-> assets -> [level of detail: stitch] -> rocks -> lighting -> Scene. One module per stage in
this package (:mod:`.terrain`, :mod:`.craters`, :mod:`.rocks`, :mod:`.lighting`; the
level-of-detail steps in :mod:`.lod`). Each stage draws from its own random stream
(:func:`marsscene.seeding.stage_rng`), so changing one stage's parameters never changes another
stage's random draws.
"""

from __future__ import annotations

import logging
from typing import Any

from marsscene.assets import place_assets
from marsscene.assets.io import load_assets
from marsscene.config import SceneConfig
from marsscene.craters.table import CraterTable
from marsscene.dem.model import DEM
from marsscene.pipeline.craters import crater_stage
from marsscene.pipeline.lighting import lighting_stage
from marsscene.pipeline.lod import LodWorld
from marsscene.pipeline.record import BuildRecord
from marsscene.pipeline.rocks import check_rock_budget, rock_stage
from marsscene.pipeline.terrain import TerrainStage, resolve_lod, terrain_stage
from marsscene.scene import ModelRef, Provenance, Scene
from marsscene.seeding import stage_rng
from marsscene.soil import author_soil_map
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import OuterTerrain, lod_summary, stitch

__all__ = ["build_scene"]

log = logging.getLogger("marsscene")


def build_scene(config: SceneConfig | None = None, *, seed: int, dem: DEM | None = None) -> Scene:
    """Build a Mars scene: terrain, then craters, rocks and lighting, all from one seed.

    The same ``config`` and ``seed`` give the same scene on every run (each stage draws from
    its own stream, :func:`marsscene.seeding.stage_rng`). Nothing is written to disk: pass
    the scene to :func:`marsscene.write_scene` for USD and MJCF, or to :func:`marsscene.drive`.

    Parameters
    ----------
    config : SceneConfig, optional
        Stage parameters (defaults: the bundled Gale crater DEM at 0.25 m with detail).
        :meth:`SceneConfig.from_dict` and :meth:`SceneConfig.from_toml` take the keys of a
        ``scene.toml``.
    seed : int
        User seed; every stage derives its own stream from it.
    dem : DEM, optional
        An already-read DEM (:func:`marsscene.read_dem`); overrides ``config.terrain.source``.

    Returns
    -------
    Scene
        The terrain (``heightfield``, craters stamped), the ``craters`` and ``rocks`` tables
        (None for a disabled stage), the ``lighting``, the ``config`` and ``seed``.

    Raises
    ------
    ConfigError
        A configuration that cannot be built (for example, more rocks than ``rocks.max_rocks``).
    DEMReadError
        A DEM source that cannot be read.

    Examples
    --------
    A procedural 20 m x 20 m scene (0.25 m posts):

    >>> import marsscene as ms
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> scene = ms.build_scene(cfg, seed=7)
    >>> scene.heightfield.shape
    (81, 81)
    >>> len(scene.craters), len(scene.rocks)
    (3, 265)
    """
    config = config if config is not None else SceneConfig()
    rec = BuildRecord()
    config, lod_note = resolve_lod(config, dem)
    if lod_note:
        log.warning(lod_note)
        rec.notes.append(lod_note)
    check_rock_budget(config, lod=False)  # one grid: a rock plan that cannot fit, before it
    with rec.stage("terrain"):
        terrain = terrain_stage(config, seed, dem, rec.models, rec.notes, rec.summary)
    world = terrain.world
    hf, coarse, craters = terrain.hf, world.coarse if world is not None else None, None
    if config.craters.enabled:
        stamped, lod_coarse, craters = crater_stage(config, seed, terrain, rec)
        hf, coarse = (stamped, lod_coarse) if world is None else (hf, lod_coarse)
    if world is not None:  # the focus square, tile by tile, now that the craters are known
        hf = _focus_tiles(config, world, craters, rec)
    assert hf is not None
    placed = None
    if config.assets.active:
        hf, placed = _assets(config, hf, rec)
    outer = _stitch(config, hf, world, coarse, rec) if world is not None else None
    rocks = prototypes = None
    if config.rocks.enabled:
        rocks, prototypes = rock_stage(config, seed, hf, craters, world, outer, placed, rec)
    lighting = lighting_stage(config, terrain.frame, rec) if config.lighting.enabled else None
    soil = None
    if config.soil.enabled:
        with rec.stage("soil"):
            soil = author_soil_map(config.soil, hf, craters, stage_rng(seed, "soil"))
            rec.summary["soil_shares"] = {k: round(v, 4) for k, v in soil.shares().items()}
            rec.models.append(ModelRef("soil", "Wong-Reece rigid wheel on Bekker / Janosi-"
                                       "Hanamoto soils", "Wong & Reece (1967); Ishigami et al. "
                                       "(2007), doi:10.1002/rob.20187"))
    return Scene(heightfield=hf, texture_rgb=terrain.texture_rgb, config=config, seed=seed,
                 provenance=_provenance(terrain, rec), craters=craters, rocks=rocks,
                 rock_prototypes=prototypes, lighting=lighting, assets=placed, outer=outer,
                 soil=soil)


def _focus_tiles(config: SceneConfig, world: LodWorld, craters: CraterTable | None,
                 rec: BuildRecord) -> Heightfield:
    from marsscene.pipeline.lod import focus_heightfield

    check_rock_budget(config, lod=True)  # after the terrain's focus plan, before its tiles
    with rec.stage("tiles"):
        return focus_heightfield(world, craters, config.craters if craters is not None else None)


def _assets(config: SceneConfig, hf: Heightfield, rec: BuildRecord) -> tuple[Heightfield, Any]:
    with rec.stage("assets"):
        hf, placed = place_assets(hf, load_assets(config.assets), config.assets)
        rec.summary["assets"] = [{"name": a.model.name, "xy_m": [round(v, 3) for v in a.xy_m],
                                  "base_z_m": round(a.base_z_m, 4),
                                  "pad_radius_m": round(a.pad_radius_m, 3)} for a in placed]
    return hf, placed


def _stitch(config: SceneConfig, hf: Heightfield, world: LodWorld, coarse: Heightfield | None,
            rec: BuildRecord) -> OuterTerrain | None:
    if coarse is None:
        return None
    with rec.stage("stitch"):
        outer = OuterTerrain(stitch(coarse, hf, world.plan, blend_m=config.terrain.lod_blend_m),
                             world.plan.bounds_xy_m)
        tiling = world.tiling
        rec.summary["lod"] = lod_summary(hf, outer, config.terrain, tiles=tiling.count,
                                         tile_m=tiling.tile_cells * world.plan.coarse_post_m,
                                         detail_rms_m=world.detail.rms_m)
    return outer


def _provenance(terrain: TerrainStage, rec: BuildRecord) -> Provenance:
    return Provenance(frame=terrain.frame, inputs=terrain.inputs, models=tuple(rec.models),
                      timings_s=rec.timings_s, notes=tuple(rec.notes), extra=rec.summary)
