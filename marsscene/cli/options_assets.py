"""``marsscene build`` options of the preset and asset stages.

``--preset NAME`` expands a reference scene (``marsscene.presets``) under the config file and
the other options; ``--asset FILE`` (repeatable) places user assets on levelled ground, at the
flattest suitable site or at ``--asset-xy X Y`` (one per asset); ``--habitat`` places the
procedural habitat (the ``mars-base`` preset does so by default).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose
from marsscene.presets import PRESET_NAMES

__all__ = ["apply", "options"]

_OPTIONS = compose(
    click.option("--preset", "preset", type=click.Choice(PRESET_NAMES), default=None,
                 help="MarsLab reference scene (size, terrain shape, rock, dust and sun "
                 "defaults); with --dem the DTM is used. Other options override it."),
    click.option("--asset", "asset_files", multiple=True, type=click.Path(
                 exists=True, dir_okay=False, path_type=Path),
                 help="Asset to place (.usd/.usda/.usdc/.usdz, .obj, .glb/.gltf, .stl, .ply); "
                 "repeatable."),
    click.option("--asset-xy", "asset_xy", type=(float, float), multiple=True,
                 metavar="X Y", help="Where to place an --asset (m, world frame); repeatable: "
                 "the n-th --asset-xy places the n-th --asset. Default: the flattest "
                 "suitable site."),
    click.option("--habitat/--no-habitat", "habitat", default=None,
                 help="Place the procedural habitat when no --asset is given."),
)


def options(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate the build command with these options."""
    return _OPTIONS(func)


def apply(cfg: Any, values: dict[str, Any]) -> Any:
    """Return cfg with the asset options applied (``--preset`` is applied when the config is
    read, see :func:`marsscene.cli.build.build`)."""
    changes: dict[str, Any] = {}
    if values.get("asset_files"):
        changes["files"] = tuple(str(p) for p in values["asset_files"])
        changes["xy_m"] = None
    if values.get("asset_xy"):
        changes["xy_m"] = tuple(tuple(p) for p in values["asset_xy"])
    if values.get("habitat") is not None:
        changes["habitat"] = values["habitat"]
    if not changes:
        return cfg
    return cfg.replace(assets=dataclasses.replace(cfg.assets, **changes))
