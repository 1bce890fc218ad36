"""The Perseverance-class rover as MJCF text, and its wheel kinematics.

Layout (``base_link`` frame: x forward, y left, z up, REP-103): six wheels on a rocker-bogie
suspension with a differential (a joint equality ``rocker_left = -rocker_right``, the role of
the rover's differential bar), four steerable corner wheels (front and rear) and two fixed middle
wheels, all six driven. With steering every wheel rolls without side slip about an instantaneous
centre on the middle-axle line, so ``cmd_vel = (v, omega)`` maps exactly to wheel speeds and
steering angles (:func:`wheel_commands`) and turning in place (v = 0) is possible.
Numbers and sources: ``docs/runtime.md``.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from marsscene.export.mjcf.build import fmt
from marsscene.runtime.config import RoverConfig

__all__ = [
    "DRIVE_JOINTS",
    "STEER_JOINTS",
    "body_twists_from_wheels",
    "rover_mjcf",
    "sensor_mounts",
    "wheel_commands",
    "wheel_positions_xy",
]

#: Drive joints in order: front, middle, rear; left before right.
DRIVE_JOINTS = ("drive_fl", "drive_fr", "drive_ml", "drive_mr", "drive_rl", "drive_rr")
#: Steering joints of the four corner wheels.
STEER_JOINTS = ("steer_fl", "steer_fr", "steer_rl", "steer_rr")
_STEERED = np.array([0, 1, 4, 5])  # indices into DRIVE_JOINTS

# Masses (kg): chassis body incl. mast, arm, RTG; rockers; bogies; corner steering units; wheels.
_M_ROCKER, _M_BOGIE, _M_STEER, _M_WHEEL = 30.0, 20.0, 4.0, 20.0
_ROCKER_Y_FRAC = 0.375  # rocker pivot |y| as a fraction of the track
_PIVOT_ABOVE_GROUND_M = 0.65
_BOGIE_ABOVE_GROUND_M = 0.45
_BOGIE_HALF_M = 0.5
# Sensor mounts in base_link (m): LiDAR on the mast top, navcam at the mast height, tilted down.
_LIDAR_X_M, _LIDAR_ABOVE_CAMERA_M = 0.7, 0.12
_CAMERA_X_M, _CAMERA_TILT_DEG = 0.75, 20.0


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


def wheel_commands(
    v_m_s: float, omega_rad_s: float, cfg: RoverConfig
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Map ``cmd_vel`` to wheel rates and corner steering angles (no-side-slip kinematics).

    Parameters
    ----------
    v_m_s : float
        Forward speed of ``base_link`` (in m/s).
    omega_rad_s : float
        Yaw rate (in rad/s), positive counter-clockwise seen from above.
    cfg : RoverConfig

    Returns
    -------
    rates : ndarray of shape (6,)
        Wheel angular speeds (in rad/s), positive = rolling forward (DRIVE_JOINTS order).
    steer : ndarray of shape (4,)
        Steering angles of the corner wheels (in rad), STEER_JOINTS order, within +-pi/2.
    """
    xy = _wheel_xy(cfg)
    vx = v_m_s - omega_rad_s * xy[:, 1]
    vy = omega_rad_s * xy[:, 0]
    delta = np.arctan2(vy, vx)
    speed = np.hypot(vx, vy)
    flip = np.abs(delta) > math.pi / 2 + 1e-12
    delta = np.where(flip, delta - math.pi * np.sign(delta), delta)
    speed = np.where(flip, -speed, speed)
    delta = np.where(speed == 0.0, 0.0, delta)
    steer = delta[_STEERED]
    return speed / cfg.wheel_radius_m, steer


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
    sol = _odometry_pinv(cfg) @ b
    return float(sol[0]), float(sol[1])


def body_twists_from_wheels(
    rates_rad_s: NDArray[np.float64], steer_rad: NDArray[np.float64], cfg: RoverConfig
) -> NDArray[np.float64]:
    """Vectorised :func:`body_twist_from_wheels`: (N, 6) rates, (N, 4) steering -> (N, 2)."""
    rates = np.asarray(rates_rad_s, dtype=np.float64).reshape(-1, 6)
    delta = np.zeros_like(rates)
    delta[:, _STEERED] = np.asarray(steer_rad, dtype=np.float64).reshape(-1, 4)
    u = cfg.wheel_radius_m * rates
    b = np.concatenate([u * np.cos(delta), u * np.sin(delta)], axis=1)
    return np.asarray(b @ _odometry_pinv(cfg).T, dtype=np.float64)


def sensor_mounts(cfg: RoverConfig) -> dict[str, tuple[tuple[float, float, float], float]]:
    """Sensor mounts in ``base_link``: ``{name: ((x, y, z) in m, pitch in rad)}``.

    ``lidar`` and ``camera`` (the navcam body: x forward, y left, z up, pitched down by
    ``pitch``); the IMU sits at the ``base_link`` origin. The MJCF below uses the same numbers.
    """
    mast = cfg.mast_height_m - cfg.ride_height_m
    return {
        "imu": ((0.0, 0.0, 0.0), 0.0),
        "lidar": ((_LIDAR_X_M, 0.0, mast + _LIDAR_ABOVE_CAMERA_M), 0.0),
        "camera": ((_CAMERA_X_M, 0.0, mast), math.radians(_CAMERA_TILT_DEG)),
    }


@lru_cache(maxsize=16)
def _odometry_pinv(cfg: RoverConfig) -> NDArray[np.float64]:
    xy = _wheel_xy(cfg)
    a = np.zeros((12, 2))
    a[:6, 0] = 1.0
    a[:6, 1] = -xy[:, 1]
    a[6:, 1] = xy[:, 0]
    return np.asarray(np.linalg.pinv(a), dtype=np.float64)


def _body(name: str, pos: tuple[float, float, float], inner: str) -> str:
    return f'<body name="{name}" pos="{fmt(pos)}">{inner}</body>'


def _wheel(cfg: RoverConfig, tag: str, pos: tuple[float, float, float], steered: bool) -> str:
    r, hw = cfg.wheel_radius_m, cfg.wheel_width_m / 2.0
    if cfg.wheel_collision == "cylinder":
        geom = (
            f'<geom name="wheel_{tag}" class="wheel" type="cylinder" size="{fmt((r, hw))}" '
            f'quat="0.707107 0.707107 0 0" mass="{fmt(_M_WHEEL)}"/>'
        )
    else:  # collision sphere + visual cylinder
        geom = (
            f'<geom name="wheel_{tag}" class="wheel" type="sphere" size="{fmt(r)}" '
            f'rgba="0 0 0 0" mass="{fmt(_M_WHEEL)}"/>'
            f'<geom class="visual" type="cylinder" size="{fmt((r, hw))}" '
            f'quat="0.707107 0.707107 0 0" rgba="0.6 0.6 0.6 1" mass="0"/>'
        )
    wheel = _body(
        f"wheel_{tag}",
        (0.0, 0.0, 0.0),
        f'<joint name="drive_{tag}" type="hinge" axis="0 1 0" armature="0.5" damping="0.5"/>'
        + geom,
    )
    if not steered:
        return _body(f"hub_{tag}", pos, wheel)
    lim = cfg.steer_limit_rad
    steer = (
        f'<joint name="steer_{tag}" type="hinge" axis="0 0 1" range="{fmt((-lim, lim))}" '
        f'armature="1" damping="50"/>'
        f'<geom class="visual" type="cylinder" size="0.05 0.15" pos="0 0 0.2" '
        f'mass="{fmt(_M_STEER)}"/>'
    )
    return _body(f"steer_{tag}", pos, steer + wheel)


def _side(cfg: RoverConfig, side: str, sign: float) -> str:
    r, ride = cfg.wheel_radius_m, cfg.ride_height_m
    y_rocker = sign * _ROCKER_Y_FRAC * cfg.track_m
    dy = sign * cfg.track_m / 2.0 - y_rocker
    s = side[0]
    pz = _PIVOT_ABOVE_GROUND_M
    bz = _BOGIE_ABOVE_GROUND_M - pz
    xb = -cfg.wheelbase_rear_m + _BOGIE_HALF_M  # bogie pivot x
    xf = cfg.wheelbase_front_m
    front = _wheel(cfg, f"f{s}", (xf, dy, r - pz), True)
    mid = _wheel(cfg, f"m{s}", (_BOGIE_HALF_M, dy, r - _BOGIE_ABOVE_GROUND_M), False)
    rear = _wheel(cfg, f"r{s}", (-_BOGIE_HALF_M, dy, r - _BOGIE_ABOVE_GROUND_M), True)
    bogie = _body(
        f"bogie_{side}",
        (xb, 0.0, bz),
        f'<joint name="bogie_{side}" type="hinge" axis="0 1 0" range="-0.6 0.6" damping="20"/>'
        f'<geom class="visual" type="capsule" '
        f'fromto="{fmt((-_BOGIE_HALF_M, 0, 0, _BOGIE_HALF_M, 0, 0))}" '
        f'size="0.05" mass="{fmt(_M_BOGIE)}"/>' + mid + rear,
    )
    rocker = (
        f'<joint name="rocker_{side}" type="hinge" axis="0 1 0" range="-0.5 0.5" damping="20"/>'
        f'<geom class="visual" type="capsule" fromto="{fmt((xb, 0, bz, xf, 0, r - pz + 0.2))}" '
        f'size="0.06" mass="{fmt(_M_ROCKER)}"/>' + front + bogie
    )
    return _body(f"rocker_{side}", (0.0, y_rocker, pz - ride), rocker)


def rover_mjcf(cfg: RoverConfig | None = None, *, camera_fovy_deg: float = 60.0) -> str:
    """MJCF text of the rover: root body ``base_link`` (free joint), actuators and sensors.

    Collision: wheels and chassis collide with the terrain and rocks (contype 2 / conaffinity 1,
    so rover parts never collide with each other); links are visual only (group 2).
    """
    cfg = cfg if cfg is not None else RoverConfig()
    chassis_kg = cfg.mass_kg - 2 * (_M_ROCKER + _M_BOGIE) - 4 * _M_STEER - 6 * _M_WHEEL
    ride, mast = cfg.ride_height_m, cfg.mast_height_m - cfg.ride_height_m
    tilt = math.radians(_CAMERA_TILT_DEG)
    cam_axes = fmt((0, -1, 0, math.sin(tilt), 0, math.cos(tilt)))
    mu = fmt((cfg.friction, 0.02, 0.002))
    base = (
        '<freejoint name="root"/>'
        f'<geom name="chassis" class="body" type="box" size="0.9 0.55 0.2" pos="0 0 0.05" '
        f'mass="{fmt(chassis_kg)}"/>'
        f'<geom class="visual" type="cylinder" size="0.06 {fmt(mast / 2)}" '
        f'pos="{fmt((0.7, 0.0, 0.25 + mast / 2 - 0.125))}" mass="0"/>'
        '<site name="imu" pos="0 0 0" size="0.02"/>'
        f'<site name="lidar" pos="{fmt((_LIDAR_X_M, 0.0, mast + _LIDAR_ABOVE_CAMERA_M))}" '
        'size="0.03"/>'
        f'<camera name="navcam" pos="{fmt((_CAMERA_X_M, 0.0, mast))}" xyaxes="{cam_axes}" '
        f'fovy="{fmt(camera_fovy_deg)}"/>' + _side(cfg, "left", 1.0) + _side(cfg, "right", -1.0)
    )
    lim, tq = cfg.wheel_speed_limit_rad_s, cfg.drive_torque_limit_nm
    acts = "".join(
        f'<velocity name="{j}" joint="{j}" kv="{fmt(cfg.drive_kv_nm_s)}" '
        f'ctrlrange="{fmt((-lim, lim))}" forcerange="{fmt((-tq, tq))}"/>'
        for j in DRIVE_JOINTS
    ) + "".join(
        f'<position name="{j}" joint="{j}" kp="{fmt(cfg.steer_kp_nm)}" kv="200" '
        f'ctrlrange="{fmt((-cfg.steer_limit_rad, cfg.steer_limit_rad))}" '
        f'forcerange="{fmt((-cfg.steer_torque_limit_nm, cfg.steer_torque_limit_nm))}"/>'
        for j in STEER_JOINTS
    )
    return (
        '<mujoco model="rover">\n'
        '  <compiler angle="radian" autolimits="true"/>\n'
        "  <default>\n"
        f'    <default class="wheel"><geom contype="2" conaffinity="1" condim="3" group="2" '
        f'friction="{mu}" rgba="0.6 0.6 0.6 1"/></default>\n'
        '    <default class="body"><geom contype="2" conaffinity="1" condim="3" group="2" '
        'rgba="0.85 0.85 0.8 1"/></default>\n'
        '    <default class="visual"><geom contype="0" conaffinity="0" group="2" '
        'rgba="0.4 0.4 0.4 1"/></default>\n'
        "  </default>\n"
        f'  <worldbody><body name="base_link" pos="0 0 {fmt(ride)}">{base}</body></worldbody>\n'
        '  <equality><joint name="differential" joint1="rocker_left" joint2="rocker_right" '
        'polycoef="0 -1 0 0 0"/></equality>\n'
        f"  <actuator>{acts}</actuator>\n"
        '  <sensor><accelerometer name="imu_accel" site="imu"/><gyro name="imu_gyro" site="imu"/>'
        "</sensor>\n"
        "</mujoco>\n"
    )
