"""The crater stage: sample the crater population and stamp it into the terrain (or, on a
level-of-detail world, into its coarse grid; the focus tiles are stamped later)."""

from __future__ import annotations

import warnings

from marsscene.config import SceneConfig
from marsscene.craters import crater_models, sample_craters, stamp_craters
from marsscene.craters.population import PopulationStats
from marsscene.craters.table import CraterTable
from marsscene.errors import MarsSceneWarning
from marsscene.pipeline.record import BuildRecord
from marsscene.pipeline.terrain import TerrainStage
from marsscene.scene import ModelRef
from marsscene.seeding import stage_rng
from marsscene.terrain.heightfield import Heightfield

__all__ = ["crater_stage"]


def crater_stage(config: SceneConfig, seed: int, terrain: TerrainStage, rec: BuildRecord
                 ) -> tuple[Heightfield | None, Heightfield | None, CraterTable]:
    """Craters of the scene; returns ``(stamped terrain or None on a LOD world, the coarse
    LOD grid with its craters or None, the crater table)``."""
    ccfg = config.craters
    world, hf, coarse = terrain.world, None, None
    with rec.stage("craters"), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MarsSceneWarning)
        if world is not None:
            from marsscene.pipeline.lod import lod_craters

            coarse, craters, cstats = lod_craters(world, ccfg, seed)
        else:
            assert terrain.hf is not None
            frame = terrain.frame
            craters, cstats = sample_craters(
                terrain.hf.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters"),
                heightfield=terrain.hf, origin_lonlat_deg=frame.origin_lonlat_deg,
                grid_convergence_deg=frame.grid_convergence_deg,
            )
            hf = stamp_craters(terrain.hf, craters, profile_kwargs=ccfg.profile_kwargs())
    for w in caught:  # re-emit once each, and record in the manifest
        msg = f"craters: {w.message}"
        if msg not in rec.notes:
            rec.notes.append(msg)
            warnings.warn(str(w.message), w.category, stacklevel=3)
    rec.models.extend(ModelRef("craters", n, c) for n, c in crater_models(ccfg))
    rec.summary["craters"] = _summary(config, craters, cstats)
    return hf, coarse, craters


def _summary(config: SceneConfig, craters: CraterTable, cstats: PopulationStats
             ) -> dict[str, object]:
    ccfg = config.craters
    return {
        "count": len(craters),
        "expected_in_scene": round(cstats.expected_in_scene, 3),
        "sampled_over_grown_area": cstats.sampled,
        "erased_by_resurfacing": cstats.resurfaced,
        "degraded_away": cstats.degraded_away,
        "d_range_m": [ccfg.d_min_m, ccfg.d_max_m],
        "system": ccfg.system,
        "age_ga": ccfg.age_ga,
    }
