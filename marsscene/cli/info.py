"""``marsscene info PATH``: what a DEM or a built scene folder contains."""

from __future__ import annotations

import json
from pathlib import Path

import click

from marsscene.cli._common import user_errors


def _scene_info(folder: Path) -> list[str]:
    manifest = folder / "manifest.json"
    if not manifest.is_file():
        raise click.ClickException(f"{folder} has no manifest.json: not a marsscene scene folder")
    doc = json.loads(manifest.read_text(encoding="utf-8"))
    t = doc["terrain"]
    lines = [
        f"scene: {folder}",
        f"  marsscene {doc['marsscene_version']}, seed {doc['seed']}, "
        f"config {doc['config_hash'][:12]}",
        f"  terrain: {t['shape_rows_cols'][0]} x {t['shape_rows_cols'][1]} posts at "
        f"{t['post_m']:g} m ({t['size_m'][0]:.1f} x {t['size_m'][1]:.1f} m), "
        f"z {t['z_min_m']:.2f} .. {t['z_max_m']:.2f} m above datum {doc['frame']['datum_m']} m",
    ]
    if doc["frame"]["origin_lonlat_deg"]:
        lon, lat = doc["frame"]["origin_lonlat_deg"]
        lines.append(f"  origin: lon {lon:.5f} E, lat {lat:.5f}")
    for key, value in sorted(doc.get("summary", {}).items()):
        lines.append(f"  {key}: {value}")
    lines.append("  outputs: " + ", ".join(doc["outputs"]))
    return lines


def _dem_info(path: Path, band: int | None) -> list[str]:
    import numpy as np

    from marsscene.dem.io import read_dem

    dem = read_dem(path, band=band)
    z = dem.elevation_m
    valid = np.isfinite(z)
    lines = [
        f"DEM: {path}",
        f"  {dem.shape[0]} rows x {dem.shape[1]} cols, post {dem.post_m:g} m",
        f"  valid posts: {valid.mean() * 100:.1f} %",
    ]
    if valid.any():
        lines.append(f"  elevation: {np.nanmin(z):.2f} .. {np.nanmax(z):.2f} m")
    if dem.center_lonlat_deg:
        lines.append(f"  centre: lon {dem.center_lonlat_deg[0]:.5f} E, "
                     f"lat {dem.center_lonlat_deg[1]:.5f}")
    for key in sorted(dem.metadata):
        if key.isupper() or key in ("driver", "product_id"):
            lines.append(f"  {key}: {dem.metadata[key]}")
    return lines


@click.command(short_help="Describe a DEM file or a built scene folder.")
@click.argument("path", type=click.Path(exists=True, path_type=Path))
@click.option("--band", type=click.IntRange(min=1), default=None,
              help="Band of a multi-band DTM to describe.")
def info(path: Path, band: int | None) -> None:
    """Print what PATH (a DEM raster or a scene folder) contains."""
    with user_errors():
        lines = _scene_info(path) if path.is_dir() else _dem_info(path, band)
    click.echo("\n".join(lines))
