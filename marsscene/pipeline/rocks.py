"""The rock stage: prototypes, then rocks placed over the terrain, cleared from asset pads.

Where the rocks go is decided first, from expected counts (:mod:`marsscene.rocks.budget`): one
level over the footprint while its population fits ``rocks.max_rocks``; otherwise (and always
over a level-of-detail terrain) the full population tile by tile over the focus square, each
tile from its own random stream, and rocks above a cut-off outside it.
"""

from __future__ import annotations

import logging
from typing import Any

from marsscene.assets import clear_rocks
from marsscene.config import SceneConfig
from marsscene.craters.table import CraterTable
from marsscene.pipeline.lod import LodWorld, focus_rocks, focus_window, outer_rocks, rock_focus
from marsscene.pipeline.record import BuildRecord
from marsscene.rocks import make_prototypes, place_rocks
from marsscene.rocks.budget import RockLevels, expected_rocks, plan_levels
from marsscene.rocks.report import EJECTA_CITATION, level_summary, rock_notes, rock_summary
from marsscene.rocks.sfd import GOLOMBEK_CITATION
from marsscene.rocks.shapes import RockPrototype
from marsscene.rocks.table import RockTable
from marsscene.scene import ModelRef
from marsscene.seeding import stage_rng
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import OuterTerrain
from marsscene.terrain.tiles import FocusTiling

__all__ = ["check_rock_budget", "rock_levels", "rock_stage"]

log = logging.getLogger("marsscene")


def rock_levels(config: SceneConfig, hf: Heightfield, world: LodWorld | None,
                outer: OuterTerrain | None, notes: list[str]
                ) -> tuple[RockLevels, FocusTiling | None]:
    """Where the scene's rocks go, and the focus tiles when they have two levels."""
    rcfg = config.rocks
    if world is not None and outer is not None:
        return plan_levels(rcfg, outer.heightfield.bounds_xy_m, world.plan.bounds_xy_m,
                           two_level_terrain=True), world.tiling
    tiling = None
    if expected_rocks(hf.area_m2, rcfg, rcfg.d_min_m) > rcfg.max_rocks:
        tiling = rock_focus(hf, config.terrain, notes)
    levels = plan_levels(rcfg, hf.bounds_xy_m,
                         tiling.plan.bounds_xy_m if tiling is not None else None)
    return levels, tiling if levels.two_level else None


def check_rock_budget(config: SceneConfig, *, lod: bool) -> None:
    """Refuse early a procedural scene whose rocks cannot fit ``rocks.max_rocks`` (the rock
    stage's own refusal, a minute earlier on a large scene); only for a scene whose
    ``terrain.lod`` is ``lod`` (:func:`~marsscene.pipeline.build_scene` asks before a one-grid
    terrain, and before a level-of-detail scene's focus tiles: after its focus plan, whose own
    refusal of a focus too large to hold comes first).

    The footprint and focus square are taken 8 posts smaller than the terrain can make them
    (snapping, a focus that does not fit), so this refuses nothing the stage would accept.
    """
    rcfg, tcfg = config.rocks, config.terrain
    if not rcfg.enabled or tcfg.source != "procedural" or bool(tcfg.lod) is not lod:
        return
    w, h = tcfg.effective_size_m
    margin = 8.0 * (tcfg.post_m if tcfg.post_m is not None else 0.25)
    side = max(0.0, min(tcfg.focus_size_m, w, h) - margin)
    plan_levels(rcfg, (0.0, 0.0, max(0.0, w - margin), max(0.0, h - margin)),
                (0.0, 0.0, side, side), two_level_terrain=tcfg.lod is True)


def _place(config: SceneConfig, seed: int, hf: Heightfield, craters: CraterTable,
           world: LodWorld | None, outer: OuterTerrain | None, placed: Any,
           levels: RockLevels, tiling: FocusTiling | None) -> RockTable:
    rcfg = config.rocks
    if tiling is None:  # one level (the scenes that always fitted: unchanged)
        rocks = place_rocks(hf, craters, rcfg, rng=stage_rng(seed, "rocks"))
        return clear_rocks(rocks, placed) if placed else rocks
    focus_hf = hf if world is not None else focus_window(hf, tiling.plan)
    rocks = focus_rocks(focus_hf, tiling, craters, rcfg, seed)
    if world is not None and placed:  # a level-of-detail scene's assets lie in its focus
        rocks = clear_rocks(rocks, placed)
    terrain = outer.heightfield if outer is not None else hf
    rocks = outer_rocks(rocks, terrain, tiling.plan.bounds_xy_m, craters, rcfg, seed,
                        d_min_m=levels.outer_d_min_m)
    if world is None and placed:
        rocks = clear_rocks(rocks, placed)
    return rocks


def rock_stage(config: SceneConfig, seed: int, hf: Heightfield, craters: CraterTable | None,
               world: LodWorld | None, outer: OuterTerrain | None, placed: Any,
               rec: BuildRecord) -> tuple[RockTable, tuple[RockPrototype, ...]]:
    """The scene's rocks and rock prototypes."""
    rcfg = config.rocks
    with rec.stage("rocks"):
        levels, tiling = rock_levels(config, hf, world, outer, rec.notes)
        line = levels.describe(rcfg.d_min_m)
        log.info(line)  # the memory it needs, before placing starts
        prototypes = make_prototypes(rcfg, rng=stage_rng(seed, "rock_shapes"))
        crater_table = craters if craters is not None else CraterTable.empty()
        rocks = _place(config, seed, hf, crater_table, world, outer, placed, levels, tiling)
        rec.models.append(ModelRef("rocks", "Golombek-Rapp rock size-frequency F_k(D) = "
                                   "k exp(-q(k) D), q = 1.79 + 0.152/k", GOLOMBEK_CITATION))
        if rcfg.placement == "ejecta":
            rec.models.append(ModelRef("rocks", "crater-ejecta rock weighting",
                                       EJECTA_CITATION))
        rec.notes.extend(rock_notes(hf, crater_table, rcfg, rocks))
        summary = rock_summary(hf, rcfg, rocks, prototypes)
        rec.summary["rocks"] = summary
        if levels.two_level:
            counts = summary["levels"] = level_summary(levels, rocks)
            rec.notes.append(line)
            log.info("[rocks] %d rocks in the focus square (from %g m), %d outside it (from a "
                     "cut-off of %g m)", counts["focus_count"], rcfg.d_min_m,
                     counts["outer_count"], levels.outer_d_min_m)
    return rocks, prototypes
