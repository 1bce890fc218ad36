"""The :class:`Heightfield`: terrain as a regular grid of elevations in the scene frame.

Grid convention (the only place it is defined): ``z_m[row, col]`` is the elevation of the post at
``x = origin_x + col * cell_size_m`` (east) and ``y = origin_y + row * cell_size_m`` (north), so
row 0 is the **southern** edge (MuJoCo's hfield row order). World frame: x east, y north, z up,
metres (REP-103). DEM rasters (row 0 = north) are flipped once, in :func:`from_dem`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import plain
from marsscene.errors import ConfigError

XY = tuple[NDArray[np.float64], NDArray[np.float64]]

__all__ = ["Heightfield"]


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Regular elevation grid in the scene frame.

    Parameters
    ----------
    z_m : ndarray of shape (rows, cols), float32
        Elevation of each post above the scene datum (in m). Row 0 is the southern edge.
    cell_size_m : float
        Post spacing, equal in x and y (in m).
    origin_xy_m : tuple of float
        World (x east, y north) of post ``[0, 0]``, the south-west corner (in m).
    """

    z_m: NDArray[np.float32]
    cell_size_m: float
    origin_xy_m: tuple[float, float] = field(default=(0.0, 0.0))

    def __post_init__(self) -> None:
        z = np.array(self.z_m, dtype=np.float32, copy=True)  # never freeze the caller's array
        self._adopt(z)

    @classmethod
    def _owning(cls, z_m: NDArray[np.float32], cell_size_m: float,
                origin_xy_m: tuple[float, float] = (0.0, 0.0)) -> Heightfield:
        """A heightfield that takes ``z_m`` itself (no defensive copy): for arrays made fresh
        by the caller and not used after, as the pipeline's stages do with 10^7-post grids.
        The array is made read-only."""
        hf = object.__new__(cls)
        object.__setattr__(hf, "cell_size_m", cell_size_m)
        object.__setattr__(hf, "origin_xy_m", origin_xy_m)
        hf._adopt(np.ascontiguousarray(z_m, dtype=np.float32))
        return hf

    def _adopt(self, z: NDArray[np.float32]) -> None:
        if z.ndim != 2 or min(z.shape) < 2:
            raise ConfigError(f"z_m must be a 2-D grid of at least 2x2 posts; got shape {z.shape}")
        if not np.isfinite(z).all():
            raise ConfigError("z_m contains NaN or inf; fill missing posts before building terrain")
        if not (self.cell_size_m > 0 and np.isfinite(self.cell_size_m)):
            raise ConfigError(f"cell_size_m must be > 0; got {plain(self.cell_size_m)!r}")
        z.setflags(write=False)
        object.__setattr__(self, "z_m", z)
        object.__setattr__(self, "cell_size_m", float(self.cell_size_m))
        ox, oy = self.origin_xy_m
        object.__setattr__(self, "origin_xy_m", (float(ox), float(oy)))

    # ---- geometry ---------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape ``(rows, cols)``."""
        return (int(self.z_m.shape[0]), int(self.z_m.shape[1]))

    @property
    def size_m(self) -> tuple[float, float]:
        """Footprint ``(width east, height north)`` between the outer posts (in m)."""
        rows, cols = self.shape
        return ((cols - 1) * self.cell_size_m, (rows - 1) * self.cell_size_m)

    @property
    def area_m2(self) -> float:
        """Footprint area (in m^2)."""
        w, h = self.size_m
        return w * h

    @property
    def bounds_xy_m(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` of the footprint (in m)."""
        w, h = self.size_m
        ox, oy = self.origin_xy_m
        return (ox, oy, ox + w, oy + h)

    def xy_of(self, rows: ArrayLike, cols: ArrayLike) -> XY:
        """World ``(x, y)`` of (possibly fractional) grid indices."""
        ox, oy = self.origin_xy_m
        c = np.asarray(cols, dtype=np.float64)
        r = np.asarray(rows, dtype=np.float64)
        return ox + c * self.cell_size_m, oy + r * self.cell_size_m

    def rowcol_of(self, x: ArrayLike, y: ArrayLike) -> XY:
        """Fractional grid indices ``(row, col)`` of world points (inverse of :meth:`xy_of`)."""
        ox, oy = self.origin_xy_m
        xa = np.asarray(x, dtype=np.float64)
        ya = np.asarray(y, dtype=np.float64)
        return (ya - oy) / self.cell_size_m, (xa - ox) / self.cell_size_m

    def grid_xy(self) -> XY:
        """Coordinate vectors ``(x of each col, y of each row)`` (in m)."""
        rows, cols = self.shape
        return self.xy_of(np.zeros(cols), np.arange(cols))[0], self.xy_of(np.arange(rows), 0)[1]

    def contains(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.bool_]:
        """True where ``(x, y)`` lies inside the footprint."""
        x0, y0, x1, y1 = self.bounds_xy_m
        xa = np.asarray(x)
        ya = np.asarray(y)
        return (xa >= x0) & (xa <= x1) & (ya >= y0) & (ya <= y1)

    # ---- sampling ---------------------------------------------------------------------------
    def _cell(self, x: ArrayLike, y: ArrayLike) -> tuple[Any, Any, Any, Any]:
        rows, cols = self.shape
        r, c = self.rowcol_of(x, y)
        r = np.clip(r, 0.0, rows - 1.0)
        c = np.clip(c, 0.0, cols - 1.0)
        r0 = np.minimum(np.floor(r).astype(np.int64), rows - 2)
        c0 = np.minimum(np.floor(c).astype(np.int64), cols - 2)
        return r0, c0, r - r0, c - c0

    def _corners(self, r0: Any, c0: Any) -> tuple[Any, Any, Any, Any]:
        """Posts ``[r0, c0]``, ``[r0, c0+1]``, ``[r0+1, c0]``, ``[r0+1, c0+1]`` as float64
        (flat-index gathers: one index array, four ``take``s)."""
        cols = self.shape[1]
        flat = self.z_m.ravel()
        i = r0 * cols
        i += c0
        out = []
        for step in (0, 1, cols, cols + 1):
            out.append(flat.take(i + step if step else i).astype(np.float64))
        return out[0], out[1], out[2], out[3]

    def sample(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Bilinear elevation at world points (clamped to the footprint) (in m)."""
        r0, c0, fr, fc = self._cell(x, y)
        z00, z01, z10, z11 = self._corners(r0, c0)
        return (z00 * (1 - fc) + z01 * fc) * (1 - fr) + (z10 * (1 - fc) + z11 * fc) * fr

    def gradient(self, x: ArrayLike, y: ArrayLike) -> XY:
        """Surface gradient ``(dz/dx, dz/dy)`` of the bilinear surface at world points."""
        r0, c0, fr, fc = self._cell(x, y)
        z00, z01, z10, z11 = self._corners(r0, c0)
        dzdx = ((z01 - z00) * (1 - fr) + (z11 - z10) * fr) / self.cell_size_m
        dzdy = ((z10 - z00) * (1 - fc) + (z11 - z01) * fc) / self.cell_size_m
        return dzdx, dzdy

    def normal(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Unit upward surface normal at world points, shape ``(..., 3)``."""
        gx, gy = self.gradient(x, y)
        n = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def grid_gradient(self) -> XY:
        """Central-difference gradient ``(dz/dx, dz/dy)`` at every post."""
        gy, gx = np.gradient(self.z_m.astype(np.float64), self.cell_size_m)
        return np.asarray(gx), np.asarray(gy)

    def slope_deg(self) -> NDArray[np.float64]:
        """Slope at every post (in degrees), from central differences."""
        gx, gy = self.grid_gradient()
        out: NDArray[np.float64] = np.degrees(np.arctan(np.hypot(gx, gy)))
        return out

    def grid_normals(self) -> NDArray[np.float32]:
        """Unit normals at every post, shape ``(rows, cols, 3)``."""
        rows, cols = self.shape
        return self.window_normals((0, rows), (0, cols))

    def window_normals(self, rows: tuple[int, int],
                       cols: tuple[int, int]) -> NDArray[np.float32]:
        """Unit normals of the posts ``[r0, r1) x [c0, c1)``, shape ``(r1 - r0, c1 - c0, 3)``;
        equal to that window of :meth:`grid_normals` (the gradient reads one post beyond the
        window where there is one), so a mesh can be made tile by tile.

        Computed in float32 (the output precision) from the float32 posts: differences of
        neighbouring posts lose nothing that a float32 normal keeps.
        """
        (r0, r1), (c0, c1) = rows, cols
        # -dz/dx, -dz/dy: central differences, one-sided on the grid's edge posts (as
        # np.gradient); contiguous float32 arrays, interleaved into (x, y, z) only at the end
        slopes = []
        for axis, lo, hi, size in ((1, c0, c1, self.shape[1]), (0, r0, r1, self.shape[0])):
            j = np.arange(lo, hi)
            fwd, bwd = np.minimum(j + 1, size - 1), np.maximum(j - 1, 0)
            a, b = int(bwd[0]), int(fwd[-1]) + 1  # the posts read along this axis
            z = self.z_m[r0:r1, a:b] if axis else self.z_m[a:b, c0:c1]
            diff = np.take(z, bwd - a, axis=axis) - np.take(z, fwd - a, axis=axis)
            step = ((fwd - bwd) * np.float32(self.cell_size_m)).astype(np.float32)
            diff /= step[None, :] if axis else step[:, None]
            slopes.append(diff)
        ngx, ngy = slopes
        inv = np.square(ngx)
        inv += np.square(ngy)
        inv += 1.0
        np.sqrt(inv, out=inv)
        np.reciprocal(inv, out=inv)  # 1 / |(-gx, -gy, 1)|
        n = np.zeros((r1 - r0, c1 - c0, 3), dtype=np.float32)
        np.multiply(ngx, inv, out=n[..., 0])
        np.multiply(ngy, inv, out=n[..., 1])
        n[..., 2] = inv
        return n

    def with_z(self, z_m: ArrayLike) -> Heightfield:
        """A new heightfield on the same grid with other elevations."""
        return Heightfield(np.asarray(z_m, dtype=np.float32), self.cell_size_m, self.origin_xy_m)

    def _with_owned_z(self, z_m: NDArray[np.float32]) -> Heightfield:
        """:meth:`with_z` for a fresh array the caller hands over (no defensive copy)."""
        return Heightfield._owning(z_m, self.cell_size_m, self.origin_xy_m)

    @classmethod
    def centered(cls, z_m: ArrayLike, cell_size_m: float) -> Heightfield:
        """A heightfield whose footprint is centred on the world origin."""
        z = np.asarray(z_m, dtype=np.float32)
        return cls(z, cell_size_m, _centred_origin(z.shape, cell_size_m))

    @classmethod
    def _centered_owning(cls, z_m: NDArray[np.float32], cell_size_m: float) -> Heightfield:
        """:meth:`centered` for a fresh array the caller hands over (no defensive copy)."""
        return cls._owning(z_m, cell_size_m, _centred_origin(z_m.shape, cell_size_m))


def _centred_origin(shape: tuple[int, ...], cell_size_m: float) -> tuple[float, float]:
    rows, cols = shape
    return (-(cols - 1) * cell_size_m / 2.0, -(rows - 1) * cell_size_m / 2.0)
