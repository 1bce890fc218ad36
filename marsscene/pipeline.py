"""``build_scene``: the only module that wires the stages together, in pipeline order.

DEM / procedural -> terrain (+ sub-DEM detail) -> craters -> rocks -> lighting -> Scene.
Each stage draws from its own random stream (:func:`marsscene.seeding.stage_rng`), so changing
one stage's parameters never changes another stage's random draws.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from marsscene.assets import clear_rocks, place_assets
from marsscene.assets.io import load_assets
from marsscene.config import SceneConfig
from marsscene.craters import crater_models, sample_craters, stamp_craters
from marsscene.craters.config import CraterConfig
from marsscene.craters.population import PopulationStats
from marsscene.craters.table import CraterTable
from marsscene.dem.model import DEM
from marsscene.errors import MarsSceneWarning, NoGeoreferenceWarning
from marsscene.inputs import HIRISE_DTM_CITATION, drape_ortho, load_inputs
from marsscene.lighting.compute import compute_lighting
from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG
from marsscene.lighting.irradiance import AF_CITATION, DELTA_EDDINGTON_CITATION
from marsscene.lighting.mars24 import MARS24_CITATION
from marsscene.rocks import make_prototypes, place_rocks
from marsscene.rocks.config import RockConfig
from marsscene.rocks.report import EJECTA_CITATION, rock_notes, rock_summary
from marsscene.rocks.sfd import GOLOMBEK_CITATION
from marsscene.rocks.table import RockTable
from marsscene.scene import ModelRef, Provenance, Scene
from marsscene.seeding import stage_rng
from marsscene.terrain import add_detail, heightfield_from_dem, resample, synthesize
from marsscene.terrain.config import TerrainConfig
from marsscene.terrain.default import DEFAULT_DEM_CITATION
from marsscene.terrain.from_dem import (
    GeoFrame,
    prepare_dem,
)
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.landforms import LANDFORM_CITATIONS, add_landform, default_size_m
from marsscene.terrain.lod import (
    FocusPlan,
    OuterTerrain,
    concat_tables,
    lod_summary,
    merge_craters,
    plan_focus,
    stitch,
    synthesize_focus,
    taper_detail,
)

__all__ = ["build_scene"]

log = logging.getLogger("marsscene")

_FBM_CITATION = (
    "fractional Brownian surface by spectral synthesis (Saupe 1988; Turcotte 1997, "
    "doi:10.1017/CBO9781139174695); Mars self-affinity: Orosei et al. 2003, "
    "doi:10.1029/2002JE001883"
)


_LOD_DEM_NOTE = ("terrain: terrain.lod is ignored with a DEM (level-of-detail DEM terrain is not "
                 "implemented yet): one heightfield at post_m")


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


def _warn_no_georeference(dem: DEM, config: SceneConfig) -> None:
    lcfg = config.lighting
    sun = ""
    if lcfg.enabled and (lcfg.site_lat_deg is None or lcfg.site_lon_east_deg is None):
        lat, lon = DEFAULT_SITE_LAT_LON_EAST_DEG
        sun = (f"; the sun uses the default site (lat {lat}, lon {lon} E) unless "
               "lighting.site_lat_deg and lighting.site_lon_east_deg are set")
    name = Path(str(dem.source_path)).name if dem.source_path else "the DEM"
    warnings.warn(f"{name} has no geo-reference (no CRS): the scene has no lon/lat{sun}",
                  NoGeoreferenceWarning, stacklevel=3)


def _lod_terrain(tcfg: TerrainConfig, seed: int) -> tuple[Heightfield, Heightfield, FocusPlan]:
    """Level-of-detail terrain: (focus heightfield, coarse footprint, focus plan)."""
    size = tcfg.effective_size_m
    lf_size = tcfg.landform_size_m if tcfg.landform_size_m is not None else \
        default_size_m(tcfg.landform, min(size))
    coarse = synthesize(size, tcfg.post_m if tcfg.post_m is not None else 1.0, hurst=tcfg.hurst,
                        rms_height_m=tcfg.rms_height_m, rms_slope_deg=tcfg.rms_slope_deg,
                        rng=stage_rng(seed, "terrain"))
    plan = plan_focus(coarse, center_xy_m=tcfg.focus_xy_m, size_m=tcfg.focus_size_m,
                      fine_post_m=tcfg.focus_post_m)
    fine = synthesize_focus(plan, hurst=tcfg.hurst, rms_height_m=tcfg.rms_height_m,
                            rms_slope_deg=tcfg.rms_slope_deg, rng=stage_rng(seed, "terrain_focus"))
    coarse, fine = (add_landform(h, tcfg.landform, size_m=lf_size, depth_m=tcfg.landform_depth_m)
                    for h in (coarse, fine))
    return fine, coarse, plan


def _lod_craters(hf: Heightfield, coarse: Heightfield, plan: FocusPlan, ccfg: CraterConfig,
                 seed: int) -> tuple[Heightfield, Heightfield, CraterTable, PopulationStats]:
    """Craters of a level-of-detail scene: the focus square samples its own craters."""
    focus, _ = sample_craters(plan.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters_focus"),
                              heightfield=hf)
    outer, stats = sample_craters(coarse.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters"),
                                  heightfield=coarse)
    table = merge_craters(focus, outer, plan.bounds_xy_m, ejecta_reach=ccfg.ejecta_reach,
                          axis_ratio_min=ccfg.axis_ratio_min)
    kwargs = ccfg.profile_kwargs()
    return (stamp_craters(hf, focus, profile_kwargs=kwargs),
            stamp_craters(coarse, table, profile_kwargs=kwargs), table, stats)


def _outer_rocks(rocks: RockTable, outer: OuterTerrain, craters: CraterTable, rcfg: RockConfig,
                 seed: int) -> RockTable:
    """Add rocks of at least ``rocks.outer_d_min_m`` outside the focus square."""
    d_min = max(rcfg.d_min_m, rcfg.outer_d_min_m)
    if d_min >= rcfg.d_max_m:
        return rocks
    cfg = dataclasses.replace(rcfg, d_min_m=d_min)
    far = place_rocks(outer.heightfield, craters, cfg, rng=stage_rng(seed, "rocks_outer"))
    x0, y0, x1, y1 = outer.focus_bounds_xy_m
    x, y = far.position_xyz_m[:, 0], far.position_xyz_m[:, 1]
    result: RockTable = concat_tables(rocks, far.take(~((x >= x0) & (x <= x1) & (y >= y0)
                                                        & (y <= y1))))
    return result


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

    texture_rgb = None
    plan: FocusPlan | None = None
    coarse: Heightfield | None = None  # the outer grid of a level-of-detail terrain
    with timer.stage("terrain"):
        dem, inputs = load_inputs(config, dem)
        if dem is None and tcfg.lod:
            hf, coarse, plan = _lod_terrain(tcfg, seed)
            frame = GeoFrame(0.0, None, None, "", 1.0)
            models.append(ModelRef("terrain", "procedural fBm terrain", _FBM_CITATION))
            if tcfg.landform in LANDFORM_CITATIONS:
                models.append(ModelRef("terrain", f"{tcfg.landform} landform",
                                       LANDFORM_CITATIONS[tcfg.landform]))
        elif dem is None:
            hf = synthesize(
                tcfg.effective_size_m,
                tcfg.post_m if tcfg.post_m is not None else 0.25,
                hurst=tcfg.hurst,
                rms_height_m=tcfg.rms_height_m,
                rms_slope_deg=tcfg.rms_slope_deg,
                rng=stage_rng(seed, "terrain"),
            )
            hf = add_landform(hf, tcfg.landform, size_m=tcfg.landform_size_m,
                              depth_m=tcfg.landform_depth_m)
            if tcfg.landform in LANDFORM_CITATIONS:
                models.append(ModelRef("terrain", f"{tcfg.landform} landform",
                                       LANDFORM_CITATIONS[tcfg.landform]))
            frame = GeoFrame(0.0, None, None, "", 1.0)
            models.append(ModelRef("terrain", "procedural fBm terrain", _FBM_CITATION))
        else:
            default_post = 0.25 if tcfg.source == "default" else None
            if tcfg.lod:
                notes.append(_LOD_DEM_NOTE)
                log.warning(_LOD_DEM_NOTE)
            dem, post_m, dem_notes, dem_summary = prepare_dem(
                dem, tcfg, default_post_m=default_post
            )
            notes.extend(dem_notes)
            if "data_file" in dem.metadata:  # the .IMG of a detached .LBL
                inputs["dem_data"] = str(dem.metadata["data_file"])
            summary.update(dem_summary)
            hf, frame = heightfield_from_dem(dem, z_scale=tcfg.z_scale)
            if not frame.crs_wkt:
                _warn_no_georeference(dem, config)
            if tcfg.source == "default":
                models.append(ModelRef("terrain", "default DEM", DEFAULT_DEM_CITATION))
            if "HIRISE" in str(dem.metadata.get("DATA_SET_ID", "")).upper():
                dataset = str(dem.metadata["DATA_SET_ID"])
                models.append(ModelRef("terrain", dataset, HIRISE_DTM_CITATION))
            if post_m < hf.cell_size_m * (1 - 1e-9):
                if tcfg.detail:
                    hf = add_detail(
                        hf,
                        post_m=post_m,
                        hurst=tcfg.hurst,
                        detail_rms_m=tcfg.detail_rms_m,
                        rng=stage_rng(seed, "terrain_detail"),
                    )
                    models.append(ModelRef("terrain", "sub-DEM fractal detail", _FBM_CITATION))
                else:
                    hf = resample(hf, post_m=post_m)
            if frame.crs_wkt:
                from marsscene.dem.crs import iau_2015_code

                summary["crs_iau_2015"] = iau_2015_code(frame.crs_wkt)
                summary["grid_convergence_deg"] = frame.grid_convergence_deg
            texture_rgb = drape_ortho(tcfg, dem, hf, frame, inputs, notes, summary)

    # --- craters stage (issue: craters) ---------------------------------------------------
    craters = None
    ccfg = config.craters
    if ccfg.enabled:
        with timer.stage("craters"), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MarsSceneWarning)
            if plan is not None and coarse is not None:
                hf, coarse, craters, cstats = _lod_craters(hf, coarse, plan, ccfg, seed)
            else:
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
    if plan is not None:
        hf = taper_detail(hf, plan)  # the focus border now lies on the coarse surface

    placed = None
    if config.assets.active:
        with timer.stage("assets"):
            hf, placed = place_assets(hf, load_assets(config.assets), config.assets)
            summary["assets"] = [{"name": a.model.name, "xy_m": [round(v, 3) for v in a.xy_m],
                                  "base_z_m": round(a.base_z_m, 4),
                                  "pad_radius_m": round(a.pad_radius_m, 3)} for a in placed]
    outer = None
    if plan is not None and coarse is not None:
        with timer.stage("stitch"):
            outer = OuterTerrain(stitch(coarse, hf, plan, blend_m=tcfg.lod_blend_m),
                                 plan.bounds_xy_m)
            summary["lod"] = lod_summary(hf, outer, tcfg)

    # --- rocks stage (issue: rocks) -------------------------------------------------------
    rocks = None
    rock_prototypes = None
    if config.rocks.enabled:
        with timer.stage("rocks"):
            rcfg = config.rocks
            rock_prototypes = make_prototypes(rcfg, rng=stage_rng(seed, "rock_shapes"))
            crater_table = craters if craters is not None else CraterTable.empty()
            rocks = place_rocks(hf, crater_table, rcfg, rng=stage_rng(seed, "rocks"))
            rocks = clear_rocks(rocks, placed) if placed else rocks
            if outer is not None:
                rocks = _outer_rocks(rocks, outer, crater_table, rcfg, seed)
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
