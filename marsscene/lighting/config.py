"""Lighting stage configuration (``[lighting]`` table).

How the sun is placed (first match wins):

1. ``utc`` (ISO 8601 with zone) -> Mars24 sun position at the site;
2. ``mars_year`` + ``ls_deg`` + ``ltst_h`` -> the sol of that Mars year nearest Ls, at that
   local true solar time;
3. ``sun_azimuth_deg`` + ``sun_elevation_deg`` -> explicit (distance from ``ls_deg`` if given,
   else Mars' mean distance);
4. nothing -> the documented default :data:`DEFAULT_SUN_AZIMUTH_DEG` /
   :data:`DEFAULT_SUN_ELEVATION_DEG` (deterministic; never "now").

The site is ``site_lat_deg``/``site_lon_east_deg`` if given, else the DEM centre, else
:data:`DEFAULT_SITE_LAT_LON_EAST_DEG` (Jezero crater, Perseverance landing site).
"""

from __future__ import annotations

from dataclasses import dataclass

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError
from marsscene.lighting.timescale import parse_utc

__all__ = [
    "DEFAULT_SITE_LAT_LON_EAST_DEG",
    "DEFAULT_SUN_AZIMUTH_DEG",
    "DEFAULT_SUN_ELEVATION_DEG",
    "LightingConfig",
]

#: Default sun when no time is given: azimuth 70 deg (ENE, clockwise from north), elevation
#: 13 deg -- a low morning sun with long shadows, as in the MarsLab reference renders.
DEFAULT_SUN_AZIMUTH_DEG = 70.0
DEFAULT_SUN_ELEVATION_DEG = 13.0
#: Default site for procedural terrain: Octavia E. Butler landing site, Jezero crater
#: (18.4447 N, 77.4508 E; Perseverance, 2021-02-18).
DEFAULT_SITE_LAT_LON_EAST_DEG = (18.4447, 77.4508)

USD_UNITS = ("lux", "w_m2")


@dataclass(frozen=True, slots=True, kw_only=True)
class LightingConfig:
    """Sun and sky parameters (see the module docstring for how the sun is placed)."""

    enabled: bool = True
    """Compute and export sun and sky lights."""
    utc: str | None = None
    """UTC instant, ISO 8601 with zone, e.g. ``"2021-02-18T20:55:00Z"``."""
    mars_year: int | None = None
    """Mars Year (Clancy et al. 2000 numbering; MY 36 began 2021-02-07)."""
    ls_deg: float | None = None
    """Areocentric solar longitude (with ``mars_year`` + ``ltst_h``, or for the distance)."""
    ltst_h: float | None = None
    """Local true solar time, hours [0, 24)."""
    sun_azimuth_deg: float | None = None
    """Explicit sun azimuth, clockwise from north, [0, 360]."""
    sun_elevation_deg: float | None = None
    """Explicit sun elevation, [-90, 90]."""
    site_lat_deg: float | None = None
    """Site latitude (default: DEM centre, else Jezero)."""
    site_lon_east_deg: float | None = None
    """Site east longitude (default: DEM centre, else Jezero)."""
    tau: float = 0.5
    """Dust optical depth (visible); 0.3-0.9 typical clear season, 1-2 dusty, up to ~10 storm."""
    diffuse_model: str = "table"
    """``"table"`` (A&F/Pollack), ``"polynomial"`` (A&F fit) or ``"delta_eddington"``."""
    air_mass_model: str = "spherical"
    """Direct-beam air mass: ``"spherical"`` (finite at the horizon) or ``"secant"`` (A&F)."""
    surface_albedo: float = 0.1
    """Broadband surface albedo (A&F polynomial / delta-Eddington)."""
    single_scattering_albedo: float = 0.93
    """Dust omega for the delta-Eddington option (illustrative broadband value)."""
    asymmetry: float = 0.68
    """Dust asymmetry parameter g for the delta-Eddington option."""
    dust_scale_height_m: float = 11_000.0
    """Dust scale height H; visibility = 3.912 H / tau."""
    solar_constant_w_m2: float = 1361.0
    """Total solar irradiance at 1 AU."""
    usd_units: str = "lux"
    """USD light intensity unit: ``"lux"`` (photometric, via ``luminous_efficacy_lm_per_w``)
    or ``"w_m2"`` (radiometric, 1 unit = 1 W m^-2)."""
    luminous_efficacy_lm_per_w: float = 98.0
    """W m^-2 -> lux factor: 98 lm/W = 133.8 klx / 1361 W m^-2 for the extraterrestrial solar
    spectrum (Darula, Kittler & Gueymard 2005, Solar Energy 79, 559)."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"lighting.enabled must be true or false; got {self.enabled!r}")
        if self.utc is not None:
            if not isinstance(self.utc, str):
                raise ConfigError(f"lighting.utc = {self.utc!r} must be an ISO 8601 string")
            parse_utc(self.utc)
        if self.mars_year is not None and (
            isinstance(self.mars_year, bool) or not isinstance(self.mars_year, int)
        ):
            raise ConfigError(f"lighting.mars_year = {self.mars_year!r} must be an integer")
        optional = {
            "sun_azimuth_deg": (self.sun_azimuth_deg, 0.0, 360.0),
            "sun_elevation_deg": (self.sun_elevation_deg, -90.0, 90.0),
            "site_lat_deg": (self.site_lat_deg, -90.0, 90.0),
            "site_lon_east_deg": (self.site_lon_east_deg, -180.0, 360.0),
        }
        for key, (value, lo, hi) in optional.items():
            if value is not None:
                check_range(f"lighting.{key}", value, lo, hi)
        for key, value, hi in (("ls_deg", self.ls_deg, 360.0), ("ltst_h", self.ltst_h, 24.0)):
            if value is not None:
                check_range(f"lighting.{key}", value, 0.0, hi, hi_open=True)
        local = (self.mars_year, self.ltst_h)
        if (any(v is not None for v in local) and not all(v is not None for v in local)) or (
            self.mars_year is not None and self.ls_deg is None
        ):
            raise ConfigError(
                "lighting.mars_year, lighting.ls_deg and lighting.ltst_h go together; got "
                f"mars_year={self.mars_year!r}, ls_deg={self.ls_deg!r}, ltst_h={self.ltst_h!r}"
            )
        if (self.sun_azimuth_deg is None) != (self.sun_elevation_deg is None):
            raise ConfigError(
                "lighting.sun_azimuth_deg and lighting.sun_elevation_deg go together; got "
                f"{self.sun_azimuth_deg!r} and {self.sun_elevation_deg!r}"
            )
        if (self.site_lat_deg is None) != (self.site_lon_east_deg is None):
            raise ConfigError(
                "lighting.site_lat_deg and lighting.site_lon_east_deg go together; got "
                f"{self.site_lat_deg!r} and {self.site_lon_east_deg!r}"
            )
        check_range("lighting.tau", self.tau, 0.0, 50.0)
        check_choice("lighting.diffuse_model", self.diffuse_model,
                     ("table", "polynomial", "delta_eddington"))
        check_choice("lighting.air_mass_model", self.air_mass_model, ("spherical", "secant"))
        check_range("lighting.surface_albedo", self.surface_albedo, 0.0, 0.9)
        check_range("lighting.single_scattering_albedo", self.single_scattering_albedo, 0.0, 1.0)
        check_range("lighting.asymmetry", self.asymmetry, 0.0, 1.0, hi_open=True)
        check_range("lighting.dust_scale_height_m", self.dust_scale_height_m, 100.0, 100_000.0)
        check_range("lighting.solar_constant_w_m2", self.solar_constant_w_m2, 0.0, 10_000.0,
                    lo_open=True)
        check_choice("lighting.usd_units", self.usd_units, USD_UNITS)
        check_range("lighting.luminous_efficacy_lm_per_w", self.luminous_efficacy_lm_per_w,
                    0.0, 683.0, lo_open=True)

    @property
    def sun_mode(self) -> str:
        """``"utc"``, ``"local"``, ``"explicit"`` or ``"default"`` (see the module docstring)."""
        if self.utc is not None:
            return "utc"
        if self.mars_year is not None:
            return "local"
        if self.sun_azimuth_deg is not None:
            return "explicit"
        return "default"
