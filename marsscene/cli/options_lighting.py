"""``marsscene build`` options of the lighting stage and how they map onto the config."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import click

from marsscene.cli._common import compose
from marsscene.errors import ConfigError

__all__ = ["apply", "options"]

#: option name (click parameter) -> LightingConfig field
_FIELDS = {
    "utc": "utc",
    "tau": "tau",
    "sun_azimuth_deg": "sun_azimuth_deg",
    "sun_elevation_deg": "sun_elevation_deg",
    "mars_year": "mars_year",
    "ls_deg": "ls_deg",
    "ltst_h": "ltst_h",
    "site_lat_deg": "site_lat_deg",
    "site_lon_east_deg": "site_lon_east_deg",
    "diffuse_model": "diffuse_model",
    "usd_light_units": "usd_units",
}

options: Callable[[Any], Any] = compose(
    click.option("--utc", default=None, metavar="ISO",
                 help="UTC time of the sun, e.g. 2021-02-18T20:55Z (Mars24 at the site)."),
    click.option("--tau", type=click.FloatRange(0.0, 50.0), default=None,
                 help="Dust optical depth (default 0.5)."),
    click.option("--sun-azimuth-deg", type=click.FloatRange(0.0, 360.0), default=None,
                 help="Explicit sun azimuth, clockwise from north (with --sun-elevation-deg)."),
    click.option("--sun-elevation-deg", type=click.FloatRange(-90.0, 90.0), default=None,
                 help="Explicit sun elevation."),
    click.option("--mars-year", type=int, default=None,
                 help="Mars Year (with --ls-deg and --ltst-h): sun at a Mars-local time."),
    click.option("--ls-deg", "ls_deg", type=click.FloatRange(0.0, 360.0, max_open=True),
                 default=None, help="Solar longitude Ls in degrees (season)."),
    click.option("--ltst-h", "ltst_h", type=click.FloatRange(0.0, 24.0, max_open=True),
                 default=None, help="Local true solar time in hours."),
    click.option("--site-lat-deg", type=click.FloatRange(-90.0, 90.0), default=None,
                 help="Site latitude (default: DEM centre, else Jezero)."),
    click.option("--site-lon-east-deg", type=click.FloatRange(-180.0, 360.0), default=None,
                 help="Site east longitude (default: DEM centre, else Jezero)."),
    click.option("--diffuse-model", type=click.Choice(["table", "polynomial", "delta_eddington"]),
                 default=None, help="Diffuse sky model (default: table)."),
    click.option("--usd-light-units", type=click.Choice(["lux", "w_m2"]), default=None,
                 help="USD light intensity units (default: lux)."),
    click.option("--no-lighting", is_flag=True, default=False,
                 help="Disable the lighting stage (neutral default lights)."),
)


def apply(cfg: Any, values: dict[str, Any]) -> Any:
    """Return cfg with this stage's command-line values applied.

    A time given on the command line replaces the other ways of placing the sun from the
    config file (``--utc`` clears an explicit azimuth/elevation, and so on).
    """
    changes = {field: values[opt] for opt, field in _FIELDS.items()
               if values.get(opt) is not None}
    if values.get("no_lighting"):
        changes["enabled"] = False
    if not changes:
        return cfg
    if "utc" in changes:
        changes.update({k: changes.get(k) for k in ("sun_azimuth_deg", "sun_elevation_deg",
                                                      "mars_year", "ltst_h")})
    elif "sun_azimuth_deg" in changes or "sun_elevation_deg" in changes:
        changes.update({"utc": None, "mars_year": None, "ltst_h": None})
    elif "mars_year" in changes:
        changes.update({"utc": None})
    try:
        lighting = dataclasses.replace(cfg.lighting, **changes)
    except ConfigError as err:
        raise click.UsageError(str(err)) from None
    return cfg.replace(lighting=lighting)
