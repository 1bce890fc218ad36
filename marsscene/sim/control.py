"""The controller seam of a drive: what a controller sees each control step, and what it returns.

A **controller** is any callable ``controller(obs) -> (v_m_s, omega_rad_s)``, called once per
control period (``RunConfig.control_hz``, 50 Hz by default) with an :class:`Observation`. The
drive stops after the step at which the controller's optional ``done`` attribute is true (as
:class:`~marsscene.sim.pursuit.PurePursuit` sets it at the goal) or at the time limit.

What an observation holds at control time ``t``: the wheel encoders read at ``t`` and the wheel
odometry integrated up to ``t`` (the rover's own pose estimate), the latest IMU sample, camera
frame and LiDAR scan taken **before** ``t`` (sensors sample after the control step of their
tick, as a real rover's drivers deliver data before the planner's next cycle), the command in
force, and the ground-truth pose. Ground truth is privileged: a fair autonomy stack reads only
the measured fields; pure pursuit on ground truth is the MarsLab paper's route-following
protocol, and rewards of learning environments use it.

Examples
--------
A controller that drives a circle for 20 s and stops when the odometry says it went 5 m:

>>> import math
>>> class Circle:
...     done = False
...     def __call__(self, obs):
...         self.done = math.hypot(*obs.odom_xyz_m[:2]) > 5.0
...         return 0.3, 0.1
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

__all__ = ["CameraFrame", "Controller", "Observation", "OnStart", "OpenLoop"]


@runtime_checkable
class Controller(Protocol):
    """``controller(obs) -> (v_m_s, omega_rad_s)``; an optional ``done`` attribute ends the
    drive after the step at which it turns true."""

    def __call__(self, obs: Observation) -> tuple[float, float]: ...


class CameraFrame:
    """One navcam frame: ``t_s``, ``rgb`` (H, W, 3) uint8 and ``depth_m`` (H, W) float32 in m
    (None when depth is off)."""

    __slots__ = ("depth_m", "rgb", "t_s")

    def __init__(self, t_s: float, rgb: NDArray[np.uint8], depth_m: NDArray[np.float32] | None):
        self.t_s, self.rgb, self.depth_m = t_s, rgb, depth_m

    def __repr__(self) -> str:
        return f"CameraFrame(t_s={self.t_s:.3f}, rgb={self.rgb.shape})"


class Observation:
    """What a controller sees at one control step (read-only; arrays are copies).

    Attributes
    ----------
    t_s : float
        Simulation time of the control step.
    step : int
        Index of the control step (0 at the start).
    odom_xyz_m, odom_quat_wxyz : ndarray
        Wheel-odometry pose of ``base_link`` in the ``odom`` frame (= map at t = 0).
    odom_yaw_rad : float
    wheel_rates_rad_s : ndarray of shape (6,)
        Measured wheel speeds (noisy encoders), front, middle, rear, left before right.
    steer_rad : ndarray of shape (4,)
        Measured corner steering angles.
    imu_t_s : float or None
        Time of the latest IMU sample (None before the first one).
    accel_m_s2, gyro_rad_s : ndarray of shape (3,) or None
        The latest IMU sample (noisy, body frame, specific force incl. gravity).
    cmd : tuple of float
        The ``(v, omega)`` in force before this step.
    gt_xyz_m, gt_quat_wxyz, gt_yaw_rad
        Ground-truth ``base_link`` pose in ``map`` (privileged).
    camera : CameraFrame or None
        The latest navcam frame (None without the camera or before the first frame).
    lidar : dict or None
        The latest LiDAR scan (``t``, ``xyz_m`` (N, 3) in the LiDAR frame, ``range_m``,
        ``intensity``, ``ring``, ``t_s``), fetched when first read.
    """

    __slots__ = (
        "_lidar",
        "accel_m_s2",
        "camera",
        "cmd",
        "gt_quat_wxyz",
        "gt_xyz_m",
        "gt_yaw_rad",
        "gyro_rad_s",
        "imu_t_s",
        "odom_quat_wxyz",
        "odom_xyz_m",
        "odom_yaw_rad",
        "steer_rad",
        "step",
        "t_s",
        "wheel_rates_rad_s",
    )

    t_s: float
    step: int
    odom_xyz_m: NDArray[np.float64]
    odom_quat_wxyz: NDArray[np.float64]
    odom_yaw_rad: float
    wheel_rates_rad_s: NDArray[np.float64]
    steer_rad: NDArray[np.float64]
    imu_t_s: float | None
    accel_m_s2: NDArray[np.float64] | None
    gyro_rad_s: NDArray[np.float64] | None
    cmd: tuple[float, float]
    gt_xyz_m: NDArray[np.float64]
    gt_quat_wxyz: NDArray[np.float64]
    gt_yaw_rad: float
    camera: CameraFrame | None

    def __init__(self, **values: Any) -> None:
        self._lidar: Callable[[], dict[str, Any] | None] = values.pop("lidar")
        for key, value in values.items():
            setattr(self, key, value)

    @property
    def lidar(self) -> dict[str, Any] | None:
        return self._lidar()

    def __repr__(self) -> str:
        x, y, _ = self.odom_xyz_m
        return f"Observation(t_s={self.t_s:.3f}, step={self.step}, odom_xy_m=({x:.2f}, {y:.2f}))"


class OpenLoop:
    """A fixed command, or a function of time ``command(t_s) -> (v, omega)``, as a controller."""

    def __init__(self, command: tuple[float, float] | Callable[[float], tuple[float, float]]):
        self.command = command

    def __call__(self, obs: Observation) -> tuple[float, float]:
        cmd = self.command(obs.t_s) if callable(self.command) else self.command
        v, w = cmd
        return v, w

    def __repr__(self) -> str:
        return f"OpenLoop({self.command!r})"


@dataclass(frozen=True)
class OnStart:
    """A controller made from the prepared simulator, just before the first control step.

    Pass it as ``controller`` to :func:`marsscene.drive` when the controller needs the rover
    it drives (its sensors, intrinsics, start pose), as the live ROS 2 bridge does to describe
    its topics. ``make(sim)`` returns the controller; with ``listen`` it also receives every
    sample as a listener of the session (:mod:`marsscene.sim.session`).
    """

    make: Callable[[Any], Any]
    listen: bool = False
