"""The rover's frame tree (REP-103 / REP-105) and its URDF (numpy + scipy only).

::

    map ──(GT: map→odom)── odom ──(wheel odometry)── base_link
        base_link ── imu_link
                  ├─ lidar_link
                  ├─ navcam_link (x fwd, y left, z up; pitched down) ── navcam_optical_frame
                  │                                  ├─ stereo_left_optical_frame  (if logged)
                  │                                  └─ stereo_right_optical_frame
                  └─ steer_XX ── wheel_XX (URDF joints, moving; see joint_states)

Optical frames follow REP-103: x right, y down, z forward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene.errors import RuntimeSimError
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, sensor_mounts, wheel_positions_xy

__all__ = [
    "OPTICAL_QUAT_XYZW",
    "StaticTransform",
    "camera_frame",
    "frame_in_base",
    "rover_urdf",
    "static_transforms",
]

#: Rotation of an optical frame (x right, y down, z forward) in its body frame (x fwd, z up).
OPTICAL_QUAT_XYZW = (-0.5, 0.5, -0.5, 0.5)


@dataclass(frozen=True)
class StaticTransform:
    """``child`` pose in ``parent``: translation (m) and unit quaternion (x, y, z, w)."""

    parent: str
    child: str
    xyz_m: tuple[float, float, float]
    quat_xyzw: tuple[float, float, float, float]

    def matrix(self) -> NDArray[np.float64]:
        m = np.eye(4)
        m[:3, :3] = Rotation.from_quat(self.quat_xyzw).as_matrix()
        m[:3, 3] = self.xyz_m
        return m


def camera_frame(name: str) -> str:
    """Optical frame id of a camera stream (``navcam`` or a stereo folder name)."""
    return "navcam_optical_frame" if name == "navcam" else f"stereo_{name}_optical_frame"


def _q(rot: Rotation) -> tuple[float, float, float, float]:
    x, y, z, w = (float(v) for v in rot.as_quat())
    return (x, y, z, w)


def static_transforms(
    rover: RoverConfig, extra_cameras: dict[str, dict[str, object]] | None = None
) -> list[StaticTransform]:
    """Static sensor transforms (for ``/tf_static`` and the URDF).

    ``extra_cameras`` maps a camera folder name to its intrinsics dict; its optical frame is
    placed from ``pose_in_base_link`` (``{"xyz_m": [...], "quat_xyzw": [...]}``, optical frame
    in ``base_link``) when given, else ``left``/``right`` sit ``±baseline/2`` along the navcam's
    y axis (``baseline_m`` or ``stereo_baseline_m`` in the intrinsics).
    """
    m = sensor_mounts(rover)
    out = [
        StaticTransform("base_link", "imu_link", m["imu"][0], (0.0, 0.0, 0.0, 1.0)),
        StaticTransform("base_link", "lidar_link", m["lidar"][0], (0.0, 0.0, 0.0, 1.0)),
        StaticTransform("base_link", "navcam_link", m["camera"][0],
                        _q(Rotation.from_euler("y", m["camera"][1]))),
        StaticTransform("navcam_link", "navcam_optical_frame", (0.0, 0.0, 0.0), OPTICAL_QUAT_XYZW),
    ]
    for name, intr in sorted((extra_cameras or {}).items()):
        pose = intr.get("pose_in_base_link")
        if isinstance(pose, dict):
            xyz = tuple(float(v) for v in pose["xyz_m"])
            quat = tuple(float(v) for v in pose["quat_xyzw"])
            out.append(StaticTransform("base_link", camera_frame(name), xyz, quat))  # type: ignore[arg-type]
            continue
        base = intr.get("baseline_m", intr.get("stereo_baseline_m"))
        if name not in ("left", "right") or not isinstance(base, (int, float)):
            raise RuntimeSimError(
                f"camera folder {name!r}: cannot place it; its intrinsics.json needs "
                "'pose_in_base_link' (or 'baseline_m' for a left/right stereo folder)"
            )
        dy = float(base) / 2.0 * (1.0 if name == "left" else -1.0)
        out.append(StaticTransform("navcam_link", camera_frame(name), (0.0, dy, 0.0),
                                   OPTICAL_QUAT_XYZW))
    return out


def frame_in_base(transforms: list[StaticTransform], frame: str) -> NDArray[np.float64]:
    """4 x 4 pose of ``frame`` in ``base_link`` by chaining static transforms."""
    by_child = {t.child: t for t in transforms}
    m = np.eye(4)
    while frame != "base_link":
        if frame not in by_child:
            raise RuntimeSimError(f"frame {frame!r} is not connected to base_link")
        t = by_child[frame]
        m = t.matrix() @ m
        frame = t.parent
    return m


def _origin(xyz: tuple[float, ...], rpy: tuple[float, ...] = (0.0, 0.0, 0.0)) -> str:
    f = " ".join(f"{v:.9g}" for v in xyz)
    r = " ".join(f"{v:.9g}" for v in rpy)
    return f'<origin xyz="{f}" rpy="{r}"/>'


def rover_urdf(rover: RoverConfig, transforms: list[StaticTransform]) -> str:
    """URDF of the rover: sensor links (fixed joints) and steering/drive joints.

    The rocker and bogie pivots are not logged, so they are fixed at their nominal (flat
    ground) angles; each wheel hangs at its nominal position below ``base_link``.
    """
    links = ['  <link name="base_link"><visual>' + _origin((0.0, 0.0, 0.05))
             + '<geometry><box size="1.8 1.1 0.4"/></geometry></visual></link>']
    joints = []
    for t in transforms:
        rpy = tuple(float(v) for v in Rotation.from_quat(t.quat_xyzw).as_euler("xyz"))
        links.append(f'  <link name="{t.child}"/>')
        joints.append(f'  <joint name="{t.child}_joint" type="fixed"><parent link="{t.parent}"/>'
                      f'<child link="{t.child}"/>{_origin(t.xyz_m, rpy)}</joint>')
    xy = wheel_positions_xy(rover)
    z = rover.wheel_radius_m - rover.ride_height_m
    r, w = rover.wheel_radius_m, rover.wheel_width_m
    lim = rover.steer_limit_rad
    wheel_geom = (f'<visual><origin xyz="0 0 0" rpy="1.57079633 0 0"/><geometry><cylinder '
                  f'radius="{r:.9g}" length="{w:.9g}"/></geometry></visual>')
    for i, drive in enumerate(DRIVE_JOINTS):
        tag = drive[-2:]
        parent = "base_link"
        pos: tuple[float, ...] = (float(xy[i, 0]), float(xy[i, 1]), z)
        if f"steer_{tag}" in STEER_JOINTS:
            links.append(f'  <link name="steer_{tag}"/>')
            joints.append(
                f'  <joint name="steer_{tag}" type="revolute"><parent link="base_link"/>'
                f'<child link="steer_{tag}"/>{_origin(pos)}<axis xyz="0 0 1"/>'
                f'<limit lower="{-lim:.9g}" upper="{lim:.9g}" effort="500" velocity="1"/>'
                "</joint>"
            )
            parent, pos = f"steer_{tag}", (0.0, 0.0, 0.0)
        links.append(f'  <link name="wheel_{tag}">{wheel_geom}</link>')
        joints.append(f'  <joint name="{drive}" type="continuous"><parent link="{parent}"/>'
                      f'<child link="wheel_{tag}"/>{_origin(pos)}<axis xyz="0 1 0"/></joint>')
    body = "\n".join(links + joints)
    return f'<?xml version="1.0"?>\n<robot name="marsscene_rover">\n{body}\n</robot>\n'
