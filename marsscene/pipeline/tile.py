"""One focus tile of a level-of-detail world built alone (:func:`build_tile`), equal to the same
window of a full :func:`marsscene.build_scene`."""

from __future__ import annotations

from marsscene.config import SceneConfig
from marsscene.craters import stamp_craters
from marsscene.craters.table import CraterTable
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError
from marsscene.pipeline.lod import lod_craters
from marsscene.pipeline.terrain import lod_inputs
from marsscene.rocks import place_rocks
from marsscene.rocks.table import RockTable
from marsscene.seeding import tile_rng
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.tiles import tile_terrain

__all__ = ["build_tile"]


def build_tile(config: SceneConfig, *, seed: int, row: int, col: int,
               dem: DEM | None = None) -> tuple[Heightfield, RockTable | None]:
    """Build one focus tile alone: its full-resolution terrain and its rocks.

    Equals the same tile of ``build_scene(config, seed=seed)`` (without assets, which flatten
    their pads after the tiles are built).

    Examples
    --------
    >>> import marsscene as ms
    >>> from marsscene.pipeline.tile import build_tile
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [120, 120],
    ...     "post_m": 1.0, "lod": True, "focus_size_m": 40, "tile_m": 20},
    ...     "craters": {"enabled": False}, "rocks": {"enabled": False}})
    >>> hf, rocks = build_tile(cfg, seed=1, row=1, col=0)
    >>> hf.shape, hf.bounds_xy_m
    ((81, 81), (-20.0, 0.0, 0.0, 20.0))
    """
    world, _ = lod_inputs(config, seed, dem)
    if not (0 <= row < world.tiling.count and 0 <= col < world.tiling.count):
        raise ConfigError(f"tile ({row}, {col}) is outside the {world.tiling.count} x "
                          f"{world.tiling.count} focus tiles")
    craters = None
    if config.craters.enabled:
        _, craters, _ = lod_craters(world, config.craters, seed)
    ccfg = config.craters if craters is not None else None
    hf = tile_terrain(world.coarse, world.tiling, row, col, detail=world.detail,
                      craters=craters, ccfg=ccfg, stamp=stamp_craters, base=world.base)
    rocks = None
    if config.rocks.enabled:
        table = craters if craters is not None else CraterTable.empty()
        rocks = place_rocks(hf, table, config.rocks, rng=tile_rng(seed, "rocks_tile", row, col))
    return hf, rocks
