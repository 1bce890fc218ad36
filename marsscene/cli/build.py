"""``marsscene build``: DEM or procedural terrain -> craters -> rocks -> lighting -> USD + MJCF."""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any

import click

from marsscene.cli import options_assets, options_dem, options_lighting, traversability
from marsscene.cli._common import user_errors

log = logging.getLogger("marsscene")

_FORMATS = ("usda", "usdc", "usdz", "mjcf")


def _apply_core(cfg: Any, *, dem: Path | None, procedural: bool, formats: tuple[str, ...],
                rock_catalogue: str | None = None, rover: bool | None = None,
                rover_xy: tuple[float, float] | None = None,
                rover_yaw_deg: float | None = None) -> Any:
    terrain = cfg.terrain
    if dem is not None and procedural:
        raise click.UsageError("--dem and --procedural are mutually exclusive")
    if dem is not None:
        terrain = dataclasses.replace(terrain, source="dem", dem_path=str(dem))
    elif procedural:
        terrain = dataclasses.replace(terrain, source="procedural", dem_path=None)
    export = cfg.export
    if formats:
        usd = [f for f in formats if f != "mjcf"]
        if len(set(usd)) > 1:
            raise click.UsageError(f"give at most one USD encoding; got {usd}")
        kinds = (["usd"] if usd else []) + (["mjcf"] if "mjcf" in formats else [])
        export = dataclasses.replace(
            export, formats=tuple(kinds), usd_format=usd[0] if usd else export.usd_format
        )
    if rock_catalogue is not None:
        export = dataclasses.replace(export, rock_catalogue=rock_catalogue)
    if rover_xy is not None or rover_yaw_deg is not None:
        if rover is False:
            raise click.UsageError("--rover-xy / --rover-yaw-deg place the rover: drop --no-rover")
        rover = True
    changes: dict[str, Any] = {"rover": rover} if rover is not None else {}
    if rover_xy is not None:
        changes["rover_xy_m"] = rover_xy
    if rover_yaw_deg is not None:
        changes["rover_yaw_deg"] = rover_yaw_deg
    export = dataclasses.replace(export, **changes)
    return cfg.replace(terrain=terrain, export=export)


@click.command(short_help="Build a Mars scene (USD + MJCF + manifest).")
@click.option("--dem", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="DEM: PDS3 .IMG/.LBL, ISIS3 .cub or GeoTIFF. Default: bundled Gale crater DEM.")
@click.option("--config", "config_path", type=click.Path(exists=True, dir_okay=False,
              path_type=Path), help="TOML scene config; command-line options override it.")
@click.option("--seed", type=click.IntRange(min=0), default=None,
              help="Random seed (default: config's seed, else 0).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("scenes/default"), show_default=True, help="Output folder.")
@click.option("--format", "formats", type=click.Choice(_FORMATS), multiple=True,
              help="Output(s); repeatable. Default: usda and mjcf.")
@click.option("--procedural", is_flag=True, help="Synthesise terrain instead of reading a DEM.")
@click.option("--rock-catalogue", type=click.Choice(["csv", "parquet", "both"]), default=None,
              help="Rock catalogue file(s): rocks.csv, rocks.parquet (needs pyarrow) or both. "
                   "Default: config's [export] rock_catalogue, else csv.")
@click.option("--rover/--no-rover", default=None,
              help="Place the USD rover (assets/rover.usda, written with every USD output) in "
                   "scene.usda as /World/Rover at the MuJoCo runtime's spawn pose, for Isaac "
                   "Sim / Newton. Default: config's [export] rover, else off.")
@click.option("--rover-xy", type=(float, float), default=None, metavar="X Y",
              help="Where to place the rover (m, world frame; implies --rover). Default: the "
                   "terrain centre, as `marsscene drive`.")
@click.option("--rover-yaw-deg", type=click.FloatRange(-360.0, 360.0), default=None,
              help="The rover's heading (deg, counter-clockwise from east; implies --rover).")
@click.option("--traversability", "write_traversability", is_flag=True,
              help="Also write OUT/traversability/ (`marsscene traversability`: GeoTIFF layers, "
                   "PNG preview, JSON summary); needs the mjcf output.")
@traversability.cell_option("--traversability-cell-m")
@click.option("--orbital-map", "write_orbital", is_flag=True,
              help="Also write OUT/orbital/: the scene as an orbiter sees it (dem.tif at 1 m "
                   "posts, ortho.tif, orbital.json; docs/orbital.md).")
@options_assets.options
@options_dem.options
@options_lighting.options
def build(
    dem: Path | None,
    config_path: Path | None,
    seed: int | None,
    out_dir: Path,
    formats: tuple[str, ...],
    procedural: bool,
    rock_catalogue: str | None,
    rover: bool | None,
    rover_xy: tuple[float, float] | None,
    rover_yaw_deg: float | None,
    write_traversability: bool,
    traversability_cell_m: float | None,
    write_orbital: bool,
    **stage_options: Any,
) -> None:
    """Build a scene and write OUT/scene.usda, OUT/mjcf/scene.xml and OUT/manifest.json.

    \b
    Examples:
      marsscene build --seed 7 --out scenes/demo
      marsscene build --dem jezero.img --seed 7
      marsscene build --procedural --format usdc --format mjcf
      marsscene build --procedural --rock-catalogue parquet
      marsscene build --preset main-crater --seed 7 --out scenes/crater
      marsscene build --preset mars-base --asset habitat.glb --asset-xy 120 -40
      marsscene build --seed 7 --rover --rover-xy 10 -5 --rover-yaw-deg 90
      marsscene build --seed 7 --traversability --orbital-map
    """
    from marsscene import SceneConfig, build_scene, write_scene
    from marsscene.export import check_export_dependencies, check_output_dir

    with user_errors():
        check_output_dir(out_dir)
        preset = stage_options.pop("preset")
        cfg = (SceneConfig.from_toml(config_path, preset=preset) if config_path
               else SceneConfig.from_dict({"preset": preset}))
        cfg = _apply_core(cfg, dem=dem, procedural=procedural, formats=formats,
                          rock_catalogue=rock_catalogue, rover=rover, rover_xy=rover_xy,
                          rover_yaw_deg=rover_yaw_deg)
        cfg = options_dem.apply(cfg, stage_options)
        cfg = options_lighting.apply(cfg, stage_options)
        cfg = options_assets.apply(cfg, stage_options)
        check_export_dependencies(cfg.export)
        if write_traversability and "mjcf" not in cfg.export.formats:
            raise click.UsageError("--traversability reads the scene's MJCF terrain: add "
                                   "--format mjcf")
        use_seed = seed if seed is not None else (cfg.seed if cfg.seed is not None else 0)
        scene = build_scene(cfg, seed=use_seed)
        log.info("[export] writing %s", ", ".join(cfg.export.formats))
        written = write_scene(scene, out_dir)
        if write_orbital:
            from marsscene.orbital import orbital_map, write_orbital_map

            written["orbital"] = [write_orbital_map(orbital_map(scene), out_dir) / "dem.tif"]
    if write_traversability:
        written["traversability"] = traversability.write_map(out_dir, traversability_cell_m)
    for kind, paths in written.items():
        for p in paths:
            if p.name in ("scene.usda", "scene.usdc", "scene.usdz", "scene.xml", "manifest.json",
                          "traversability.tif", "dem.tif"):
                click.echo(f"{kind:>8}: {p}")
