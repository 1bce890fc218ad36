"""Lighting: Mars24 sun position, Beer's-law sun, dusty-sky diffuse light and visibility.

Pure functions (numpy/scipy only); see :doc:`/lighting` for the science and citations.
"""

from __future__ import annotations

from marsscene.lighting.compute import compute_lighting
from marsscene.lighting.config import LightingConfig
from marsscene.lighting.irradiance import (
    air_mass,
    diffuse_irradiance_w_m2,
    direct_irradiance_w_m2,
    global_irradiance_w_m2,
    toa_irradiance_from_ls_w_m2,
    toa_irradiance_w_m2,
)
from marsscene.lighting.mars24 import (
    SunPosition,
    mars_sun_position,
    solar_longitude_deg,
    sun_direction_enu,
    sun_position_at_local_time,
    sun_track,
)
from marsscene.lighting.model import Lighting
from marsscene.lighting.sky import (
    contrast_transmission,
    extinction_coefficient_per_m,
    shadow_contrast,
    sky_color_rgb,
    sun_color_rgb,
    visibility_m,
)
from marsscene.lighting.usd_units import usd_dome_intensity, usd_light_intensity

__all__ = [
    "Lighting",
    "LightingConfig",
    "SunPosition",
    "air_mass",
    "compute_lighting",
    "contrast_transmission",
    "diffuse_irradiance_w_m2",
    "direct_irradiance_w_m2",
    "extinction_coefficient_per_m",
    "global_irradiance_w_m2",
    "mars_sun_position",
    "shadow_contrast",
    "sky_color_rgb",
    "solar_longitude_deg",
    "sun_color_rgb",
    "sun_direction_enu",
    "sun_position_at_local_time",
    "sun_track",
    "toa_irradiance_from_ls_w_m2",
    "toa_irradiance_w_m2",
    "usd_dome_intensity",
    "usd_light_intensity",
    "visibility_m",
]
