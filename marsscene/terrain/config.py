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
    landform: str = "fbm"
    """Procedural landform: "fbm" (none), "plain", "crater" or "canyon"
    (:mod:`marsscene.landforms`); ignored with a DEM."""
    landform_size_m: float | None = None
    """Crater rim diameter or canyon floor width (in m); default scales with the footprint."""
    landform_depth_m: float | None = None
    """Canyon depth (in m; default 250); a crater's depth follows the fresh d/D law."""
    detail: bool = True
    """Add seeded fractal detail below the DEM's resolution when upsampling."""
    detail_rms_m: float | None = None
    """RMS of the added detail (in m); default continues the DEM's own spectrum."""
    z_scale: float = 1.0
    """Vertical exaggeration applied to elevations relative to the datum."""
    ortho_path: str | None = None
    """Orthoimage draped as the terrain texture (HiRISE .LBL+.JP2, GeoTIFF, ISIS3 .cub)."""
    band: int | None = None
    """1-based elevation band; required for multi-band DEMs."""
    crop_px: tuple[int, int, int, int] | None = None
    """DEM crop as a pixel window ``[row_off, col_off, rows, cols]``."""
    crop_bounds_m: tuple[float, float, float, float] | None = None
    """DEM crop as projected bounds ``[x_min, y_min, x_max, y_max]`` (in m)."""
    crop_lonlat: tuple[float, float] | None = None
    """DEM crop centre ``[east lon, lat]`` (in deg, planetocentric); size from ``size_m``.
    With a DEM, ``size_m`` alone crops around the DEM's centre."""
    resampling: str | None = None
    """"bilinear", "cubic" or "area"; default area when coarsening, else bilinear."""
    fill_nodata: bool = True
    """Fill missing DEM posts by Laplace inpainting (else nearest valid post)."""
    max_missing_fraction: float = 0.5
    """Refuse a DEM crop with more than this fraction of missing posts."""
    detrend: bool = False
    """Remove the DEM's best-fit plane (keeps the mean elevation)."""
    max_memory_gb: float = 8.0
    """Refuse a DEM build whose estimated memory exceeds this (in GB)."""
    texture_max_px: int = 4096
    """Largest side of the draped orthoimage texture (in pixels)."""
    lod: bool | str = "auto"
    """Two-level terrain (:mod:`marsscene.terrain.lod`): ``focus_post_m`` posts over the focus
    square, ``post_m`` posts over the whole footprint outside it (with a DEM: the DEM's posts,
    snapped to a whole multiple of ``focus_post_m``). ``"auto"`` (default): one grid unless a
    procedural terrain's full-resolution grid would exceed the post budget, or a DEM crop's
    grid would be refused (too many posts, or over ``max_memory_gb``; decided from the DEM's
    header), then two levels (the build says so; see
    :func:`marsscene.pipeline.terrain.resolve_lod`)."""
    focus_xy_m: tuple[float, float] | None = None
    """Centre of the full-resolution focus square (in m, scene frame); default the origin."""
    focus_size_m: float = 1000.0
    """Side of the focus square (in m)."""
    focus_post_m: float = 0.25
    """Post spacing inside the focus square (in m); ``post_m`` must be a whole multiple."""
    lod_blend_m: float = 100.0
    """Width of the outer band over which the coarse terrain is bent onto the focus border."""
    tile_m: float = 500.0
    """Side of a focus tile (in m, snapped to whole ``post_m`` cells); each tile's terrain and
    rocks are built independently of the others (:mod:`marsscene.terrain.tiles`)."""

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
        check_choice("terrain.landform", self.landform, ("fbm", "plain", "crater", "canyon"))
        for key in ("landform_size_m", "landform_depth_m"):
            if getattr(self, key) is not None:
                check_range(f"terrain.{key}", getattr(self, key), 0.0, 100_000.0, lo_open=True)
        check_range("terrain.rms_height_m", self.rms_height_m, 0.0, 10_000.0)
        if self.rms_slope_deg is not None:
            check_range("terrain.rms_slope_deg", self.rms_slope_deg, 0.0, 60.0, lo_open=True)
        if self.detail_rms_m is not None:
            check_range("terrain.detail_rms_m", self.detail_rms_m, 0.0, 100.0)
        check_range("terrain.z_scale", self.z_scale, 0.0, 100.0, lo_open=True)
        for key in ("detail", "fill_nodata", "detrend"):
            if not isinstance(getattr(self, key), bool):
                raise ConfigError(f"terrain.{key} must be true or false; "
                                  f"got {getattr(self, key)!r}")
        self._check_dem_keys()
        self._check_lod_keys()

    def _check_lod_keys(self) -> None:
        if not isinstance(self.lod, bool) and self.lod != "auto":
            raise ConfigError(f'terrain.lod must be true, false or "auto"; got {self.lod!r}')
        if self.focus_xy_m is not None and len(self.focus_xy_m) != 2:
            raise ConfigError(f"terrain.focus_xy_m must be [x, y]; got {self.focus_xy_m!r}")
        check_range("terrain.focus_size_m", self.focus_size_m, 0.0, 20_000.0, lo_open=True)
        check_range("terrain.focus_post_m", self.focus_post_m, 0.0, 100.0, lo_open=True)
        check_range("terrain.lod_blend_m", self.lod_blend_m, 0.0, 10_000.0)
        check_range("terrain.tile_m", self.tile_m, 0.0, 20_000.0, lo_open=True)

    def _check_dem_keys(self) -> None:
        crops = [k for k in ("crop_px", "crop_bounds_m", "crop_lonlat") if getattr(self, k)]
        dem_keys = [*crops, *(["ortho_path"] if self.ortho_path else [])]
        if self.source == "procedural" and dem_keys:
            raise ConfigError(f"terrain.{dem_keys[0]} needs a DEM; terrain.source = "
                              f'"procedural" has none')
        if len(crops) > 1:
            raise ConfigError(f"give at most one of terrain.crop_px, crop_bounds_m, "
                              f"crop_lonlat; got {crops}")
        if self.crop_px is not None:
            if len(self.crop_px) != 4 or any(
                isinstance(v, bool) or not isinstance(v, int) for v in self.crop_px
            ):
                raise ConfigError(f"terrain.crop_px = {self.crop_px!r}: need 4 integers "
                                  "[row_off, col_off, rows, cols]")
            if min(self.crop_px[:2]) < 0 or min(self.crop_px[2:]) < 2:
                raise ConfigError(f"terrain.crop_px = {list(self.crop_px)}: need offsets >= 0 "
                                  "and rows, cols >= 2")
        if self.crop_bounds_m is not None:
            b = self.crop_bounds_m
            if len(b) != 4 or not (b[2] > b[0] and b[3] > b[1]):
                raise ConfigError(f"terrain.crop_bounds_m = {b!r}: need [x_min, y_min, "
                                  "x_max, y_max] with min < max")
        if self.crop_lonlat is not None:
            if len(self.crop_lonlat) != 2:
                raise ConfigError(f"terrain.crop_lonlat = {self.crop_lonlat!r}: need [lon, lat]")
            check_range("terrain.crop_lonlat longitude", self.crop_lonlat[0], -180.0, 360.0)
            check_range("terrain.crop_lonlat latitude", self.crop_lonlat[1], -90.0, 90.0)
            if self.size_m is None:
                raise ConfigError("terrain.crop_lonlat needs terrain.size_m = [width, height] "
                                  "(in m)")
        if self.band is not None and (isinstance(self.band, bool) or not isinstance(
                self.band, int) or self.band < 1):
            raise ConfigError(f"terrain.band = {self.band!r}: need an integer >= 1")
        if self.resampling is not None:
            check_choice("terrain.resampling", self.resampling, ("bilinear", "cubic", "area"))
        check_range("terrain.max_missing_fraction", self.max_missing_fraction, 0.0, 1.0)
        check_range("terrain.max_memory_gb", self.max_memory_gb, 0.0, 1e4, lo_open=True)
        if isinstance(self.texture_max_px, bool) or not isinstance(self.texture_max_px, int):
            raise ConfigError(f"terrain.texture_max_px = {self.texture_max_px!r}: need an integer")
        check_range("terrain.texture_max_px", self.texture_max_px, 16, 16384)

    @property
    def effective_size_m(self) -> tuple[float, float]:
        return self.size_m if self.size_m is not None else (200.0, 200.0)
