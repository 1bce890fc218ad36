"""Terrain stage configuration (``[terrain]`` table)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError

__all__ = ["TERRAIN_SOURCES", "TerrainConfig"]

TERRAIN_SOURCES = ("default", "procedural", "dem")


@dataclass(frozen=True, slots=True, kw_only=True)
class TerrainConfig:
    """Where the terrain comes from and how it is resampled.

    ``source = "default"`` uses the bundled 1 m Gale crater DEM (MMGIS, Apache-2.0),
    ``"procedural"`` synthesises a self-affine surface, ``"dem"`` reads ``dem_path``.
    """

    source: str = "default"
    """"default", "procedural" or "dem"."""
    dem_path: str | None = None
    """DEM file (PDS3 .IMG/.LBL, ISIS3 .cub, GeoTIFF) for ``source = "dem"``."""
    size_m: tuple[float, float] | None = None
    """Procedural terrain footprint (width east, height north) (in m); default 200 x 200."""
    post_m: float | None = None
    """Output post spacing (in m). Default 0.25 for default/procedural, native for a DEM."""
    hurst: float = 0.8
    """Hurst exponent of procedural terrain and sub-DEM detail, in (0, 1]."""
    rms_height_m: float = 1.0
    """RMS height of procedural terrain (in m)."""
    rms_slope_deg: float | None = None
    """If set, scale procedural terrain to this RMS slope instead of ``rms_height_m`` (in deg)."""
    detail: bool = True
    """Add seeded fractal detail below the DEM's resolution when upsampling."""
    detail_rms_m: float | None = None
    """RMS of the added detail (in m); default continues the DEM's own spectrum."""
    z_scale: float = 1.0
    """Vertical exaggeration applied to elevations relative to the datum."""

    def __post_init__(self) -> None:
        check_choice("terrain.source", self.source, TERRAIN_SOURCES)
        if self.source == "dem" and not self.dem_path:
            raise ConfigError('terrain.source = "dem" needs terrain.dem_path')
        if self.size_m is not None:
            if len(self.size_m) != 2:
                raise ConfigError(f"terrain.size_m must be [width, height]; got {self.size_m!r}")
            for v in self.size_m:
                check_range("terrain.size_m", v, 0.0, 100_000.0, lo_open=True)
        if self.post_m is not None:
            check_range("terrain.post_m", self.post_m, 0.0, 1000.0, lo_open=True)
        check_range("terrain.hurst", self.hurst, 0.0, 1.0, lo_open=True)
        check_range("terrain.rms_height_m", self.rms_height_m, 0.0, 10_000.0)
        if self.rms_slope_deg is not None:
            check_range("terrain.rms_slope_deg", self.rms_slope_deg, 0.0, 60.0, lo_open=True)
        if self.detail_rms_m is not None:
            check_range("terrain.detail_rms_m", self.detail_rms_m, 0.0, 100.0)
        check_range("terrain.z_scale", self.z_scale, 0.0, 100.0, lo_open=True)
        if not isinstance(self.detail, bool):
            raise ConfigError(f"terrain.detail must be true or false; got {self.detail!r}")

    @property
    def effective_size_m(self) -> tuple[float, float]:
        return self.size_m if self.size_m is not None else (200.0, 200.0)
