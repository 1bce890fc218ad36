"""Wheel encoders and wheel odometry with seeded noise.

All noise is drawn from a ``numpy.random.Generator`` passed in (seed it with
``stage_rng(seed, "sensors")``); nothing here touches global random state.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import body_twist_from_wheels

__all__ = ["BatchWheelOdometry", "WheelOdometry", "measure_wheels"]


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
    (:func:`marsscene.rover.geometry.body_twist_from_wheels`) and integrates with the midpoint
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


class BatchWheelOdometry:
    """:class:`WheelOdometry` of N rovers at once: arrays (N,) of the estimate, each row
    integrated as :meth:`WheelOdometry.update` integrates one (the batched drives' odometry)."""

    def __init__(self, rover: RoverConfig, xyz_m: NDArray[np.float64],
                 yaw_rad: NDArray[np.float64]):
        self.rover = rover
        xyz = np.asarray(xyz_m, dtype=np.float64)
        self.x_m, self.y_m, self.z_m = xyz[:, 0].copy(), xyz[:, 1].copy(), xyz[:, 2].copy()
        self.yaw_rad = np.asarray(yaw_rad, dtype=np.float64).copy()

    def update(self, rates_rad_s: NDArray[np.float64], steer_rad: NDArray[np.float64],
               dt_s: float, moving: NDArray[np.bool_]) -> None:
        """One control step of the rovers where ``moving`` (N,) bool; the others hold."""
        from marsscene.rover.geometry import body_twists_from_wheels

        vw = body_twists_from_wheels(rates_rad_s, steer_rad, self.rover)
        v, w = np.where(moving, vw[:, 0], 0.0), np.where(moving, vw[:, 1], 0.0)
        mid = self.yaw_rad + 0.5 * w * dt_s
        self.x_m = self.x_m + v * dt_s * np.cos(mid)
        self.y_m = self.y_m + v * dt_s * np.sin(mid)
        self.yaw_rad = self.yaw_rad + w * dt_s

    def pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Positions (N, 3) in m and quaternions (N, 4) (w, x, y, z) of the estimates."""
        h, zero = 0.5 * self.yaw_rad, np.zeros_like(self.yaw_rad)
        return (np.column_stack([self.x_m, self.y_m, self.z_m]),
                np.column_stack([np.cos(h), zero, zero, np.sin(h)]))
