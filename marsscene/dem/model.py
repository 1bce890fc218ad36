"""The :class:`DEM` value object: a north-up elevation raster in projected metres."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError

__all__ = ["DEM"]


@dataclass(frozen=True, eq=False)
class DEM:
    """A digital elevation model as read from disk.

    Parameters
    ----------
    elevation_m : ndarray of shape (rows, cols), float32
        Elevation above the source datum (in m); NaN marks missing posts. Row 0 is the northern
        edge (raster order).
    transform : tuple of 6 floats
        Affine ``(a, b, c, d, e, f)`` (rasterio/affine order) mapping (col, row) of a pixel's
        upper-left corner to projected (x, y) in metres: ``x = a*col + b*row + c``,
        ``y = d*col + e*row + f``.
    crs_wkt : str
        Projected CRS as WKT ("" if unknown).
    source_path : str
        Where it was read from ("" if built in memory).
    metadata : dict
        Label metadata (product id, projection keywords, MAP_SCALE, centre lat/lon, radius, ...).
    center_lonlat_deg : tuple of float or None
        Planetocentric east longitude and latitude of the raster centre (in degrees).
    """

    elevation_m: NDArray[np.float32]
    transform: tuple[float, float, float, float, float, float]
    crs_wkt: str = ""
    source_path: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)
    center_lonlat_deg: tuple[float, float] | None = None
    ortho: NDArray[np.uint8] | None = None

    def __post_init__(self) -> None:
        z = np.asarray(self.elevation_m, dtype=np.float32)
        if z.ndim != 2 or min(z.shape) < 2:
            raise ConfigError(f"elevation_m must be a 2-D grid of at least 2x2; got {z.shape}")
        z.setflags(write=False)
        object.__setattr__(self, "elevation_m", z)
        object.__setattr__(self, "transform", tuple(float(v) for v in self.transform))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.elevation_m.shape[0]), int(self.elevation_m.shape[1]))

    @property
    def post_m(self) -> float:
        """Post spacing (in m); the raster must have square, unrotated pixels."""
        a, b, _, d, e, _ = self.transform
        if b != 0 or d != 0 or not np.isclose(abs(a), abs(e), rtol=1e-6):
            raise ConfigError(
                f"DEM pixels must be square and unrotated; transform = {self.transform}"
            )
        return abs(a)

    @property
    def valid_fraction(self) -> float:
        """Fraction of posts that are not missing."""
        return float(np.isfinite(self.elevation_m).mean())

    def center_xy(self) -> tuple[float, float]:
        """Projected (x, y) of the raster's centre (in m)."""
        a, b, c, d, e, f = self.transform
        rows, cols = self.shape
        return (a * cols / 2 + b * rows / 2 + c, d * cols / 2 + e * rows / 2 + f)
