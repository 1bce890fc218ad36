"""Array content of the rover's ROS messages (numpy + scipy, vectorised over rows of samples).

The steps that :mod:`.compose_state` and :mod:`.compose_sensors` compose, each testable on its
own: ``map -> odom`` from ground truth and odometry, body twists, joint states, the odometry's
6 x 6 covariances, one LaserScan ring, depth images to metres and to organised point clouds.
The bag calls them on a whole run, the live publisher on its latest samples.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene._validate import dataclass_from_mapping
from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import body_twists_from_wheels

__all__ = [
    "body_twist_from_poses",
    "depth_m",
    "depth_points",
    "joint_states",
    "laser_scan",
    "map_to_odom",
    "noise_of_run",
    "odometry_covariance_rows",
    "rate_of_change",
]


def rate_of_change(values: NDArray[np.float64], t_s: NDArray[np.float64]) -> NDArray[np.float64]:
    """d(values)/dt along the rows (N >= 2): ``np.gradient`` (central differences inside,
    one-sided at the ends); for two rows, their difference quotient, as ``np.gradient``
    computes it, without its set-up (a live stream's two latest samples, every step)."""
    if len(t_s) == 2:
        d = (values[1:] - values[:1]) / (t_s[1] - t_s[0])
        return np.concatenate([d, d])
    return np.gradient(values, t_s, axis=0)


def map_to_odom(
    gt_xyz_m: NDArray[np.float64], gt_rot: Rotation, odom_xyz_m: NDArray[np.float64],
    odom_rot: Rotation,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``T_map_odom = T_map_base (GT) * T_odom_base^-1 (odometry)``, row by row.

    Positions (N, 3) and orientations (scipy ``Rotation`` of N) of ground truth and odometry
    at the same stamps; returns translations (N, 3) and quaternions (N, 4, x y z w).
    """
    rot = gt_rot * odom_rot.inv()
    return gt_xyz_m - rot.apply(odom_xyz_m), rot.as_quat()


def body_twist_from_poses(
    t_s: NDArray[np.float64], xyz_m: NDArray[np.float64], rot: Rotation
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Body-frame linear (m/s) and angular (rad/s) velocity, (N, 3) each, of poses at stamps
    ``t_s`` (positions (N, 3), orientations a ``Rotation`` of N): central differences inside,
    one-sided ones at the ends (``np.gradient``); zero for a single pose."""
    t = t_s
    if len(t) < 2:
        return np.zeros((len(t), 3)), np.zeros((len(t), 3))
    v_world = rate_of_change(xyz_m, t)
    rotvec = np.zeros((len(t), 3))
    step = (rot[:-1].inv() * rot[1:]).as_rotvec() / np.diff(t)[:, None]  # body rates per interval
    rotvec[1:-1] = 0.5 * (step[:-1] + step[1:])
    rotvec[0], rotvec[-1] = step[0], step[-1]
    return rot.inv().apply(v_world), rotvec


def joint_states(
    wheels: NDArray[np.float64], rover: RoverConfig
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Joint positions and velocities from ``wheels.csv`` rows, plus the odometry twist.

    Drive-joint angles integrate the measured rates (rectangle rule, from 0); steering angles
    are the measured ones, their rates central differences. Returns ``position`` (N, 10),
    ``velocity`` (N, 10) in DRIVE_JOINTS + STEER_JOINTS order and ``twist`` (N, 2) = (v, omega)
    solved from the wheels as the odometry does.
    """
    t, rates, steer = wheels[:, 0], wheels[:, 1:7], wheels[:, 7:11]
    dt = np.diff(t, prepend=t[0])
    angle = np.cumsum(rates * dt[:, None], axis=0)
    steer_rate = rate_of_change(steer, t) if len(t) > 1 else np.zeros_like(steer)
    return (
        np.hstack([angle, steer]),
        np.hstack([rates, steer_rate]),
        body_twists_from_wheels(rates, steer, rover),
    )


def laser_scan(scan: NDArray[Any], lidar: dict[str, Any]) -> dict[str, Any]:
    """One LaserScan from the ring nearest to horizontal (REP-117: +inf = no return).

    Ranges are the 3-D beam ranges of that ring, binned by azimuth over [0, 2 pi).
    """
    n = int(lidar["horizontal_samples"])
    if "vertical_angles_deg" in lidar:  # rings are the beams sorted by elevation, lowest first
        elev = np.sort(np.asarray(lidar["vertical_angles_deg"], dtype=np.float64))
    else:  # run folders written before named models: uniform beams
        channels, (lo, hi) = int(lidar["channels"]), lidar["vertical_fov_deg"]
        elev = np.linspace(lo, hi, channels) if channels > 1 else np.array([lo])
    ring = int(np.argmin(np.abs(elev)))
    pts = scan[scan["ring"] == ring]
    inc = 2.0 * np.pi / n
    idx = np.round(np.arctan2(pts["y"], pts["x"]) / inc).astype(np.int64) % n
    ranges = np.full(n, np.inf, dtype=np.float32)
    inten = np.zeros(n, dtype=np.float32)
    ranges[idx] = np.sqrt(pts["x"] ** 2 + pts["y"] ** 2 + pts["z"] ** 2)
    inten[idx] = pts["intensity"]
    rmin, rmax = lidar["range_m"]
    return {"angle_min": 0.0, "angle_max": float(inc * (n - 1)), "angle_increment": float(inc),
            "range_min": float(rmin), "range_max": float(rmax), "ranges": ranges,
            "intensities": inten, "ring": ring, "elevation_deg": float(elev[ring])}


#: The run's depth PNGs saturate here (>= 65.535 m, e.g. the sky).
FAR_MM = 65535


def depth_m(depth_mm: NDArray[np.uint16]) -> NDArray[np.float32]:
    """uint16 mm -> float32 m (REP-118): 0 (no return) -> NaN, 65535 (too far) -> +inf."""
    d = depth_mm.astype(np.float32) * np.float32(0.001)
    d[depth_mm == 0] = np.nan
    d[depth_mm == FAR_MM] = np.inf
    return d


def depth_points(
    depth_mm: NDArray[np.uint16], k: NDArray[np.float64], stride_px: int
) -> NDArray[np.float32]:
    """Organised (H/s, W/s, 3) float32 points in the optical frame; NaN: no return or too far."""
    mm = depth_mm[::stride_px, ::stride_px]
    d = mm.astype(np.float32) * np.float32(0.001)
    h, w = d.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float32) * np.float32(stride_px)
    x = (u - np.float32(k[0, 2])) / np.float32(k[0, 0]) * d
    y = (v - np.float32(k[1, 2])) / np.float32(k[1, 1]) * d
    pts = np.stack([x, y, d], axis=-1)
    pts[(mm == 0) | (mm == FAR_MM)] = np.nan
    return pts


#: Variance declared for what wheel odometry does not observe (z, roll, pitch; lateral and
#: vertical velocity, roll and pitch rates), as ROS odometry publishers conventionally do.
UNOBSERVED_VAR = 1e6


def noise_of_run(run_meta: dict[str, Any]) -> NoiseConfig:
    """The drive's :class:`~marsscene.rover.config.NoiseConfig` from ``run.json``
    (keys that older versions wrote and this one does not know are ignored)."""
    known = {f.name for f in fields(NoiseConfig)}
    return dataclass_from_mapping(
        NoiseConfig, {k: v for k, v in run_meta.get("noise", {}).items() if k in known}, "noise")


def odometry_covariance_rows(
    pose_xy_yaw: NDArray[np.float64], twist_v_omega: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(N, 36) pose and twist covariances of ``/rover/odom``.

    Row-major 6 x 6 in (x, y, z, roll, pitch, yaw) and (vx, vy, vz, wx, wy, wz), as
    ``nav_msgs/Odometry`` orders them, from the (N, 3, 3) covariance of the dead-reckoned
    ``(x, y, yaw)`` and the (N, 2, 2) one of ``(v, omega)``
    (:mod:`marsscene.rover.odometry_covariance`); what wheel odometry does not observe gets
    :data:`UNOBSERVED_VAR`.
    """
    n = len(pose_xy_yaw)
    pose = np.zeros((n, 6, 6))
    twist6 = np.zeros((n, 6, 6))
    for k in (2, 3, 4):
        pose[:, k, k] = UNOBSERVED_VAR
    for k in (1, 2, 3, 4):
        twist6[:, k, k] = UNOBSERVED_VAR
    ix = np.array([0, 1, 5])
    pose[:, ix[:, None], ix[None, :]] = pose_xy_yaw
    jx = np.array([0, 5])
    twist6[:, jx[:, None], jx[None, :]] = twist_v_omega
    return pose.reshape(n, 36), twist6.reshape(n, 36)
