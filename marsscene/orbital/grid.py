"""The :class:`OrbitalMap`: an orbital DTM (and orthoimage) of a scene as south-up scene grids."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.orbital.model import OrbitalModel

__all__ = ["OrbitalMap", "sample_bilinear"]


def sample_bilinear(grid: NDArray[np.floating], origin_xy_m: tuple[float, float], cell_m: float,
                    x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
    """Bilinear value of a south-up grid (row along +y, post (0, 0) at ``origin_xy_m``) at
    scene points; NaN outside the grid (and where a neighbouring post is NaN)."""
    g = np.asarray(grid, dtype=np.float64)
    rows, cols = g.shape
    u = (np.asarray(x_m, dtype=np.float64) - origin_xy_m[0]) / cell_m
    v = (np.asarray(y_m, dtype=np.float64) - origin_xy_m[1]) / cell_m
    inside = (u >= 0) & (u <= cols - 1) & (v >= 0) & (v <= rows - 1)
    c0 = np.clip(np.floor(u), 0, cols - 2).astype(np.int64)
    r0 = np.clip(np.floor(v), 0, rows - 2).astype(np.int64)
    fu, fv = np.clip(u - c0, 0, 1), np.clip(v - r0, 0, 1)
    top = g[r0, c0] * (1 - fu) + g[r0, c0 + 1] * fu
    bot = g[r0 + 1, c0] * (1 - fu) + g[r0 + 1, c0 + 1] * fu
    return np.where(inside, top * (1 - fv) + bot * fv, np.nan)


@dataclass(frozen=True, eq=False)
class OrbitalMap:
    """What an orbiter sees of a scene, in the scene frame.

    Attributes
    ----------
    dem_m : ndarray of shape (rows, cols), float32
        Elevation in the scene's z (``(elevation - datum) * z_scale``), row 0 = south; NaN
        where the input DTM has no data.
    cell_m : float
        Post spacing of ``dem_m`` (in m).
    origin_xy_m : tuple of float
        Scene (x, y) of post ``[0, 0]`` (the south-west post) (in m).
    image : ndarray of shape (rows, cols), float32, optional
        Orthoimage (reflectance-like, panchromatic), row 0 = south; ``None`` without one.
    image_pixel_m : float, optional
        Pixel size of ``image`` (in m).
    image_origin_xy_m : tuple of float, optional
        Scene (x, y) of the centre of image pixel ``[0, 0]`` (in m).
    crs_wkt : str
        The scene frame's CRS ("" for a procedural scene: scene metres).
    origin_projected_xy_m : tuple of float, optional
        Projected (x, y) of the scene origin (the frame's), or ``None``.
    source : str
        ``"dem"`` (the input DTM as it is) or ``"procedural"`` (the terrain through ``model``).
    model : OrbitalModel
        The model of a procedural map (recorded for a DEM one, which does not use it).
    seed : int
        The scene's seed (the noise's stream: ``stage_rng(seed, "orbital")``).
    """

    dem_m: NDArray[np.float32]
    cell_m: float
    origin_xy_m: tuple[float, float]
    source: str
    model: OrbitalModel
    seed: int
    image: NDArray[np.float32] | None = None
    image_pixel_m: float | None = None
    image_origin_xy_m: tuple[float, float] | None = None
    crs_wkt: str = ""
    origin_projected_xy_m: tuple[float, float] | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """DTM grid shape ``(rows, cols)``."""
        return (int(self.dem_m.shape[0]), int(self.dem_m.shape[1]))

    @property
    def bounds_xy_m(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` of the DTM's outer posts (in m)."""
        rows, cols = self.shape
        x0, y0 = self.origin_xy_m
        return (x0, y0, x0 + (cols - 1) * self.cell_m, y0 + (rows - 1) * self.cell_m)

    def elevation_at(self, x_m: ArrayLike, y_m: ArrayLike) -> NDArray[np.float64]:
        """Bilinear DTM elevation at scene points (NaN outside the map)."""
        return sample_bilinear(self.dem_m, self.origin_xy_m, self.cell_m, x_m, y_m)
