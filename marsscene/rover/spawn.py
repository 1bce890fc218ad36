"""Where the rover is put down on a terrain (pure numpy): the pose the MuJoCo runtime spawns
it at and the USD rover is placed at, before it settles onto its wheels."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError
from marsscene.rover.config import RoverConfig
from marsscene.transforms import quat_from_yaw_normal

__all__ = ["SETTLE_S", "spawn_pose"]

#: Settling time of a spawned rover in s (wheels on the ground, brakes on) before time 0: the
#: default of ``RoverSim`` and ``DriveOptions.settle_s``.
SETTLE_S = 3.0


def spawn_pose(hf: Any, xy: tuple[float, float], yaw: float,
               cfg: RoverConfig) -> NDArray[np.float64]:
    """``base_link`` pose over the terrain at ``xy`` (m) heading ``yaw`` (rad, from east).

    A plane fitted to the terrain (9 x 9 samples) under the rover's footprint gives roll and
    pitch; the body sits ``ride_height_m`` above that plane along its normal, plus the highest
    bump above the plane and 1 cm, so no wheel starts inside the ground.

    Parameters
    ----------
    hf : Heightfield
        Anything with ``contains(x, y)``, ``sample(x, y)`` and ``bounds_xy_m``.
    xy : tuple of float
    yaw : float
    cfg : RoverConfig

    Returns
    -------
    ndarray of shape (7,)
        Position (m) and quaternion (w, x, y, z).

    Raises
    ------
    RuntimeSimError
        When the footprint leaves the terrain.
    """
    x, y = float(xy[0]), float(xy[1])
    half = max(cfg.wheelbase_front_m, cfg.wheelbase_rear_m) + 0.6
    if not bool(hf.contains(x - half, y - half) & hf.contains(x + half, y + half)):
        x0, y0, x1, y1 = hf.bounds_xy_m
        raise RuntimeSimError(
            f"spawn point ({x:.2f}, {y:.2f}) m is outside the terrain or closer than "
            f"{half:.2f} m to its edge; terrain spans x [{x0:.2f}, {x1:.2f}], "
            f"y [{y0:.2f}, {y1:.2f}] m"
        )
    # Plane fitted to the terrain under the rover footprint gives roll and pitch.
    g = np.linspace(-half, half, 9)
    gx, gy = np.meshgrid(x + g, y + g)
    gz = hf.sample(gx, gy)
    a = np.column_stack([gx.ravel() - x, gy.ravel() - y, np.ones(gz.size)])
    (sx, sy, z0), *_ = np.linalg.lstsq(a, gz.ravel(), rcond=None)
    normal = np.array([-sx, -sy, 1.0]) / math.sqrt(sx * sx + sy * sy + 1.0)
    clearance = float(np.max(gz.ravel() - a @ np.array([sx, sy, z0])))  # bumps above plane
    quat = quat_from_yaw_normal(yaw, normal)
    pos = np.array([x, y, z0]) + normal * (cfg.ride_height_m + max(clearance, 0) + 0.01)
    return np.concatenate([pos, quat])
