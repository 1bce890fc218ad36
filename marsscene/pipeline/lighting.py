"""The lighting stage: the sun at the scene's site (Mars24 or given), Beer's-law direct beam
and the dusty sky. Deterministic: no random draws."""

from __future__ import annotations

from marsscene.config import SceneConfig
from marsscene.lighting.compute import compute_lighting
from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG
from marsscene.lighting.irradiance import AF_CITATION, DELTA_EDDINGTON_CITATION
from marsscene.lighting.mars24 import MARS24_CITATION
from marsscene.lighting.model import Lighting
from marsscene.pipeline.record import BuildRecord
from marsscene.scene import ModelRef
from marsscene.terrain.from_dem import GeoFrame

__all__ = ["lighting_stage"]


def _site(config: SceneConfig, frame: GeoFrame) -> tuple[float, float, str]:
    lcfg = config.lighting
    if lcfg.site_lat_deg is not None and lcfg.site_lon_east_deg is not None:
        return lcfg.site_lat_deg, lcfg.site_lon_east_deg, "config"
    if frame.origin_lonlat_deg is not None:
        lon_e_deg, lat_deg = frame.origin_lonlat_deg
        return lat_deg, lon_e_deg, "DEM centre"
    lat_deg, lon_e_deg = DEFAULT_SITE_LAT_LON_EAST_DEG
    return lat_deg, lon_e_deg, "default site (Jezero)"


def lighting_stage(config: SceneConfig, frame: GeoFrame, rec: BuildRecord) -> Lighting:
    """The scene's :class:`~marsscene.lighting.model.Lighting`."""
    lcfg = config.lighting
    with rec.stage("lighting"):
        lat_deg, lon_e_deg, site_src = _site(config, frame)
        lighting = compute_lighting(lcfg, lat_deg=lat_deg, lon_east_deg=lon_e_deg,
                                    grid_convergence_deg=frame.grid_convergence_deg)
        if lcfg.sun_mode in ("utc", "local"):
            rec.models.append(ModelRef("lighting", "Mars24 sun position", MARS24_CITATION))
        diffuse_ref = DELTA_EDDINGTON_CITATION if lcfg.diffuse_model == "delta_eddington" \
            else AF_CITATION
        rec.models.append(ModelRef("lighting", f"Beer's-law sun + {lcfg.diffuse_model} sky",
                                   diffuse_ref))
        rec.notes.append(f"lighting: sun from {lcfg.sun_mode} at {site_src} "
                         f"(lat {lat_deg:.4f}, lon {lon_e_deg % 360.0:.4f} E)")
        if lighting.sun_elevation_deg <= 0.0:
            rec.notes.append("lighting: the sun is below the horizon (no direct or diffuse light)")
        rec.summary.update({
            "lighting_tau": lighting.tau,
            "lighting_sun_azimuth_deg": round(lighting.sun_azimuth_deg, 6),
            "lighting_sun_elevation_deg": round(lighting.sun_elevation_deg, 6),
            "lighting_direct_normal_w_m2": round(lighting.direct_normal_w_m2, 4),
            "lighting_diffuse_horizontal_w_m2": round(lighting.diffuse_horizontal_w_m2, 4),
            "lighting_visibility_m": round(lighting.visibility_m, 1)
            if lighting.visibility_m != float("inf") else None,
        })
    return lighting
