"""``marsscene build`` options of the dem stage and how they map onto the config.

``--dem`` itself is a core option of ``build``; these refine it: the draped orthoimage, the crop
(``--crop-lonlat LON LAT --size-m W H``, ``--crop-px ROW COL ROWS COLS``, or ``--size-m`` alone
for a centred crop), output post spacing, vertical scale, elevation band and resampling. Each
maps onto the ``[terrain]`` key of the same name (``crop_lonlat``, ``size_m``, ``crop_px``,
``post_m``, ``z_scale``, ``band``, ``ortho_path``, ``resampling``), plus the level-of-detail
keys ``lod``, ``focus_xy_m``, ``focus_size_m``, ``focus_post_m``, ``tile_m`` (``--focus-xy``,
``--focus-size-m`` and ``--tile-m`` imply ``--lod``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose
from marsscene.terrain.config import TerrainConfig

__all__ = ["apply", "options"]

_T = TerrainConfig()  # the terrain defaults live in TerrainConfig only

_OPTIONS = compose(
    click.option("--ortho", "ortho", type=click.Path(exists=True, dir_okay=False,
                 path_type=Path), help="Orthoimage draped as texture (HiRISE .LBL+.JP2, "
                 "GeoTIFF, ISIS3 .cub); co-registered to the DEM crop."),
    click.option("--crop-lonlat", "crop_lonlat", type=(float, float), default=None,
                 metavar="LON LAT", help="Crop centre, planetocentric east longitude and "
                 "latitude (deg); needs --size-m."),
    click.option("--size-m", "size_m", type=(click.FloatRange(min=0, min_open=True),
                 click.FloatRange(min=0, min_open=True)), default=None, metavar="W H",
                 help="Footprint width (east) and height (north) in m: the crop size of a "
                 "DEM (centred unless --crop-lonlat), or the procedural terrain's size."),
    click.option("--crop-px", "crop_px", type=(click.IntRange(min=0), click.IntRange(min=0),
                 click.IntRange(min=2), click.IntRange(min=2)), default=None,
                 metavar="ROW COL ROWS COLS", help="Crop as a pixel window of the DEM."),
    click.option("--post-m", "post_m", type=click.FloatRange(min=0, min_open=True),
                 default=None, help="Output post spacing (m); coarser than the DEM averages, "
                 "finer adds seeded detail."),
    click.option("--z-scale", "z_scale", type=click.FloatRange(min=0, min_open=True),
                 default=None, help="Vertical exaggeration of elevations above the datum."),
    click.option("--band", "band", type=click.IntRange(min=1), default=None,
                 help="Elevation band of a multi-band DEM (1-based)."),
    click.option("--lod/--no-lod", "lod", default=None, help="Two-level terrain: full "
                 "resolution (--focus-post-m) over a focus square, --post-m (with --dem: the "
                 "DEM's posts, averaged coarser if a large crop needs it) outside. Default: "
                 "two levels only when one grid would be too large (a procedural terrain or a "
                 "DEM crop; the build says so); --no-lod insists on one grid."),
    click.option("--focus-xy", "focus_xy_m", type=(float, float), default=None, metavar="X Y",
                 help="Centre of the full-resolution focus square (m); implies --lod."),
    click.option("--focus-size-m", "focus_size_m", type=click.FloatRange(min=0, min_open=True),
                 default=None,
                 help=f"Side of the focus square (m, default {_T.focus_size_m:g}); implies --lod."),
    click.option("--focus-post-m", "focus_post_m", type=click.FloatRange(min=0, min_open=True),
                 default=None,
                 help=f"Post spacing inside the focus square (m, default {_T.focus_post_m:g})."),
    click.option("--tile-m", "tile_m", type=click.FloatRange(min=0, min_open=True),
                 default=None, help="Side of a focus tile, built independently (m, default "
                 f"{_T.tile_m:g}); implies --lod."),
    click.option("--resampling", "resampling", type=click.Choice(["bilinear", "cubic", "area"]),
                 default=None, help="DEM resampling (default: area when coarsening)."),
)


def options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate the build command with this stage's options."""
    return _OPTIONS(func)


def apply(cfg: Any, values: dict[str, Any]) -> Any:
    """Return cfg with this stage's command-line values applied (unset options keep the
    config's values)."""
    changes: dict[str, Any] = {}
    if values.get("ortho") is not None:
        changes["ortho_path"] = str(values["ortho"])
    for key in ("crop_lonlat", "size_m", "crop_px"):
        if values.get(key) is not None:
            changes[key] = tuple(values[key])
    for key in ("post_m", "z_scale", "band", "resampling", "lod", "focus_size_m",
                "focus_post_m", "tile_m"):
        if values.get(key) is not None:
            changes[key] = values[key]
    if values.get("focus_xy_m") is not None:
        changes["focus_xy_m"] = tuple(values["focus_xy_m"])
    if values.get("lod") is None and any(k in changes for k in ("focus_xy_m", "focus_size_m",
                                                                  "tile_m")):
        changes["lod"] = True
    if not changes:
        return cfg
    if "crop_lonlat" in changes and "size_m" not in changes and cfg.terrain.size_m is None:
        raise click.UsageError("--crop-lonlat needs --size-m W H")
    crop_given = [k for k in ("crop_lonlat", "crop_px") if k in changes]
    if crop_given:  # a crop on the command line replaces any crop from the config file
        for key in ("crop_lonlat", "crop_px", "crop_bounds_m"):
            changes.setdefault(key, None)
    terrain = dataclasses.replace(cfg.terrain, **changes)
    return cfg.replace(terrain=terrain)
