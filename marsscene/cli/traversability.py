"""``marsscene traversability SCENE_DIR``: a built scene's ground-truth traversability map
(:mod:`marsscene.traversability`), written to ``SCENE_DIR/traversability/``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import user_errors

_CELL_HELP = ("Traversability grid spacing in m, rounded to whole terrain posts (default: the "
              "posts, coarser past 4 M cells).")


def cell_option(name: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """The grid option, as ``--cell-m`` here and ``--traversability-cell-m`` on build."""
    return click.option(name, "traversability_cell_m", default=None, help=_CELL_HELP,
                        type=click.FloatRange(min=0.0, min_open=True))


def write_map(scene_dir: Path, cell_m: float | None) -> list[Path]:
    """Compute and write the map of a built scene (one-line errors for bad input)."""
    from marsscene.traversability import TraversabilityConfig
    from marsscene.traversability.scene import write_traversability

    with user_errors():
        return write_traversability(scene_dir, config=TraversabilityConfig(cell_m=cell_m))


@click.command(short_help="Write a built scene's traversability map (GeoTIFF, PNG, JSON).")
@click.argument("scene_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@cell_option("--cell-m")
def traversability(scene_dir: Path, traversability_cell_m: float | None) -> None:
    """Compute the ground-truth traversability of SCENE_DIR (its terrain, rock catalogue and
    soil map against the rover's geometry) and write SCENE_DIR/traversability/:
    traversability.tif (slope, roughness, step, rock, belly, slip, cost, hazard bands),
    preview.png and summary.json.

    \b
    Examples:
      marsscene traversability scenes/demo
      marsscene traversability scenes/demo --cell-m 1
    """
    for path in write_map(scene_dir, traversability_cell_m):
        click.echo(f"traversability: {path}")
