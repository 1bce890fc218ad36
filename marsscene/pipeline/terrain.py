"""The terrain stage of :func:`marsscene.build_scene`: a DEM, a procedural terrain, or the
level-of-detail world (:mod:`marsscene.pipeline.lod`) whose focus tiles are built after the
crater table exists."""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from marsscene.config import SceneConfig
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError, NoGeoreferenceWarning
from marsscene.landforms import LANDFORM_CITATIONS, add_landform
from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG
from marsscene.pipeline.inputs import HIRISE_DTM_CITATION, drape_ortho, load_inputs
from marsscene.scene import ModelRef
from marsscene.seeding import stage_rng
from marsscene.terrain import add_detail, heightfield_from_dem, resample, synthesize
from marsscene.terrain.default import DEFAULT_DEM_CITATION
from marsscene.terrain.from_dem import GeoFrame, prepare_dem
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lattice import LATTICE_CITATION

if TYPE_CHECKING:
    from marsscene.pipeline.lod import LodWorld

__all__ = ["TerrainStage", "lod_inputs", "resolve_lod", "terrain_stage"]

#: Outer-level posts an automatic level-of-detail terrain aims at (main-crater: 13 M), and the
#: largest side of its focus square in posts (4000: 1 km at 0.25 m, 16 M posts).
AUTO_OUTER_POSTS = 16_000_000
AUTO_FOCUS_POSTS_PER_SIDE = 4000
#: Posts above which ``terrain.lod = "auto"`` gives a procedural terrain two levels (a 1.58 km
#: square at 0.25 m). Measured on the 2-core machine (python perf/run.py scene_sizes): one 2 km
#: grid built in 52.5 s at 2.76 GB peak, two levels in 41.8 s at 1.16 GB; one 2.5 km grid 104.5 s at
#: 3.87 GB, two levels 48.5 s at 1.14 GB. ``--no-lod`` keeps one grid up to ``MAX_POSTS``.
AUTO_ONE_GRID_POSTS = 40_000_000

_FBM_CITATION = (
    "fractional Brownian surface by spectral synthesis (Saupe 1988; Turcotte 1997, "
    "doi:10.1017/CBO9781139174695); Mars self-affinity: Orosei et al. 2003, "
    "doi:10.1029/2002JE001883"
)


def _warn_no_georeference(dem: DEM, config: SceneConfig) -> None:
    lcfg = config.lighting
    sun = ""
    if lcfg.enabled and (lcfg.site_lat_deg is None or lcfg.site_lon_east_deg is None):
        lat, lon = DEFAULT_SITE_LAT_LON_EAST_DEG
        sun = (f"; the sun uses the default site (lat {lat}, lon {lon} E) unless "
               "lighting.site_lat_deg and lighting.site_lon_east_deg are set")
    name = Path(str(dem.source_path)).name if dem.source_path else "the DEM"
    warnings.warn(f"{name} has no geo-reference (no CRS): the scene has no lon/lat{sun}",
                  NoGeoreferenceWarning, stacklevel=5)  # build_scene's caller


_PROCEDURAL = GeoFrame(0.0, None, None, "", 1.0)


@dataclass(eq=False)
class TerrainStage:
    """The terrain stage's result: one heightfield, or the level-of-detail world whose focus
    tiles are built after the crater table exists."""

    hf: Heightfield | None
    frame: GeoFrame
    inputs: dict[str, str]
    texture_rgb: Any = None
    world: LodWorld | None = None


def _procedural(config: SceneConfig, seed: int) -> Heightfield:
    tcfg = config.terrain
    hf = synthesize(tcfg.effective_size_m, tcfg.post_m if tcfg.post_m is not None else 0.25,
                    hurst=tcfg.hurst, rms_height_m=tcfg.rms_height_m,
                    rms_slope_deg=tcfg.rms_slope_deg, rng=stage_rng(seed, "terrain"))
    return add_landform(hf, tcfg.landform, size_m=tcfg.landform_size_m,
                        depth_m=tcfg.landform_depth_m)


def _dem_terrain(config: SceneConfig, seed: int, dem: DEM, inputs: dict[str, str],
                 models: list[ModelRef], notes: list[str], summary: dict[str, object]
                 ) -> tuple[Heightfield, GeoFrame, float]:
    """The DEM as a heightfield at its own posts (after fill/crop/resample), the frame and the
    target post spacing."""
    tcfg = config.terrain
    default_post = 0.25 if tcfg.source == "default" else None
    if tcfg.lod:  # the focus uses the DEM's own posts; the outer level averages them itself
        tcfg, default_post = dataclasses.replace(tcfg, post_m=None), None
    dem, post_m, dem_notes, dem_summary = prepare_dem(dem, tcfg, default_post_m=default_post)
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
        models.append(ModelRef("terrain", str(dem.metadata["DATA_SET_ID"]), HIRISE_DTM_CITATION))
    if frame.crs_wkt:
        from marsscene.dem.crs import iau_2015_code

        summary["crs_iau_2015"] = iau_2015_code(frame.crs_wkt)
        summary["grid_convergence_deg"] = frame.grid_convergence_deg
    return hf, frame, post_m


def terrain_stage(config: SceneConfig, seed: int, dem: DEM | None, models: list[ModelRef],
                   notes: list[str], summary: dict[str, object]) -> TerrainStage:
    tcfg = config.terrain
    averaged = None
    if tcfg.lod and dem is None:  # a whole DTM: the outer level read averaged, strip by strip
        from marsscene.pipeline.dem_lod import read_averaged_outer

        averaged = read_averaged_outer(config)
    if averaged is not None:
        dem, inputs = averaged.dem, dict(averaged.inputs)
        notes.append(f"terrain: outer level read averaged to {averaged.dem.post_m:g} m posts "
                     "strip by strip; the focus window read at the DEM's posts")
    else:
        dem, inputs = load_inputs(config, dem)
    if dem is None:
        models.append(ModelRef("terrain", "procedural fBm terrain", _FBM_CITATION))
        if tcfg.landform in LANDFORM_CITATIONS:
            models.append(ModelRef("terrain", f"{tcfg.landform} landform",
                                   LANDFORM_CITATIONS[tcfg.landform]))
        if tcfg.lod:
            from marsscene.pipeline.lod import lod_world

            models.append(ModelRef("terrain", "sub-post pointwise fractal detail (tiles)",
                                   LATTICE_CITATION))
            return TerrainStage(None, _PROCEDURAL, inputs,
                                world=lod_world(tcfg, seed, notes=notes))
        return TerrainStage(_procedural(config, seed), _PROCEDURAL, inputs)
    hf, frame, post_m = _dem_terrain(config, seed, dem, inputs, models, notes, summary)
    world: LodWorld | None = None
    if tcfg.lod:
        from marsscene.pipeline.lod import lod_world

        reader = averaged.base_reader(config, frame) if averaged is not None else None
        world = lod_world(tcfg, seed, dem_hf=hf, notes=notes, base_reader=reader)
        p, n = world.plan, world.plan.cells  # the ortho is draped over the focus square
        hf = Heightfield(world.coarse.z_m[p.row0:p.row0 + n + 1, p.col0:p.col0 + n + 1],
                         p.coarse_post_m, p.bounds_xy_m[:2])
        if world.detail.rms_m > 0:
            models.append(ModelRef("terrain", "sub-DEM pointwise fractal detail (tiles)",
                                   LATTICE_CITATION))
    elif post_m < hf.cell_size_m * (1 - 1e-9):
        if tcfg.detail:
            hf = add_detail(hf, post_m=post_m, hurst=tcfg.hurst, detail_rms_m=tcfg.detail_rms_m,
                            rng=stage_rng(seed, "terrain_detail"))
            models.append(ModelRef("terrain", "sub-DEM fractal detail", _FBM_CITATION))
        else:
            hf = resample(hf, post_m=post_m)
    texture = drape_ortho(tcfg, dem, hf, frame, inputs, notes, summary)
    return TerrainStage(None if world else hf, frame, inputs, texture, world)


def resolve_lod(config: SceneConfig, dem: DEM | None = None) -> tuple[SceneConfig, str | None]:
    """``terrain.lod = "auto"`` made true or false, and the note saying why when true.

    A procedural terrain whose full-resolution grid would hold more than
    :data:`AUTO_ONE_GRID_POSTS` posts gets two levels: its ``post_m`` inside the
    ``focus_size_m`` square, and the smallest whole multiple of it outside that keeps the outer
    grid under :data:`AUTO_OUTER_POSTS`. A DEM scene is decided from the DEM's header by
    :func:`marsscene.pipeline.dem_lod.resolve_dem_lod`: a crop that one grid would refuse gets
    the DEM's posts in the focus square and the DEM averaged to the smallest whole multiple of
    them outside (and ``lod = true`` without ``post_m`` gets that outer level when the DEM's own
    posts would be refused). Everything else keeps one grid.
    """
    import math

    from marsscene.terrain.synth import MAX_POSTS

    tcfg = config.terrain
    if dem is not None or tcfg.source != "procedural":
        from marsscene.pipeline.dem_lod import LodBudget, resolve_dem_lod

        return resolve_dem_lod(config, dem, LodBudget(MAX_POSTS, AUTO_OUTER_POSTS,
                                                      AUTO_FOCUS_POSTS_PER_SIDE))
    if tcfg.lod != "auto":
        return config, None
    post = tcfg.post_m if tcfg.post_m is not None else 0.25
    w, h = tcfg.effective_size_m
    posts = (round(w / post) + 1) * (round(h / post) + 1)
    if posts <= AUTO_ONE_GRID_POSTS:
        return config.replace(terrain=dataclasses.replace(tcfg, lod=False)), None
    k = max(2, math.ceil(math.sqrt(posts / AUTO_OUTER_POSTS)))
    focus = min(tcfg.focus_size_m, w, h, AUTO_FOCUS_POSTS_PER_SIDE * post)
    lod = dataclasses.replace(tcfg, lod=True, focus_post_m=post, post_m=post * k,
                              focus_size_m=focus)
    note = (f"terrain: a {w:g} x {h:g} m grid at {post:g} m posts would hold {posts:,} posts "
            f"(one grid up to {AUTO_ONE_GRID_POSTS:,}), so the terrain has two levels "
            f"(terrain.lod = \"auto\"): "
            f"{post:g} m posts in the central {focus:g} m square (move it with --focus-xy), "
            f"{post * k:g} m outside; --no-lod insists on one grid")
    return config.replace(terrain=lod), note


def lod_inputs(config: SceneConfig, seed: int, dem: DEM | None = None
               ) -> tuple[LodWorld, GeoFrame]:
    """The level-of-detail world of ``config`` (the terrain stage alone)."""
    config, _ = resolve_lod(config, dem)
    if not config.terrain.lod:
        raise ConfigError("a focus tile needs terrain.lod = true")
    t = terrain_stage(config, seed, dem, [], [], {})
    assert t.world is not None
    return t.world, t.frame
