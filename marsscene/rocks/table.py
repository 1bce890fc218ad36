"""The :class:`RockTable`: placed rocks as column arrays."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["RockTable"]


@dataclass(frozen=True, eq=False)
class RockTable:
    """Rocks as columns (one row per rock).

    Attributes
    ----------
    position_xyz_m : ndarray of shape (N, 3)
        Rock base centre in the scene frame (in m): on the terrain, lowered by ``burial_m``.
    diameter_m : ndarray of shape (N,)
        Horizontal diameter (in m).
    height_m : ndarray of shape (N,)
        Exposed height above the surface (in m).
    burial_m : ndarray of shape (N,)
        Depth of the rock's base below the local surface (in m).
    orientation_wxyz : ndarray of shape (N, 4)
        Unit quaternion (w, x, y, z) from prototype frame to scene frame.
    prototype : ndarray of shape (N,), int
        Index into the scene's rock prototypes.
    scale_xyz_m : ndarray of shape (N, 3), optional
        Scale applied to the unit prototype (x, y in [-0.5, 0.5], z in [0, 1], base at z = 0)
        before rotation: (long axis, short axis, total height = height + burial) (in m).
        Defaults to ``(D, D, height + burial)``.
    """

    position_xyz_m: NDArray[np.float64]
    diameter_m: NDArray[np.float64]
    height_m: NDArray[np.float64]
    burial_m: NDArray[np.float64]
    orientation_wxyz: NDArray[np.float64]
    prototype: NDArray[np.int64]
    scale_xyz_m: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        n = len(self.diameter_m)
        scale = self.scale_xyz_m
        if scale is None:
            d = np.asarray(self.diameter_m, dtype=np.float64)
            total = np.asarray(self.height_m, dtype=np.float64) + np.asarray(
                self.burial_m, dtype=np.float64
            )
            scale = np.column_stack([d, d, total]) if n else np.zeros((0, 3))
        cols = {
            "position_xyz_m": np.asarray(self.position_xyz_m, dtype=np.float64).reshape(n, 3),
            "diameter_m": np.asarray(self.diameter_m, dtype=np.float64),
            "height_m": np.asarray(self.height_m, dtype=np.float64),
            "burial_m": np.asarray(self.burial_m, dtype=np.float64),
            "orientation_wxyz": np.asarray(self.orientation_wxyz, dtype=np.float64).reshape(n, 4),
            "prototype": np.asarray(self.prototype, dtype=np.int64),
            "scale_xyz_m": np.asarray(scale, dtype=np.float64).reshape(n, 3),
        }
        for name, arr in cols.items():
            if arr.shape[0] != n:
                raise ValueError(f"RockTable.{name} has {arr.shape[0]} rows; expected {n}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.diameter_m.shape[0])

    @classmethod
    def empty(cls) -> RockTable:
        z = np.zeros(0)
        return cls(np.zeros((0, 3)), z, z, z, np.zeros((0, 4)), np.zeros(0, dtype=np.int64))

    def take(self, index: NDArray[np.int64] | NDArray[np.bool_]) -> RockTable:
        """A new table with the selected rows."""
        assert self.scale_xyz_m is not None
        return RockTable(
            self.position_xyz_m[index],
            self.diameter_m[index],
            self.height_m[index],
            self.burial_m[index],
            self.orientation_wxyz[index],
            self.prototype[index],
            scale_xyz_m=self.scale_xyz_m[index],
        )
