"""Assets (habitats, landers): placement on levelled ground, procedural habitat (pure, except
:mod:`marsscene.assets.io`, which reads files)."""

from marsscene.assets.config import AssetConfig
from marsscene.assets.habitat import habitat_model
from marsscene.assets.model import AssetModel, PlacedAsset
from marsscene.assets.site import clear_rocks, find_site, level_site, place_assets

__all__ = [
    "AssetConfig",
    "AssetModel",
    "PlacedAsset",
    "clear_rocks",
    "find_site",
    "habitat_model",
    "level_site",
    "place_assets",
]
