"""Turn a :class:`LightingConfig` and a site into a :class:`Lighting` (pure)."""

from __future__ import annotations

import math

from marsscene.lighting.config import (
    DEFAULT_SUN_AZIMUTH_DEG,
    DEFAULT_SUN_ELEVATION_DEG,
    LightingConfig,
)
from marsscene.lighting.irradiance import (
    MEAN_DISTANCE_AU,
    air_mass,
    diffuse_irradiance_w_m2,
    direct_irradiance_w_m2,
    toa_irradiance_w_m2,
)
from marsscene.lighting.mars24 import (
    SunPosition,
    mars_sun_position,
    sun_angular_diameter_deg,
    sun_direction_enu,
    sun_position_at_local_time,
)
from marsscene.lighting.model import Lighting
from marsscene.lighting.sky import (
    extinction_coefficient_per_m,
    shadow_contrast,
    sky_color_rgb,
    sun_color_rgb,
    visibility_m,
)

__all__ = ["compute_lighting", "resolve_sun"]


def _distance_from_ls(ls_deg: float) -> float:
    """Sun-Mars distance (AU) from Ls with the Keplerian orbit of Appelbaum & Flood
    (a = 1.523679 AU, e = 0.093377, perihelion at Ls = 248 deg)."""
    e = 0.093377
    return MEAN_DISTANCE_AU * (1 - e * e) / (1 + e * math.cos(math.radians(ls_deg - 248.0)))


def resolve_sun(
    config: LightingConfig, *, lat_deg: float, lon_east_deg: float
) -> tuple[float, float, float, SunPosition | None]:
    """``(azimuth_deg, elevation_deg, distance_au, SunPosition or None)`` for a config."""
    mode = config.sun_mode
    if mode == "utc":
        assert config.utc is not None
        pos = mars_sun_position(config.utc, lat_deg=lat_deg, lon_east_deg=lon_east_deg)
        return pos.azimuth_deg, pos.elevation_deg, pos.distance_au, pos
    if mode == "local":
        assert config.mars_year is not None and config.ls_deg is not None
        assert config.ltst_h is not None
        pos = sun_position_at_local_time(
            mars_year=config.mars_year, ls_deg=config.ls_deg, ltst_h=config.ltst_h,
            lat_deg=lat_deg, lon_east_deg=lon_east_deg,
        )
        return pos.azimuth_deg, pos.elevation_deg, pos.distance_au, pos
    dist = _distance_from_ls(config.ls_deg) if config.ls_deg is not None else MEAN_DISTANCE_AU
    if mode == "explicit":
        assert config.sun_azimuth_deg is not None and config.sun_elevation_deg is not None
        return float(config.sun_azimuth_deg), float(config.sun_elevation_deg), dist, None
    return DEFAULT_SUN_AZIMUTH_DEG, DEFAULT_SUN_ELEVATION_DEG, dist, None


def compute_lighting(
    config: LightingConfig,
    *,
    lat_deg: float,
    lon_east_deg: float,
    grid_convergence_deg: float = 0.0,
) -> Lighting:
    """Sun position, irradiances, sky colour and visibility for a site.

    Parameters
    ----------
    config : LightingConfig
    lat_deg, lon_east_deg : float
        The site (used when the sun comes from a time; recorded otherwise).
    grid_convergence_deg : float
        Angle from true north to the scene's +y axis (non-zero on polar stereographic DEMs).
        ``sun_azimuth_deg`` stays clockwise from true north; ``sun_direction_enu`` is in the
        scene frame, i.e. at scene azimuth ``azimuth - grid_convergence_deg``.

    Examples
    --------
    >>> from marsscene.lighting import LightingConfig
    >>> lt = compute_lighting(LightingConfig(utc="2021-02-18T20:55Z", tau=0.5),
    ...                       lat_deg=18.4447, lon_east_deg=77.4508)
    >>> round(lt.sun_elevation_deg, 1), round(lt.sun_azimuth_deg, 1)
    (37.0, 258.7)
    """
    az, el, dist, pos = resolve_sun(config, lat_deg=lat_deg, lon_east_deg=lon_east_deg)
    zen = 90.0 - el
    tau = config.tau
    kw = {"tau": tau, "distance_au": dist, "solar_constant_w_m2": config.solar_constant_w_m2}
    dni = float(direct_irradiance_w_m2(zen, air_mass_model=config.air_mass_model, **kw))  # type: ignore[arg-type]
    dhi = float(diffuse_irradiance_w_m2(
        zen, model=config.diffuse_model, albedo=config.surface_albedo,  # type: ignore[arg-type]
        single_scattering_albedo=config.single_scattering_albedo, asymmetry=config.asymmetry,
        air_mass_model=config.air_mass_model, **kw,  # type: ignore[arg-type]
    ))
    bh = dni * max(math.sin(math.radians(el)), 0.0)
    m = float(air_mass(min(max(zen, 0.0), 90.0), model="spherical"))
    vec = sun_direction_enu(az - grid_convergence_deg, el)
    return Lighting(
        sun_azimuth_deg=float(az % 360.0),
        sun_elevation_deg=float(el),
        sun_direction_enu=(float(vec[0]), float(vec[1]), float(vec[2])),
        direct_normal_w_m2=dni,
        diffuse_horizontal_w_m2=dhi,
        tau=float(tau),
        sky_color_rgb=sky_color_rgb(tau, sun_elevation_deg=el),
        sky_aureole_rgb=sky_color_rgb(tau, sun_elevation_deg=el, near_sun=True),
        sun_color_rgb=sun_color_rgb(tau, air_mass=m),
        sun_angular_diameter_deg=sun_angular_diameter_deg(dist),
        visibility_m=float(visibility_m(tau, dust_scale_height_m=config.dust_scale_height_m)),
        direct_horizontal_w_m2=bh,
        global_horizontal_w_m2=bh + dhi,
        toa_w_m2=float(toa_irradiance_w_m2(dist, solar_constant_w_m2=config.solar_constant_w_m2)),
        distance_au=float(dist),
        extinction_per_m=float(extinction_coefficient_per_m(
            tau, dust_scale_height_m=config.dust_scale_height_m)),
        dust_scale_height_m=float(config.dust_scale_height_m),
        shadow_contrast=float(shadow_contrast(bh, dhi)),
        site_lat_deg=float(lat_deg),
        site_lon_east_deg=float(lon_east_deg % 360.0),
        utc=pos.utc.strftime("%Y-%m-%dT%H:%M:%S.%fZ") if pos is not None else None,
        ls_deg=pos.ls_deg if pos is not None else config.ls_deg,
        ltst_h=pos.ltst_h if pos is not None else None,
        sun_mode=config.sun_mode,
        diffuse_model=config.diffuse_model,
        usd_units=config.usd_units,
        luminous_efficacy_lm_per_w=float(config.luminous_efficacy_lm_per_w),
    )
