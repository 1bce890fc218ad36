"""The rover's local elevation map: LiDAR points in one local frame gridded to cells.

The local frame is any frame the scans' poses are given in (the odometry frame, or the rover's
body frame at the query): :func:`~marsscene.orbital.match.match_dem` estimates the pose of that
frame in the scene (x, y, yaw). A run folder's scans are in the sensor frame of their stamp
(``lidar/NNNNNN.ply``, :func:`marsscene.runs.runlog.read_ply`); their poses are the rover's
(``gt.tum`` or ``odom.tum`` at the scan stamps) composed with the LiDAR mount.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.errors import ConfigError
from marsscene.transforms import quat_to_matrix

__all__ = ["LocalMap", "local_elevation_map", "points_in_frame", "pose_matrix"]


@dataclass(frozen=True, eq=False)
class LocalMap:
    """A local elevation grid (row along local +y, column along local +x).

    Attributes
    ----------
    z_m : ndarray of shape (rows, cols), float64
        Elevation of each cell (in m, the local frame's z; any datum); NaN where unobserved.
    mask : ndarray of shape (rows, cols), bool
        Observed cells.
    cell_m : float
        Cell size (in m).
    origin_xy_m : tuple of float
        Local (x, y) of the centre of cell ``[0, 0]`` (in m).
    """

    z_m: NDArray[np.float64]
    mask: NDArray[np.bool_]
    cell_m: float
    origin_xy_m: tuple[float, float]

    @property
    def observed(self) -> int:
        """How many cells are observed."""
        return int(self.mask.sum())

    def cell_xy(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Local (x, y) of every cell centre, shape (rows, cols) each."""
        rows, cols = self.z_m.shape
        x, y = np.meshgrid(self.origin_xy_m[0] + self.cell_m * np.arange(cols),
                           self.origin_xy_m[1] + self.cell_m * np.arange(rows))
        return x, y

def pose_matrix(xyz_m: ArrayLike, quat_wxyz: ArrayLike) -> NDArray[np.float64]:
    """(..., 4, 4) homogeneous transforms of translations and unit quaternions (w, x, y, z)."""
    t = np.asarray(xyz_m, dtype=np.float64)
    out = np.zeros((*t.shape[:-1], 4, 4))
    out[..., :3, :3] = quat_to_matrix(quat_wxyz)
    out[..., :3, 3] = t
    out[..., 3, 3] = 1.0
    return out


def points_in_frame(scans: Sequence[ArrayLike], poses: ArrayLike) -> NDArray[np.float64]:
    """All scans' points (each (n_i, 3), sensor frame) in the frame of ``poses`` ((m, 4, 4),
    sensor to that frame, one per scan), stacked (sum n_i, 3)."""
    t = np.asarray(poses, dtype=np.float64).reshape(-1, 4, 4)
    if len(scans) != len(t):
        raise ConfigError(f"{len(scans)} scans but {len(t)} poses")
    parts = [np.asarray(p, dtype=np.float64).reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
             for p, m in zip(scans, t, strict=True)]
    return np.concatenate(parts) if parts else np.zeros((0, 3))


def local_elevation_map(points_xyz_m: ArrayLike, *, cell_m: float = 1.0,
                        radius_m: float | None = None, min_points: int = 3,
                        statistic: str = "mean") -> LocalMap:
    """Grid points (local frame) to a :class:`LocalMap` of ``cell_m`` cells.

    Cell centres lie on multiples of ``cell_m`` (cell ``[0, 0]`` the south-west one covering the
    points); ``radius_m`` keeps points within that horizontal distance of the local origin; a
    cell is observed with ``min_points`` points or more; its elevation is their ``"mean"`` or
    ``"min"`` (the ground under rocks and the noise floor's low side).
    """
    p = np.asarray(points_xyz_m, dtype=np.float64).reshape(-1, 3)
    p = p[np.isfinite(p).all(axis=1)]
    if radius_m is not None:
        p = p[np.hypot(p[:, 0], p[:, 1]) <= radius_m]
    if statistic not in ("mean", "min"):
        raise ConfigError(f"local map statistic must be 'mean' or 'min'; got {statistic!r}")
    if len(p) == 0:
        raise ConfigError("no LiDAR points to make a local elevation map from")
    ij = np.rint(p[:, :2] / cell_m).astype(np.int64)
    lo = ij.min(axis=0)
    cols, rows = (ij.max(axis=0) - lo + 1).tolist()
    flat = (ij[:, 1] - lo[1]) * cols + (ij[:, 0] - lo[0])
    count = np.bincount(flat, minlength=rows * cols)
    if statistic == "mean":
        z = np.bincount(flat, weights=p[:, 2], minlength=rows * cols) / np.maximum(count, 1)
    else:
        z = np.full(rows * cols, np.inf)
        np.minimum.at(z, flat, p[:, 2])
    mask = (count >= min_points).reshape(rows, cols)
    z = np.where(mask, z.reshape(rows, cols), np.nan)
    return LocalMap(z, mask, float(cell_m), (float(lo[0] * cell_m), float(lo[1] * cell_m)))
