"""A ray-cast spinning 3D LiDAR: heightfield march plus MuJoCo rays for rocks."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import LidarConfig
from marsscene.sensors.raycast import ray_heightfield
from marsscene.terrain.heightfield import Heightfield

__all__ = ["Lidar"]


class Lidar:
    """A spinning multi-channel LiDAR by MuJoCo ray casting (``mj_multiRay``).

    Rays start at the ``lidar`` site and see scene geoms only (groups 0 and 1; the rover's geoms
    are in group 2). Returns points in the sensor frame (x forward, y left, z up) with an
    intensity ``|cos(incidence)| * exp(-2 alpha r)``: dust attenuates intensity, never range.
    """

    def __init__(self, config: LidarConfig):
        self.config = config
        lo, hi = np.radians(config.vertical_fov_deg)
        elev = np.linspace(lo, hi, config.channels) if config.channels > 1 else np.array([lo])
        azim = np.arange(config.horizontal_samples) * (2 * math.pi / config.horizontal_samples)
        e, a = np.meshgrid(elev, azim, indexing="ij")
        self.ring = np.repeat(np.arange(config.channels), config.horizontal_samples)
        self.dirs_sensor = np.stack(
            [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1
        ).reshape(-1, 3)
        self._geomid = np.zeros(len(self.dirs_sensor), dtype=np.int32)
        self._dist = np.zeros(len(self.dirs_sensor), dtype=np.float64)
        self._normal = np.zeros((len(self.dirs_sensor), 3), dtype=np.float64)
        self._groups = np.array([1, 1, 0, 0, 0, 0], dtype=np.uint8)

    def scan(
        self, model: Any, data: Any, site_id: int, terrain: Heightfield | None = None
    ) -> dict[str, NDArray[Any]]:
        """One full sweep at the current state.

        With ``terrain`` the heightfield is ray-marched in numpy (fast on large terrains) and
        MuJoCo rays see geom groups 0 and 1 only (``RoverSim`` moves its terrain geom to
        group 3); without it MuJoCo casts against groups 0, 1 and 3.

        Returns
        -------
        dict with ``xyz_m`` (N, 3) float32 (sensor frame), ``intensity`` (N,) float32 in [0, 1],
        ``ring`` (N,) uint16, ``range_m`` (N,) float32 — only rays that hit within range.
        """
        import mujoco

        rot = data.site_xmat[site_id].reshape(3, 3)
        origin = data.site_xpos[site_id].copy()
        dirs_world = self.dirs_sensor @ rot.T
        n = len(dirs_world)
        rmin, rmax = self.config.range_m
        groups = self._groups if terrain is not None else np.array([1, 1, 0, 1, 0, 0], np.uint8)
        mujoco.mj_multiRay(
            model,
            data,
            origin,
            dirs_world.ravel(),
            groups,
            1,
            -1,
            self._geomid,
            self._dist,
            self._normal.ravel(),
            n,
            rmax,
        )
        dist = np.where(self._geomid >= 0, self._dist, np.inf)
        normals = self._normal.reshape(-1, 3).copy()
        if terrain is not None:
            t_dist, t_normal = ray_heightfield(terrain, origin, dirs_world, (rmin, rmax))
            closer = t_dist < dist
            dist = np.where(closer, t_dist, dist)
            normals[closer] = t_normal[closer]
        hit = np.isfinite(dist) & (dist >= rmin) & (dist <= rmax)
        r = dist[hit]
        cos_inc = np.abs(np.einsum("ij,ij->i", normals[hit], dirs_world[hit]))
        intensity = cos_inc * np.exp(-2.0 * self.config.dust_extinction_per_m * r)
        return {
            "xyz_m": (self.dirs_sensor[hit] * r[:, None]).astype(np.float32),
            "intensity": intensity.astype(np.float32),
            "ring": self.ring[hit].astype(np.uint16),
            "range_m": r.astype(np.float32),
        }
