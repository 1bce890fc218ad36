"""The :class:`DEM` and :class:`Ortho` value objects: north-up rasters in projected metres.

Pixel convention (GDAL "area"): ``transform`` maps the upper-left **corner** of pixel
``(row, col)``; the elevation post sits at the pixel **centre**, ``(col + 0.5, row + 0.5)``.
:meth:`DEM.xy_of` / :meth:`DEM.rowcol_of` are the only grid <-> projected conversions.
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.errors import ConfigError

__all__ = ["DEM", "Ortho"]

Transform = tuple[float, float, float, float, float, float]


def _check_transform(transform: Any) -> Transform:
    t = tuple(float(v) for v in transform)
    if len(t) != 6:
        raise ConfigError(f"transform must have 6 numbers (a, b, c, d, e, f); got {transform!r}")
    a, b, _, d, e, _ = t
    if b != 0 or d != 0 or a <= 0 or e >= 0:
        raise ConfigError(
            f"transform must be north-up and unrotated (a > 0, b = d = 0, e < 0); got {t}"
        )
    return (t[0], t[1], t[2], t[3], t[4], t[5])


class _Georef:
    """Grid <-> projected helpers shared by :class:`DEM` and :class:`Ortho`."""

    transform: Transform

    @property
    @abstractmethod
    def shape(self) -> tuple[int, int]:
        """Grid shape ``(rows, cols)`` (defined by each raster class)."""

    def xy_of(
        self, rows: ArrayLike, cols: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Projected ``(x, y)`` (in m) of the centres of (fractional) pixels ``(row, col)``."""
        a, _, c, _, e, f = self.transform
        return (
            c + a * (np.asarray(cols, dtype=np.float64) + 0.5),
            f + e * (np.asarray(rows, dtype=np.float64) + 0.5),
        )

    def rowcol_of(
        self, x_m: ArrayLike, y_m: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Fractional ``(row, col)`` whose pixel centre is at projected ``(x, y)``."""
        a, _, c, _, e, f = self.transform
        return (
            (np.asarray(y_m, dtype=np.float64) - f) / e - 0.5,
            (np.asarray(x_m, dtype=np.float64) - c) / a - 0.5,
        )

    @property
    def bounds_xy_m(self) -> tuple[float, float, float, float]:
        """Outer pixel edges ``(x_min, y_min, x_max, y_max)`` (in m)."""
        a, _, c, _, e, f = self.transform
        rows, cols = self.shape
        return (c, f + e * rows, c + a * cols, f)

    @property
    def post_bounds_xy_m(self) -> tuple[float, float, float, float]:
        """Extent of the pixel *centres* ``(x_min, y_min, x_max, y_max)`` (in m): the terrain
        footprint between the outer posts."""
        rows, cols = self.shape
        x, y = self.xy_of([rows - 1, 0], [0, cols - 1])
        return (float(x[0]), float(y[0]), float(x[1]), float(y[1]))

    def center_xy(self) -> tuple[float, float]:
        """Projected (x, y) of the raster's centre (in m)."""
        x0, y0, x1, y1 = self.bounds_xy_m
        return ((x0 + x1) / 2.0, (y0 + y1) / 2.0)


@dataclass(frozen=True, eq=False)
class Ortho(_Georef):
    """An orthoimage: reflectance-like values on a north-up grid.

    Parameters
    ----------
    image : ndarray of shape (rows, cols, bands), float32
        Calibrated values (DN * scale + offset, e.g. I/F); NaN marks missing pixels. Row 0 north.
    transform : tuple of 6 floats
        Affine of the upper-left pixel corner (rasterio order), projected metres.
    crs_wkt : str
    source_path : str
    metadata : dict
    """

    image: NDArray[np.float32]
    transform: Transform
    crs_wkt: str = ""
    source_path: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        img = np.array(self.image, dtype=np.float32, copy=True)  # never freeze the caller's
        if img.ndim == 2:
            img = img[:, :, None]
        if img.ndim != 3 or min(img.shape[:2]) < 1 or img.shape[2] not in (1, 3, 4):
            raise ConfigError(f"ortho image must be (rows, cols, 1|3|4); got {img.shape}")
        img.setflags(write=False)
        object.__setattr__(self, "image", img)
        object.__setattr__(self, "transform", _check_transform(self.transform))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.image.shape[0]), int(self.image.shape[1]))

    @property
    def pixel_m(self) -> float:
        """Pixel size (in m)."""
        return self.transform[0]


@dataclass(frozen=True, eq=False)
class DEM(_Georef):
    """A digital elevation model as read from disk.

    Parameters
    ----------
    elevation_m : ndarray of shape (rows, cols), float32
        Elevation above the source datum (in m); NaN marks missing posts. Row 0 is the northern
        edge (raster order).
    transform : tuple of 6 floats
        Affine ``(a, b, c, d, e, f)`` (rasterio/affine order) mapping (col, row) of a pixel's
        upper-left corner to projected (x, y) in metres: ``x = a*col + b*row + c``,
        ``y = d*col + e*row + f``. Must be north-up and unrotated.
    crs_wkt : str
        Projected CRS as WKT or PROJ string ("" if unknown).
    source_path : str
        Where it was read from ("" if built in memory).
    metadata : dict
        Label metadata (product id, projection keywords, MAP_SCALE, centre lat/lon, radius, ...).
    center_lonlat_deg : tuple of float or None
        Planetocentric east longitude (0-360) and latitude of the raster centre (in degrees).
    ortho : Ortho, optional
        Orthoimage of (at least) the same footprint, on its own grid.
    """

    elevation_m: NDArray[np.float32]
    transform: Transform
    crs_wkt: str = ""
    source_path: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)
    center_lonlat_deg: tuple[float, float] | None = None
    ortho: Ortho | None = None

    def __post_init__(self) -> None:
        z = np.array(self.elevation_m, dtype=np.float32, copy=True)  # caller's array untouched
        if z.ndim != 2 or min(z.shape) < 2:
            raise ConfigError(f"elevation_m must be a 2-D grid of at least 2x2; got {z.shape}")
        z.setflags(write=False)
        object.__setattr__(self, "elevation_m", z)
        object.__setattr__(self, "transform", _check_transform(self.transform))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.elevation_m.shape[0]), int(self.elevation_m.shape[1]))

    @property
    def post_m(self) -> float:
        """Post spacing (in m); the raster must have square pixels."""
        a, _, _, _, e, _ = self.transform
        if not np.isclose(abs(a), abs(e), rtol=1e-6):
            raise ConfigError(f"DEM pixels must be square; transform = {self.transform}")
        return abs(a)

    @property
    def valid_fraction(self) -> float:
        """Fraction of posts that are not missing."""
        return float(np.isfinite(self.elevation_m).mean())

    @property
    def product_id(self) -> str:
        """Label ``PRODUCT_ID`` (or the file stem, or "")."""
        pid = self.metadata.get("PRODUCT_ID")
        if pid:
            return str(pid)
        return self.source_path.replace("\\", "/").rsplit("/", 1)[-1].rsplit(".", 1)[0]

    def replace(self, **changes: Any) -> DEM:
        """A copy with some fields replaced (validated again)."""
        return replace(self, **changes)
