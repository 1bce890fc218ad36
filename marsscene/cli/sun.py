"""``marsscene sun``: sun position and irradiances at a Mars site and time."""

from __future__ import annotations

import json
import math
from typing import Any

import click

from marsscene.cli._common import user_errors


def _report(lat: float, lon: float, utc: str | None, mars_year: int | None, ls: float | None,
            ltst: float | None, tau: float, diffuse_model: str) -> dict[str, Any]:
    from marsscene.lighting import (
        LightingConfig,
        compute_lighting,
        mars_sun_position,
        sun_position_at_local_time,
    )

    if utc is not None:
        pos = mars_sun_position(utc, lat_deg=lat, lon_east_deg=lon)
    elif mars_year is not None and ls is not None and ltst is not None:
        pos = sun_position_at_local_time(mars_year=mars_year, ls_deg=ls, ltst_h=ltst,
                                         lat_deg=lat, lon_east_deg=lon)
    else:
        raise click.UsageError("give --utc, or --mars-year with --ls-deg and --ltst-h")
    cfg = LightingConfig(utc=pos.utc.isoformat(), tau=tau, diffuse_model=diffuse_model)
    lt = compute_lighting(cfg, lat_deg=lat, lon_east_deg=lon)
    return {
        "utc": pos.utc.strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
        "lat_deg": pos.lat_deg, "lon_east_deg": pos.lon_east_deg,
        "azimuth_deg": pos.azimuth_deg, "elevation_deg": pos.elevation_deg,
        "zenith_deg": pos.zenith_deg, "ls_deg": pos.ls_deg, "ltst_h": pos.ltst_h,
        "lmst_h": pos.lmst_h, "mst_h": pos.mst_h, "declination_deg": pos.declination_deg,
        "distance_au": pos.distance_au, "sun_angular_diameter_deg": lt.sun_angular_diameter_deg,
        "tau": tau, "diffuse_model": diffuse_model,
        "toa_w_m2": lt.toa_w_m2, "direct_normal_w_m2": lt.direct_normal_w_m2,
        "direct_horizontal_w_m2": lt.direct_horizontal_w_m2,
        "diffuse_horizontal_w_m2": lt.diffuse_horizontal_w_m2,
        "global_horizontal_w_m2": lt.global_horizontal_w_m2,
        "visibility_m": lt.visibility_m if math.isfinite(lt.visibility_m) else None,
        "shadow_contrast": lt.shadow_contrast,
    }


def _hms(hours: float) -> str:
    s = round(hours * 3600.0) % 86400
    return f"{s // 3600:02d}:{s % 3600 // 60:02d}:{s % 60:02d}"


@click.command(short_help="Sun position and irradiance at a Mars site and time.")
@click.option("--site-lat-deg", "lat", type=click.FloatRange(-90.0, 90.0), required=True,
              help="Planetocentric latitude of the site (deg).")
@click.option("--site-lon-east-deg", "lon", type=click.FloatRange(-360.0, 360.0), required=True,
              help="East longitude of the site (deg; negative = west).")
@click.option("--utc", default=None, metavar="ISO", help="UTC time, e.g. 2021-02-18T20:55Z.")
@click.option("--mars-year", type=int, default=None, help="Mars Year (with --ls-deg, --ltst-h).")
@click.option("--ls-deg", "ls", type=click.FloatRange(0.0, 360.0, max_open=True), default=None,
              help="Solar longitude (deg).")
@click.option("--ltst-h", "ltst", type=click.FloatRange(0.0, 24.0, max_open=True), default=None,
              help="Local true solar time (h).")
@click.option("--tau", type=click.FloatRange(0.0, 50.0), default=0.5, show_default=True,
              help="Dust optical depth.")
@click.option("--diffuse-model", type=click.Choice(["table", "polynomial", "delta_eddington"]),
              default="table", show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Machine-readable JSON output.")
def sun(lat: float, lon: float, utc: str | None, mars_year: int | None, ls: float | None,
        ltst: float | None, tau: float, diffuse_model: str, as_json: bool) -> None:
    """Print the Mars24 sun position and the surface irradiances.

    \b
    Examples:
      marsscene sun --site-lat-deg 18.44 --site-lon-east-deg 77.45 --utc 2021-02-18T20:55Z
      marsscene sun --site-lat-deg 18.44 --site-lon-east-deg 77.45 --mars-year 36 \\
        --ls-deg 90 --ltst-h 12 --tau 2 --json
    """
    with user_errors():
        r = _report(lat, lon, utc, mars_year, ls, ltst, tau, diffuse_model)
    if as_json:
        click.echo(json.dumps(r, indent=2, sort_keys=True))
        return
    vis = "inf" if r["visibility_m"] is None else f"{r['visibility_m'] / 1000:.1f} km"
    click.echo("\n".join([
        f"site      lat {r['lat_deg']:.4f}, lon {r['lon_east_deg']:.4f} E   UTC {r['utc']}",
        f"season    Ls {r['ls_deg']:.4f} deg, Sun-Mars {r['distance_au']:.5f} AU, "
        f"declination {r['declination_deg']:.4f} deg",
        f"time      LTST {_hms(r['ltst_h'])}, LMST {_hms(r['lmst_h'])}, MST {_hms(r['mst_h'])}",
        f"sun       azimuth {r['azimuth_deg']:.4f} deg (from N, clockwise), "
        f"elevation {r['elevation_deg']:.4f} deg",
        f"light     tau {tau:g} ({diffuse_model}): TOA {r['toa_w_m2']:.1f}, direct normal "
        f"{r['direct_normal_w_m2']:.1f}, diffuse {r['diffuse_horizontal_w_m2']:.1f}, global "
        f"{r['global_horizontal_w_m2']:.1f} W/m^2",
        f"dust      visibility {vis}, shadow contrast {r['shadow_contrast']:.3f}",
    ]))
