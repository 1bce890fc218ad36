"""The Perseverance-class rover's geometry and wheel kinematics (no MuJoCo; the kinematics take
numpy or PyTorch batches).

Layout (``base_link`` frame: x forward, y left, z up, REP-103): six wheels on a rocker-bogie
suspension with a differential (a joint equality ``rocker_left = -rocker_right``, the role of
the rover's differential bar), four steerable corner wheels (front and rear) and two fixed middle
wheels, all six driven. With steering every wheel rolls without side slip about an instantaneous
centre on the middle-axle line, so ``cmd_vel = (v, omega)`` maps exactly to wheel speeds and
steering angles (:func:`wheel_commands`) and turning in place (v = 0) is possible.
Numbers and sources: :doc:`/runtime`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from array_api_compat import device
from numpy.typing import NDArray

from marsscene._xp import namespace
from marsscene.rover.config import PERSEVERANCE_BODY as _P
from marsscene.rover.config import RoverConfig, rover_body

__all__ = [
    "DRIVE_JOINTS",
    "STEER_JOINTS",
    "body_twist_from_wheels",
    "body_twists_from_wheels",
    "navcam_mount",
    "sensor_mounts",
    "wheel_commands",
    "wheel_positions_xy",
]

#: Drive joints in order: front, middle, rear; left before right.
DRIVE_JOINTS = ("drive_fl", "drive_fr", "drive_ml", "drive_mr", "drive_rl", "drive_rr")
#: Steering joints of the four corner wheels.
STEER_JOINTS = ("steer_fl", "steer_fr", "steer_rl", "steer_rr")
_STEERED = [0, 1, 4, 5]  # indices into DRIVE_JOINTS

# The Perseverance-class rover's suspension and sensor mounts (a rover type's own: its
# RoverConfig body, marsscene.rover.config.rover_body).
ROCKER_Y_FRAC = _P.rocker_y_frac  # rocker pivot |y| as a fraction of the track
PIVOT_ABOVE_GROUND_M = _P.pivot_above_ground_m
BOGIE_ABOVE_GROUND_M = _P.bogie_above_ground_m
BOGIE_HALF_M = _P.bogie_half_m
# Sensor mounts in base_link (m): LiDAR on the mast top, navcam at the mast height, tilted down.
LIDAR_X_M, LIDAR_ABOVE_CAMERA_M = _P.lidar_x_m, _P.lidar_above_camera_m
CAMERA_X_M, CAMERA_TILT_DEG = _P.camera_x_m, _P.camera_tilt_deg


def wheel_positions_xy(cfg: RoverConfig) -> NDArray[np.float64]:
    """Nominal wheel contact points in ``base_link`` (x, y), shape (6, 2), order of DRIVE_JOINTS."""
    return _wheel_xy(cfg).copy()


@lru_cache(maxsize=16)
def _wheel_xy(cfg: RoverConfig) -> NDArray[np.float64]:
    half = cfg.track_m / 2.0
    xs = (
        cfg.wheelbase_front_m,
        cfg.wheelbase_front_m,
        0.0,
        0.0,
        -cfg.wheelbase_rear_m,
        -cfg.wheelbase_rear_m,
    )
    ys = (half, -half) * 3
    return np.column_stack([xs, ys]).astype(np.float64)


def wheel_commands(v_m_s: Any, omega_rad_s: Any, cfg: RoverConfig) -> tuple[Any, Any]:
    """Map ``cmd_vel`` to wheel rates and corner steering angles (no-side-slip kinematics).

    Parameters
    ----------
    v_m_s : float or array of shape (...)
        Forward speed of ``base_link`` (in m/s): a number, or a numpy / PyTorch batch.
    omega_rad_s : float or array of shape (...)
        Yaw rate (in rad/s), positive counter-clockwise seen from above.
    cfg : RoverConfig

    Returns
    -------
    rates : array of shape (..., 6)
        Wheel angular speeds (in rad/s), positive = rolling forward (DRIVE_JOINTS order).
    steer : array of shape (..., 4)
        Steering angles of the corner wheels (in rad), STEER_JOINTS order, within +-pi/2.
    """
    xp, v, w = _batch(v_m_s, omega_rad_s)
    xy = _wheel_xy(cfg) if isinstance(v, np.ndarray) else xp.asarray(_wheel_xy(cfg),
                                                                       device=device(v))
    vx = v[..., None] - w[..., None] * xy[:, 1]
    vy = w[..., None] * xy[:, 0]
    delta = xp.atan2(vy, vx)
    speed = xp.hypot(vx, vy)
    flip = xp.abs(delta) > math.pi / 2 + 1e-12
    delta = xp.where(flip, delta - math.pi * xp.sign(delta), delta)
    speed = xp.where(flip, -speed, speed)
    delta = xp.where(speed == 0.0, xp.zeros_like(delta), delta)
    return speed / cfg.wheel_radius_m, delta[..., _STEERED]


def body_twist_from_wheels(
    rates_rad_s: NDArray[np.float64], steer_rad: NDArray[np.float64], cfg: RoverConfig
) -> tuple[float, float]:
    """Least-squares ``(v, omega)`` of ``base_link`` from wheel rates and steering (odometry).

    Inverse of :func:`wheel_commands`: every wheel's ground velocity
    ``r * rate * (cos d, sin d) = (v - omega * y, omega * x)`` gives two linear equations.
    """
    delta = np.zeros(6)
    delta[_STEERED] = steer_rad
    u = cfg.wheel_radius_m * np.asarray(rates_rad_s, dtype=np.float64)
    b = np.concatenate([u * np.cos(delta), u * np.sin(delta)])
    sol = _odometry_pinv(cfg) @ b  # one rover: a matrix-vector product (the odometry's bits)
    return float(sol[0]), float(sol[1])


def body_twists_from_wheels(rates_rad_s: Any, steer_rad: Any, cfg: RoverConfig) -> Any:
    """Batched :func:`body_twist_from_wheels`: (N, 6) rates, (N, 4) steering -> (N, 2)
    ``(v, omega)`` (any leading shape; one rover's (6,) and (4,) count as N = 1); numpy or
    PyTorch arrays (float64)."""
    xp = namespace(rates_rad_s, steer_rad)
    rates = xp.astype(rates_rad_s, xp.float64)
    steer = xp.astype(steer_rad, xp.float64)
    if rates.ndim == 1:
        rates, steer = rates[None, :], steer[None, :]
    delta = xp.zeros_like(rates)
    delta[..., _STEERED] = steer
    u = cfg.wheel_radius_m * rates
    b = xp.concat([u * xp.cos(delta), u * xp.sin(delta)], axis=-1)
    pinv = xp.asarray(_odometry_pinv(cfg), device=device(rates))
    return b @ pinv.T


def _batch(*values: Any) -> tuple[Any, ...]:
    """The array namespace of ``values`` (numpy for plain numbers) and the values as float64
    arrays of it."""
    arrays = [v for v in values if hasattr(v, "__array_namespace__") or hasattr(v, "dtype")]
    if not arrays or all(isinstance(v, np.ndarray | np.generic) for v in arrays):
        return (namespace(np.zeros(0)), *(np.asarray(v, dtype=np.float64) for v in values))
    xp = namespace(*arrays)
    return (xp, *(xp.asarray(v, dtype=xp.float64, device=device(arrays[0])) for v in values))


def sensor_mounts(cfg: RoverConfig) -> dict[str, tuple[tuple[float, float, float], float]]:
    """Sensor mounts in ``base_link``: ``{name: ((x, y, z) in m, pitch in rad)}``.

    ``lidar`` and ``camera`` (the navcam body: x forward, y left, z up, pitched down by
    ``pitch``); the IMU sits at the ``base_link`` origin. The MJCF below uses the same numbers.
    """
    mast, b = cfg.mast_height_m - cfg.ride_height_m, rover_body(cfg)
    return {
        "imu": ((0.0, 0.0, 0.0), 0.0),
        "lidar": ((b.lidar_x_m, 0.0, mast + b.lidar_above_camera_m), 0.0),
        "camera": ((b.camera_x_m, 0.0, mast), math.radians(b.camera_tilt_deg)),
    }


def navcam_mount(cfg: RoverConfig) -> tuple[tuple[float, float, float], tuple[float, ...]]:
    """The mast camera's position in the chassis body frame (m) and its MJCF ``xyaxes`` (the
    camera's x and y axes in that frame; it looks along its -z, tilted down by
    ``CAMERA_TILT_DEG``)."""
    b = rover_body(cfg)
    tilt = math.radians(b.camera_tilt_deg)
    mast = cfg.mast_height_m - cfg.ride_height_m
    return (b.camera_x_m, 0.0, mast), (0.0, -1.0, 0.0, math.sin(tilt), 0.0, math.cos(tilt))


@lru_cache(maxsize=16)
def _odometry_pinv(cfg: RoverConfig) -> NDArray[np.float64]:
    xy = _wheel_xy(cfg)
    a = np.zeros((12, 2))
    a[:6, 0] = 1.0
    a[:6, 1] = -xy[:, 1]
    a[6:, 1] = xy[:, 0]
    return np.asarray(np.linalg.pinv(a), dtype=np.float64)
