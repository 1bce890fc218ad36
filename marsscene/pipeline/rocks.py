"""The rock stage: prototypes, then rocks placed over the terrain (tile by tile in the focus of
a level-of-detail world, then the outer level), cleared from asset pads."""

from __future__ import annotations

from typing import Any

from marsscene.assets import clear_rocks
from marsscene.config import SceneConfig
from marsscene.craters.table import CraterTable
from marsscene.pipeline.lod import LodWorld
from marsscene.pipeline.record import BuildRecord
from marsscene.rocks import make_prototypes, place_rocks
from marsscene.rocks.report import EJECTA_CITATION, rock_notes, rock_summary
from marsscene.rocks.sfd import GOLOMBEK_CITATION
from marsscene.rocks.shapes import RockPrototype
from marsscene.rocks.table import RockTable
from marsscene.scene import ModelRef
from marsscene.seeding import stage_rng
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import OuterTerrain

__all__ = ["rock_stage"]


def rock_stage(config: SceneConfig, seed: int, hf: Heightfield, craters: CraterTable | None,
               world: LodWorld | None, outer: OuterTerrain | None, placed: Any,
               rec: BuildRecord) -> tuple[RockTable, tuple[RockPrototype, ...]]:
    """The scene's rocks and rock prototypes."""
    rcfg = config.rocks
    with rec.stage("rocks"):
        prototypes = make_prototypes(rcfg, rng=stage_rng(seed, "rock_shapes"))
        crater_table = craters if craters is not None else CraterTable.empty()
        if world is not None and outer is not None:
            from marsscene.pipeline.lod import focus_rocks, outer_rocks

            rocks = focus_rocks(hf, world.tiling, crater_table, rcfg, seed)
            rocks = clear_rocks(rocks, placed) if placed else rocks
            rocks = outer_rocks(rocks, outer, crater_table, rcfg, seed)
        else:
            rocks = place_rocks(hf, crater_table, rcfg, rng=stage_rng(seed, "rocks"))
            rocks = clear_rocks(rocks, placed) if placed else rocks
        rec.models.append(ModelRef("rocks", "Golombek-Rapp rock size-frequency F_k(D) = "
                                   "k exp(-q(k) D), q = 1.79 + 0.152/k", GOLOMBEK_CITATION))
        if rcfg.placement == "ejecta":
            rec.models.append(ModelRef("rocks", "crater-ejecta rock weighting",
                                       EJECTA_CITATION))
        rec.notes.extend(rock_notes(hf, crater_table, rcfg, rocks))
        rec.summary["rocks"] = rock_summary(hf, rcfg, rocks, prototypes)
    return rocks, prototypes
