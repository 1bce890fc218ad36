"""The Perseverance-class rover as MJCF text (the geometry lives in
:mod:`marsscene.rover.geometry`). Numbers and sources: ``docs/runtime.md``.
"""

from __future__ import annotations

from marsscene._format import fmt
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import (
    BOGIE_ABOVE_GROUND_M,
    BOGIE_HALF_M,
    DRIVE_JOINTS,
    LIDAR_ABOVE_CAMERA_M,
    LIDAR_X_M,
    PIVOT_ABOVE_GROUND_M,
    ROCKER_Y_FRAC,
    STEER_JOINTS,
    navcam_mount,
)

__all__ = ["rover_mjcf"]

# Masses (kg): chassis body incl. mast, arm, RTG; rockers; bogies; corner steering units; wheels.
_M_ROCKER, _M_BOGIE, _M_STEER, _M_WHEEL = 30.0, 20.0, 4.0, 20.0


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
    y_rocker = sign * ROCKER_Y_FRAC * cfg.track_m
    dy = sign * cfg.track_m / 2.0 - y_rocker
    s = side[0]
    pz = PIVOT_ABOVE_GROUND_M
    bz = BOGIE_ABOVE_GROUND_M - pz
    xb = -cfg.wheelbase_rear_m + BOGIE_HALF_M  # bogie pivot x
    xf = cfg.wheelbase_front_m
    front = _wheel(cfg, f"f{s}", (xf, dy, r - pz), True)
    mid = _wheel(cfg, f"m{s}", (BOGIE_HALF_M, dy, r - BOGIE_ABOVE_GROUND_M), False)
    rear = _wheel(cfg, f"r{s}", (-BOGIE_HALF_M, dy, r - BOGIE_ABOVE_GROUND_M), True)
    bogie = _body(
        f"bogie_{side}",
        (xb, 0.0, bz),
        f'<joint name="bogie_{side}" type="hinge" axis="0 1 0" range="-0.6 0.6" damping="20"/>'
        f'<geom class="visual" type="capsule" '
        f'fromto="{fmt((-BOGIE_HALF_M, 0, 0, BOGIE_HALF_M, 0, 0))}" '
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
    cam_pos, cam_xyaxes = navcam_mount(cfg)
    cam_axes = fmt(cam_xyaxes)
    mu = fmt((cfg.friction, 0.02, 0.002))
    base = (
        '<freejoint name="root"/>'
        f'<geom name="chassis" class="body" type="box" size="0.9 0.55 0.2" pos="0 0 0.05" '
        f'mass="{fmt(chassis_kg)}"/>'
        f'<geom class="visual" type="cylinder" size="0.06 {fmt(mast / 2)}" '
        f'pos="{fmt((0.7, 0.0, 0.25 + mast / 2 - 0.125))}" mass="0"/>'
        '<site name="imu" pos="0 0 0" size="0.02"/>'
        f'<site name="lidar" pos="{fmt((LIDAR_X_M, 0.0, mast + LIDAR_ABOVE_CAMERA_M))}" '
        'size="0.03"/>'
        f'<camera name="navcam" pos="{fmt(cam_pos)}" xyaxes="{cam_axes}" '
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
