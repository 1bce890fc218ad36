"""What every simulated rover answers: its pose, twist, wheels, IMU and camera, read from a
compiled MuJoCo model that holds it under a name prefix.

:class:`RoverView` is shared by :class:`~marsscene.sim.rover_sim.RoverSim` (one rover, prefix
``rover/``) and :class:`~marsscene.sim.team.TeamMember` (one robot of a team in one model,
prefix ``<name>/``): the drive loop, the sensors and the controllers see either the same way.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, wheel_commands
from marsscene.transforms import yaw_of_quat

__all__ = ["PREFIX", "RoverView", "rover_indices"]

PREFIX = "rover/"


def rover_indices(m: Any, prefix: str = PREFIX) -> dict[str, Any]:
    """Where a rover (attached with ``prefix``, default :data:`PREFIX`) lives in a compiled
    model: body, root joint, actuators, joints, wheel geoms, sites, camera and IMU sensor
    addresses."""
    name = lambda kind, n: mujoco.mj_name2id(m, kind, prefix + n)  # noqa: E731
    root = name(mujoco.mjtObj.mjOBJ_JOINT, "root")
    drive_j = [name(mujoco.mjtObj.mjOBJ_JOINT, j) for j in DRIVE_JOINTS]
    steer_j = [name(mujoco.mjtObj.mjOBJ_JOINT, j) for j in STEER_JOINTS]
    acc = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, prefix + "imu_accel")
    gyr = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, prefix + "imu_gyro")
    return {
        "base_id": name(mujoco.mjtObj.mjOBJ_BODY, "base_link"),
        "qpos_root": int(m.jnt_qposadr[root]),
        "qvel_root": int(m.jnt_dofadr[root]),
        "drive_act": np.array([name(mujoco.mjtObj.mjOBJ_ACTUATOR, j) for j in DRIVE_JOINTS]),
        "steer_act": np.array([name(mujoco.mjtObj.mjOBJ_ACTUATOR, j) for j in STEER_JOINTS]),
        "drive_dof": np.array([m.jnt_dofadr[j] for j in drive_j]),
        "steer_qpos": np.array([m.jnt_qposadr[j] for j in steer_j]),
        "wheel_geoms": np.array([name(mujoco.mjtObj.mjOBJ_GEOM, "wheel_" + j[-2:])
                                 for j in DRIVE_JOINTS]),
        "chassis_geom": name(mujoco.mjtObj.mjOBJ_GEOM, "chassis"),
        "imu_site": name(mujoco.mjtObj.mjOBJ_SITE, "imu"),
        "lidar_site": name(mujoco.mjtObj.mjOBJ_SITE, "lidar"),
        "camera_id": name(mujoco.mjtObj.mjOBJ_CAMERA, "navcam"),
        "_acc_adr": int(m.sensor_adr[acc]),
        "_gyr_adr": int(m.sensor_adr[gyr]),
    }


class RoverView:
    """A rover's readings and commands in ``model`` / ``data`` (set by the subclass, with
    ``rover``, ``run`` and ``prefix``; :meth:`_ids` reads its indices)."""

    model: Any
    data: Any
    rover: RoverConfig
    run: RunConfig
    prefix: str = PREFIX
    cmd: tuple[float, float] = (0.0, 0.0)

    def _ids(self) -> None:
        ix = rover_indices(self.model, self.prefix)
        self.base_id = ix["base_id"]
        self.qpos_root, self.qvel_root = ix["qpos_root"], ix["qvel_root"]
        self.drive_act, self.steer_act = ix["drive_act"], ix["steer_act"]
        self.drive_dof, self.steer_qpos = ix["drive_dof"], ix["steer_qpos"]
        self.wheel_geoms, self.chassis_geom = ix["wheel_geoms"], ix["chassis_geom"]
        self.imu_site, self.lidar_site = ix["imu_site"], ix["lidar_site"]
        self.camera_id = ix["camera_id"]
        self._acc_adr, self._gyr_adr = ix["_acc_adr"], ix["_gyr_adr"]

    # ---- commands ----------------------------------------------------------------------------
    def apply(self, v_m_s: float, omega_rad_s: float) -> None:
        """Set actuator targets for ``cmd_vel`` (clipped to the actuator ranges by MuJoCo)."""
        rates, steer = wheel_commands(float(v_m_s), float(omega_rad_s), self.rover)
        self.data.ctrl[self.drive_act] = rates
        self.data.ctrl[self.steer_act] = steer
        self.cmd = (float(v_m_s), float(omega_rad_s))

    # ---- camera ------------------------------------------------------------------------------
    def make_renderer(self, *, rng: np.random.Generator | None = None,
                      config: Any = None) -> Any:
        """An offscreen mast-camera renderer (:class:`marsscene.sensors.camera.MastCamera`).

        ``rng`` draws sensor noise when ``CameraConfig.sensor_noise`` is on; ``config`` (a
        ``CameraConfig``) replaces the run's camera.
        """
        from marsscene.sensors.camera import MastCamera

        return MastCamera(self, rng=rng, config=config)

    def render(self, renderer: Any) -> tuple[NDArray[np.uint8], NDArray[np.float32] | None]:
        """RGB (H, W, 3) uint8 and depth (H, W) float32 in m (None if depth is off)."""
        return renderer.render(self)

    def camera_intrinsics(self, side: str | None = None) -> dict[str, Any]:
        """Pinhole intrinsics of the mast camera (OpenCV convention, pixels).

        ``side = "left"`` / ``"right"``: one view of the rectified stereo pair (same
        intrinsics; the right camera sits ``baseline_m`` along the left camera's +x).
        """
        cam = self.run.camera
        w, h = (cam.width_px, cam.height_px) if cam is not None else (640, 480)
        fovy = math.radians(float(self.model.cam_fovy[self.camera_id]))
        f = 0.5 * h / math.tan(fovy / 2)
        extra: dict[str, Any] = {}
        if side is not None:
            b = cam.stereo_baseline_m if cam is not None else 0.424
            extra = {
                "side": side,
                "baseline_m": b,
                "rectified": True,
                "T_left_right_m": [b, 0.0, 0.0],
                "offset_from_navcam_m": [(-0.5 if side == "left" else 0.5) * b, 0.0, 0.0],
            }
        return {
            **extra,
            "width": w,
            "height": h,
            "fx": f,
            "fy": f,
            "cx": w / 2,
            "cy": h / 2,
            "depth_unit_m": 0.001,
            "frame": "optical: x right, y down, z forward",
        }

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    # ---- state -------------------------------------------------------------------------------
    def pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Ground-truth ``base_link`` pose: position (3,) in m and quaternion (w, x, y, z)."""
        q = self.data.qpos[self.qpos_root : self.qpos_root + 7]
        return q[:3].copy(), q[3:7].copy()

    def yaw_rad(self) -> float:
        """Ground-truth heading of ``base_link`` (rad, counter-clockwise from +x)."""
        return float(yaw_of_quat(self.data.qpos[self.qpos_root + 3: self.qpos_root + 7]))

    def site_twist(self, site_id: int) -> NDArray[np.float64]:
        """A site's angular and linear velocity (rad/s, m/s; world frame), ``(wx, wy, wz, vx,
        vy, vz)``."""
        twist = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_SITE, site_id,
                                 twist, 0)
        return twist

    def wheel_rates(self) -> NDArray[np.float64]:
        """True wheel angular speeds (rad/s), DRIVE_JOINTS order."""
        return self.data.qvel[self.drive_dof].copy()

    def steer_angles(self) -> NDArray[np.float64]:
        """True corner steering angles (rad), STEER_JOINTS order."""
        return self.data.qpos[self.steer_qpos].copy()

    def imu_true(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Noise-free specific force (m/s^2, incl. gravity) and angular rate (rad/s), IMU frame."""
        s = self.data.sensordata
        return s[self._acc_adr : self._acc_adr + 3].copy(), s[
            self._gyr_adr : self._gyr_adr + 3
        ].copy()

    def wheels_in_contact(self) -> NDArray[np.bool_]:
        """Which of the six wheels touch anything (DRIVE_JOINTS order)."""
        n = self.data.ncon
        g = np.concatenate([self.data.contact.geom1[:n], self.data.contact.geom2[:n]])
        return np.isin(self.wheel_geoms, g)

