"""Export configuration (``[export]`` table)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError

__all__ = ["EXPORT_FORMATS", "ROCK_CATALOGUES", "USD_FORMATS", "ExportConfig"]

EXPORT_FORMATS = ("usd", "mjcf")
USD_FORMATS = ("usda", "usdc", "usdz")
ROCK_CATALOGUES = ("csv", "parquet", "both")


@dataclass(frozen=True, slots=True, kw_only=True)
class ExportConfig:
    """What to write and how."""

    formats: tuple[str, ...] = ("usd", "mjcf")
    """Outputs to write: any of "usd", "mjcf"."""
    usd_format: str = "usda"
    """Root USD layer encoding: "usda" (text), "usdc" (binary crate) or "usdz" (package)."""
    max_tile_posts: int = 513
    """Largest terrain mesh tile, in posts per side (bounds the vertex count per USD prim)."""
    rock_catalogue: str = "csv"
    """Rock catalogue file(s): "csv" (``rocks.csv``), "parquet" (``rocks.parquet``, needs
    pyarrow: extra ``parquet``) or "both"."""

    def __post_init__(self) -> None:
        if isinstance(self.formats, str) or not self.formats:
            raise ConfigError(f"export.formats must be a non-empty list; got {self.formats!r}")
        for f in self.formats:
            check_choice("export.formats", f, EXPORT_FORMATS)
        check_choice("export.usd_format", self.usd_format, USD_FORMATS)
        check_choice("export.rock_catalogue", self.rock_catalogue, ROCK_CATALOGUES)
        check_range("export.max_tile_posts", self.max_tile_posts, 2, 4097)
