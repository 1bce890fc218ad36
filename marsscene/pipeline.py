"""``build_scene``: the only module that wires the stages together, in pipeline order.

DEM / procedural -> terrain (+ sub-DEM detail) -> craters -> rocks -> lighting -> Scene.
Each stage draws from its own random stream (:func:`marsscene.seeding.stage_rng`), so changing
one stage's parameters never changes another stage's random draws.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

from marsscene.config import SceneConfig
from marsscene.craters import crater_models, sample_craters, stamp_craters
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError, MarsSceneWarning
from marsscene.scene import ModelRef, Provenance, Scene
from marsscene.seeding import stage_rng
from marsscene.terrain import add_detail, heightfield_from_dem, resample, synthesize
from marsscene.terrain.default import DEFAULT_DEM_CITATION, default_dem_path
from marsscene.terrain.from_dem import GeoFrame

__all__ = ["build_scene"]

log = logging.getLogger("marsscene")

_FBM_CITATION = (
    "fractional Brownian surface by spectral synthesis (Saupe 1988; Turcotte 1997, "
    "doi:10.1017/CBO9781139174695); Mars self-affinity: Orosei et al. 2003, doi:10.1029/2002JE001883"
)


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


def _load_dem(config: SceneConfig, dem: DEM | None) -> tuple[DEM | None, dict[str, str]]:
    if dem is not None:
        return dem, ({"dem": dem.source_path} if dem.source_path else {})
    src = config.terrain.source
    if src == "procedural":
        return None, {}
    from marsscene.dem.io import read_dem  # rasterio is imported only when a DEM is read

    path = default_dem_path() if src == "default" else config.terrain.dem_path
    if path is None:  # pragma: no cover - TerrainConfig validation forbids it
        raise ConfigError('terrain.source = "dem" needs terrain.dem_path')
    return read_dem(path), {"dem": str(path)}


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
        dem, inputs = _load_dem(config, dem)
        if dem is None:
            post_m = tcfg.post_m if tcfg.post_m is not None else 0.25
            hf = synthesize(
                tcfg.effective_size_m,
                post_m,
                hurst=tcfg.hurst,
                rms_height_m=tcfg.rms_height_m,
                rms_slope_deg=tcfg.rms_slope_deg,
                rng=stage_rng(seed, "terrain"),
            )
            frame = GeoFrame(0.0, None, None, "", 1.0)
            models.append(ModelRef("terrain", "procedural fBm terrain", _FBM_CITATION))
        else:
            hf, frame = heightfield_from_dem(dem, z_scale=tcfg.z_scale)
            if tcfg.source == "default":
                models.append(ModelRef("terrain", "default DEM", DEFAULT_DEM_CITATION))
            post_m = tcfg.post_m
            if tcfg.source == "default" and post_m is None:
                post_m = 0.25
            if post_m is not None and abs(post_m - hf.cell_size_m) > 1e-9 * hf.cell_size_m:
                if tcfg.detail and post_m < hf.cell_size_m:
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

    # --- craters stage (issue: craters) ---------------------------------------------------
    craters = None
    ccfg = config.craters
    if ccfg.enabled:
        with timer.stage("craters"), warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MarsSceneWarning)
            craters, cstats = sample_craters(
                hf.bounds_xy_m, ccfg, rng=stage_rng(seed, "craters"), heightfield=hf,
                origin_lonlat_deg=frame.origin_lonlat_deg,
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

    # --- rocks stage (issue: rocks) -------------------------------------------------------
    rocks = None
    rock_prototypes = None

    # --- end of rocks stage ---------------------------------------------------------------

    # --- lighting stage (issue: lighting) -------------------------------------------------
    lighting = None

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
        config=config,
        seed=seed,
        provenance=provenance,
        craters=craters,
        rocks=rocks,
        rock_prototypes=rock_prototypes,
        lighting=lighting,
    )
