"""``build_scene``: the only module that wires the stages together, in pipeline order.

DEM / procedural -> terrain (+ sub-DEM detail) -> craters -> [level of detail: focus tiles]
-> assets -> [level of detail: stitch] -> rocks -> lighting -> Scene. The terrain stage is
:mod:`marsscene.pipeline_terrain`; the level-of-detail stages are :mod:`marsscene.pipeline_lod`.
Each stage draws from its own random stream (:func:`marsscene.seeding.stage_rng`), so changing
one stage's parameters never changes another stage's random draws.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

from marsscene.assets import clear_rocks, place_assets
from marsscene.assets.io import load_assets
from marsscene.config import SceneConfig
from marsscene.craters import crater_models, sample_craters, stamp_craters
from marsscene.craters.table import CraterTable
from marsscene.dem.model import DEM
from marsscene.errors import MarsSceneWarning
from marsscene.lighting.compute import compute_lighting
from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG
from marsscene.lighting.irradiance import AF_CITATION, DELTA_EDDINGTON_CITATION
from marsscene.lighting.mars24 import MARS24_CITATION
from marsscene.pipeline_terrain import terrain_stage
from marsscene.rocks import make_prototypes, place_rocks
from marsscene.rocks.report import EJECTA_CITATION, rock_notes, rock_summary
from marsscene.rocks.sfd import GOLOMBEK_CITATION
from marsscene.scene import ModelRef, Provenance, Scene
from marsscene.seeding import stage_rng
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import OuterTerrain, lod_summary, stitch

__all__ = ["build_scene"]

log = logging.getLogger("marsscene")


class _Timer:
    def __init__(self) -> None:
        self.timings_s: dict[str, float] = {}

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        log.info("[%s] ...", name)
        t0 = time.perf_counter()
        yield
        dt = time.perf_counter() - t0
        self.timings_s[name] = round(dt, 4)
        log.info("[%s] done in %.2f s", name, dt)


def build_scene(config: SceneConfig | None = None, *, seed: int, dem: DEM | None = None) -> Scene:
    """Build a Mars scene.

    Parameters
    ----------
    config : SceneConfig, optional
        Stage parameters (defaults: the bundled Gale crater DEM at 0.25 m with detail).
    seed : int
        User seed; every stage derives its own stream from it.
    dem : DEM, optional
        An already-read DEM; overrides ``config.terrain.source``.

    Returns
    -------
    Scene

    Examples
    --------
    >>> import marsscene as ms
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> scene = ms.build_scene(cfg, seed=7)
    >>> scene.heightfield.shape
    (81, 81)
    """
    config = config if config is not None else SceneConfig()
    tcfg = config.terrain
    timer = _Timer()
    models: list[ModelRef] = []  # every model used, with its citation (manifest)
    notes: list[str] = []  # rules applied and warnings (manifest)
    summary: dict[str, object] = {}  # stage summary values: counts, tau, ... (manifest)

    with timer.stage("terrain"):
        terrain = terrain_stage(config, seed, dem, models, notes, summary)
    frame, inputs, texture_rgb, world = (terrain.frame, terrain.inputs, terrain.texture_rgb,
                                         terrain.world)
    coarse: Heightfield | None = world.coarse if world is not None else None

    # --- craters stage (issue: craters) ---------------------------------------------------
    craters = None
    ccfg = config.craters
    if ccfg.enabled:
        with timer.stage("craters"), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MarsSceneWarning)
            if world is not None:
                from marsscene.pipeline_lod import lod_craters

                coarse, craters, cstats = lod_craters(world, ccfg, seed)
            else:
                assert terrain.hf is not None
                hf = terrain.hf
                craters, cstats = sample_craters(
                    hf.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters"), heightfield=hf,
                    origin_lonlat_deg=frame.origin_lonlat_deg,
                    grid_convergence_deg=frame.grid_convergence_deg,
                )
                hf = stamp_craters(hf, craters, profile_kwargs=ccfg.profile_kwargs())
        for w in caught:  # re-emit once each, and record in the manifest
            msg = f"craters: {w.message}"
            if msg not in notes:
                notes.append(msg)
                warnings.warn(str(w.message), w.category, stacklevel=2)
        models.extend(ModelRef("craters", n, c) for n, c in crater_models(ccfg))
        summary["craters"] = {
            "count": len(craters),
            "expected_in_scene": round(cstats.expected_in_scene, 3),
            "sampled_over_grown_area": cstats.sampled,
            "erased_by_resurfacing": cstats.resurfaced,
            "degraded_away": cstats.degraded_away,
            "d_range_m": [ccfg.d_min_m, ccfg.d_max_m],
            "system": ccfg.system,
            "age_ga": ccfg.age_ga,
        }

    # --- end of craters stage -------------------------------------------------------------
    if world is not None:  # the focus square, tile by tile, now that the craters are known
        from marsscene.pipeline_lod import focus_heightfield

        with timer.stage("tiles"):
            hf = focus_heightfield(world, craters, ccfg if craters is not None else None)
    elif craters is None:
        assert terrain.hf is not None
        hf = terrain.hf

    placed = None
    if config.assets.active:
        with timer.stage("assets"):
            hf, placed = place_assets(hf, load_assets(config.assets), config.assets)
            summary["assets"] = [{"name": a.model.name, "xy_m": [round(v, 3) for v in a.xy_m],
                                  "base_z_m": round(a.base_z_m, 4),
                                  "pad_radius_m": round(a.pad_radius_m, 3)} for a in placed]
    outer = None
    if world is not None and coarse is not None:
        with timer.stage("stitch"):
            outer = OuterTerrain(stitch(coarse, hf, world.plan, blend_m=tcfg.lod_blend_m),
                                 world.plan.bounds_xy_m)
            tiling = world.tiling
            summary["lod"] = lod_summary(hf, outer, tcfg, tiles=tiling.count,
                                         tile_m=tiling.tile_cells * world.plan.coarse_post_m,
                                         detail_rms_m=world.detail.rms_m)

    # --- rocks stage (issue: rocks) -------------------------------------------------------
    rocks = None
    rock_prototypes = None
    if config.rocks.enabled:
        with timer.stage("rocks"):
            rcfg = config.rocks
            rock_prototypes = make_prototypes(rcfg, rng=stage_rng(seed, "rock_shapes"))
            crater_table = craters if craters is not None else CraterTable.empty()
            if world is not None and outer is not None:
                from marsscene.pipeline_lod import focus_rocks, outer_rocks

                rocks = focus_rocks(hf, world.tiling, crater_table, rcfg, seed)
                rocks = clear_rocks(rocks, placed) if placed else rocks
                rocks = outer_rocks(rocks, outer, crater_table, rcfg, seed)
            else:
                rocks = place_rocks(hf, crater_table, rcfg, rng=stage_rng(seed, "rocks"))
                rocks = clear_rocks(rocks, placed) if placed else rocks
            models.append(ModelRef("rocks", "Golombek-Rapp rock size-frequency F_k(D) = "
                                   "k exp(-q(k) D), q = 1.79 + 0.152/k", GOLOMBEK_CITATION))
            if rcfg.placement == "ejecta":
                models.append(ModelRef("rocks", "crater-ejecta rock weighting",
                                       EJECTA_CITATION))
            notes.extend(rock_notes(hf, crater_table, rcfg, rocks))
            summary["rocks"] = rock_summary(hf, rcfg, rocks, rock_prototypes)

    # --- end of rocks stage ---------------------------------------------------------------

    # --- lighting stage (issue: lighting) -------------------------------------------------
    lighting = None
    lcfg = config.lighting
    if lcfg.enabled:
        with timer.stage("lighting"):  # deterministic: no random draws in this stage
            if lcfg.site_lat_deg is not None and lcfg.site_lon_east_deg is not None:
                lat_deg, lon_e_deg, site_src = lcfg.site_lat_deg, lcfg.site_lon_east_deg, "config"
            elif frame.origin_lonlat_deg is not None:
                lon_e_deg, lat_deg = frame.origin_lonlat_deg
                site_src = "DEM centre"
            else:
                lat_deg, lon_e_deg = DEFAULT_SITE_LAT_LON_EAST_DEG
                site_src = "default site (Jezero)"
            lighting = compute_lighting(lcfg, lat_deg=lat_deg, lon_east_deg=lon_e_deg,
                                        grid_convergence_deg=frame.grid_convergence_deg)
            if lcfg.sun_mode in ("utc", "local"):
                models.append(ModelRef("lighting", "Mars24 sun position", MARS24_CITATION))
            diffuse_ref = DELTA_EDDINGTON_CITATION if lcfg.diffuse_model == "delta_eddington" \
                else AF_CITATION
            models.append(ModelRef("lighting", f"Beer's-law sun + {lcfg.diffuse_model} sky",
                                   diffuse_ref))
            notes.append(
                f"lighting: sun from {lcfg.sun_mode} at {site_src} "
                f"(lat {lat_deg:.4f}, lon {lon_e_deg % 360.0:.4f} E)"
            )
            if lighting.sun_elevation_deg <= 0.0:
                notes.append("lighting: the sun is below the horizon (no direct or diffuse light)")
            summary.update({
                "lighting_tau": lighting.tau,
                "lighting_sun_azimuth_deg": round(lighting.sun_azimuth_deg, 6),
                "lighting_sun_elevation_deg": round(lighting.sun_elevation_deg, 6),
                "lighting_direct_normal_w_m2": round(lighting.direct_normal_w_m2, 4),
                "lighting_diffuse_horizontal_w_m2": round(lighting.diffuse_horizontal_w_m2, 4),
                "lighting_visibility_m": round(lighting.visibility_m, 1)
                if lighting.visibility_m != float("inf") else None,
            })

    # --- end of lighting stage ------------------------------------------------------------

    provenance = Provenance(
        frame=frame,
        inputs=inputs,
        models=tuple(models),
        timings_s=timer.timings_s,
        notes=tuple(notes),
        extra=summary,
    )
    return Scene(
        heightfield=hf,
        texture_rgb=texture_rgb,
        config=config,
        seed=seed,
        provenance=provenance,
        craters=craters,
        rocks=rocks,
        rock_prototypes=rock_prototypes,
        lighting=lighting,
        assets=placed,
        outer=outer,
    )
