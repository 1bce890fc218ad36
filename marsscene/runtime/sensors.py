"""Sensors: terrain from a compiled model, wheel odometry, IMU noise and a ray-cast 3D LiDAR.

All noise is drawn from a ``numpy.random.Generator`` passed in (seed it with
``stage_rng(seed, "sensors")``); nothing here touches global random state.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.runtime.config import LidarConfig, NoiseConfig, RoverConfig
from marsscene.runtime.raycast import ray_heightfield
from marsscene.runtime.rover import body_twist_from_wheels
from marsscene.terrain.heightfield import Heightfield

__all__ = ["Lidar", "WheelOdometry", "imu_measure", "measure_wheels", "scene_heightfield"]


def scene_heightfield(model: Any, geom_name: str = "terrain") -> Heightfield:
    """Rebuild the terrain :class:`Heightfield` from a compiled model's hfield geom (exact)."""
    import mujoco

    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom_name)
    if gid < 0:
        from marsscene.errors import RuntimeSimError

        raise RuntimeSimError(f"the scene has no hfield geom named {geom_name!r}")
    hid = int(model.geom_dataid[gid])
    rows, cols = int(model.hfield_nrow[hid]), int(model.hfield_ncol[hid])
    adr = int(model.hfield_adr[hid])
    rx, ry, zr, _ = (float(v) for v in model.hfield_size[hid])
    px, py, pz = (float(v) for v in model.geom_pos[gid])
    z = pz + zr * model.hfield_data[adr : adr + rows * cols].reshape(rows, cols)
    return Heightfield(z.astype(np.float32), 2 * rx / (cols - 1), (px - rx, py - ry))


def measure_wheels(
    rates_rad_s: NDArray[np.float64],
    steer_rad: NDArray[np.float64],
    noise: NoiseConfig,
    *,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Encoder readings: ``rate * (1 + slip) + n`` per wheel and ``steer + n`` per corner.

    Slip makes the wheels turn more than the rover moves (odometry over-estimates distance
    when ``slip_mean > 0``). Draws are made in a fixed order so a seed reproduces a run.
    """
    rates = np.asarray(rates_rad_s, dtype=np.float64)
    slip = noise.slip_mean + noise.slip_sigma * rng.standard_normal(rates.shape)
    meas = rates * (1.0 + slip) + noise.wheel_rate_sigma_rad_s * rng.standard_normal(rates.shape)
    steer = np.asarray(steer_rad, dtype=np.float64)
    return meas, steer + noise.steer_sigma_rad * rng.standard_normal(steer.shape)


class WheelOdometry:
    """Planar dead reckoning from wheel encoders (x, y, yaw; z and tilt are not observed).

    Each update solves the rover's wheel kinematics for ``(v, omega)`` by least squares
    (:func:`marsscene.runtime.rover.body_twist_from_wheels`) and integrates with the midpoint
    heading. The start pose is the ground-truth spawn pose, so odometry and ground truth share
    the world frame (``odom`` = ``map`` at t = 0).
    """

    def __init__(self, rover: RoverConfig, x_m: float, y_m: float, z_m: float, yaw_rad: float):
        self.rover = rover
        self.x_m, self.y_m, self.z_m, self.yaw_rad = float(x_m), float(y_m), float(z_m), yaw_rad
        self.distance_m = 0.0

    def update(
        self, rates_rad_s: NDArray[np.float64], steer_rad: NDArray[np.float64], dt_s: float
    ) -> None:
        v, w = body_twist_from_wheels(rates_rad_s, steer_rad, self.rover)
        mid = self.yaw_rad + 0.5 * w * dt_s
        self.x_m += v * dt_s * math.cos(mid)
        self.y_m += v * dt_s * math.sin(mid)
        self.yaw_rad += w * dt_s
        self.distance_m += abs(v) * dt_s

    def pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (3,) in m and quaternion (w, x, y, z) of the estimate."""
        h = 0.5 * self.yaw_rad
        return (
            np.array([self.x_m, self.y_m, self.z_m]),
            np.array([math.cos(h), 0.0, 0.0, math.sin(h)]),
        )


def imu_measure(
    accel_m_s2: NDArray[np.float64],
    gyro_rad_s: NDArray[np.float64],
    noise: NoiseConfig,
    *,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Noisy IMU sample: true value + bias + N(0, sigma) on each axis."""
    a = (
        accel_m_s2
        + np.asarray(noise.accel_bias_m_s2)
        + noise.accel_sigma_m_s2 * rng.standard_normal(3)
    )
    g = (
        gyro_rad_s
        + np.asarray(noise.gyro_bias_rad_s)
        + noise.gyro_sigma_rad_s * rng.standard_normal(3)
    )
    return a, g


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
