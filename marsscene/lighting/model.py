"""The :class:`Lighting` value object: everything the exporters need to light a scene."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Lighting"]


@dataclass(frozen=True, slots=True, kw_only=True)
class Lighting:
    """Sun and dusty-sky lighting of a scene.

    ``sun_direction_enu`` is the unit vector from the ground **towards** the sun (x east, y north,
    z up). Irradiances are in W m^-2.
    """

    sun_azimuth_deg: float
    sun_elevation_deg: float
    sun_direction_enu: tuple[float, float, float]
    direct_normal_w_m2: float
    diffuse_horizontal_w_m2: float
    tau: float
    sky_color_rgb: tuple[float, float, float]
    sun_color_rgb: tuple[float, float, float]
    sun_angular_diameter_deg: float
    visibility_m: float
