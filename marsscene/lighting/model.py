"""The :class:`Lighting` value object: everything the exporters need to light a scene."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Lighting"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Lighting:
    """Sun and dusty-sky lighting of a scene.

    ``sun_direction_enu`` is the unit vector from the ground **towards** the sun (x east, y north,
    z up). Irradiances are in W m^-2; colours are linear RGB with a maximum of 1.
    """

    sun_azimuth_deg: float
    """Clockwise from north (east = 90)."""
    sun_elevation_deg: float
    sun_direction_enu: tuple[float, float, float]
    direct_normal_w_m2: float
    """Direct beam on a surface facing the sun."""
    diffuse_horizontal_w_m2: float
    tau: float
    sky_color_rgb: tuple[float, float, float]
    sun_color_rgb: tuple[float, float, float]
    sun_angular_diameter_deg: float
    visibility_m: float
    """Meteorological (2 % contrast) visibility; ``inf`` when tau = 0."""
    direct_horizontal_w_m2: float = 0.0
    global_horizontal_w_m2: float = 0.0
    toa_w_m2: float = 0.0
    """Top-of-atmosphere normal irradiance at ``distance_au``."""
    distance_au: float = 1.523679
    extinction_per_m: float = 0.0
    dust_scale_height_m: float = 11_000.0
    sky_aureole_rgb: tuple[float, float, float] = (1.0, 0.56, 0.24)
    """Sky colour near the sun (blue-ish at sunset)."""
    shadow_contrast: float = 0.0
    """Direct / global horizontal: how dark shadows are relative to lit ground."""
    site_lat_deg: float | None = None
    site_lon_east_deg: float | None = None
    utc: str | None = None
    ls_deg: float | None = None
    ltst_h: float | None = None
    sun_mode: str = "explicit"
    """``"utc"``, ``"local"``, ``"explicit"`` or ``"default"``."""
    diffuse_model: str = "table"
    usd_units: str = "lux"
    luminous_efficacy_lm_per_w: float = 98.0
