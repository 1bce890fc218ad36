"""The LiDAR baseline's odometry prior: the wheels' translation, the gyro's rotation.

A Mars rover dead-reckons in 3-D with its attitude from the IMU and its travel from the wheels
(the Mars Exploration Rovers: Maimone et al. 2007, doi:10.1002/rob.20184). The simulated
rover's wheel odometry (:class:`marsscene.sensors.odometry.WheelOdometry`) is planar: x, y and a
heading from the wheels, tilt and height unobserved, the heading drifting where the wheels skid
in turns. As the prior of LiDAR odometry that loses each tilt change the rover makes while the
prior stands in for the ICP (measured on main-crater's full loop: 15.6 deg of pitch error after
a rim crossing, and the estimate climbing away), and a skid's heading error on mars-base's loop.

:class:`WheelGyroPrior` gives the step between two scans as a real rover's odometry would: the
rotation from the measured gyro rates integrated between the scans (first order, one rotation
vector per IMU sample), the translation the planar wheel step's (the rover moves along its own
axes, so the step in the previous base frame is the planar one), moved to the LiDAR frame by
its mount. Before the first IMU sample (e.g. a replay without IMU) the rotation is the wheels'.
:func:`stored_steps` replays a stored run's ``odom.tum`` and ``imu.csv`` through it, for a
sensor scored after the drive (the RGB-D baseline's navcam).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

__all__ = ["PRIOR_MODEL", "WheelGyroPrior", "stored_steps"]

#: What the odometry prior is made of; part of the keys of benchmark drives, rows and
#: checkpoints made with it, so a result of another prior is made again.
PRIOR_MODEL = "wheel travel, gyro rotation"


class WheelGyroPrior:
    """Pose steps of ``lidar_link`` between scans from the wheel odometry and the gyro.

    Feed :meth:`control` (wheel odometry pose, base frame) and :meth:`imu` (gyro rates in
    ``base_link``: the IMU's frame) as the drive makes them; :meth:`step` at each scan.
    """

    def __init__(self, lidar_mount: np.ndarray | None = None, *, gyro: bool = True) -> None:
        self.lidar_mount = np.eye(4) if lidar_mount is None else np.asarray(lidar_mount, float)
        self.gyro = gyro
        self._odom: list[tuple[float, np.ndarray]] = []  # (t, base pose by the wheels)
        self._attitude: list[tuple[float, np.ndarray]] = []  # (t, base rotation since start)
        self._imu_t: float | None = None
        self._previous: tuple[np.ndarray, np.ndarray | None] | None = None

    def control(self, t: float, xyz: Any, wxyz: Any) -> None:
        """The wheel odometry's base pose at control time ``t`` (quaternion w, x, y, z)."""
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_quat(np.asarray(wxyz, float)[[1, 2, 3, 0]]).as_matrix()
        pose[:3, 3] = xyz
        self._odom.append((float(t), pose))

    def imu(self, t: float, gyro_rad_s: Any) -> None:
        """One gyro sample (rad/s, base frame): the attitude integrated up to ``t``."""
        if not self.gyro:
            return
        last = self._attitude[-1][1] if self._attitude else np.eye(3)
        if self._imu_t is not None:
            turn = Rotation.from_rotvec(np.asarray(gyro_rad_s, float) * (t - self._imu_t))
            last = last @ turn.as_matrix()
        self._imu_t = float(t)
        self._attitude.append((float(t), last))

    @staticmethod
    def _latest(samples: list[tuple[float, np.ndarray]], t: float) -> np.ndarray | None:
        """The last sample at or before ``t``; older ones are dropped (scans come in order)."""
        at = [i for i, (s, _) in enumerate(samples) if s <= t + 1e-9]
        if not at:
            return None
        del samples[:at[-1]]
        return samples[0][1]

    def step(self, t: float) -> np.ndarray | None:
        """The LiDAR's pose step from the previous scan to this one at ``t`` (4 x 4, in the
        previous scan's frame); None at the first scan or before any odometry."""
        wheel = self._latest(self._odom, t)
        attitude = self._latest(self._attitude, t)
        previous, self._previous = self._previous, (
            (wheel, attitude) if wheel is not None else self._previous)
        if wheel is None or previous is None:
            return None
        base = np.linalg.inv(previous[0]) @ wheel
        if attitude is not None and previous[1] is not None:
            base[:3, :3] = previous[1].T @ attitude
        return np.linalg.inv(self.lidar_mount) @ base @ self.lidar_mount


def stored_steps(run: Any, stamps_s: NDArray[np.float64], mount: np.ndarray, *,
                 gyro: bool = True) -> NDArray[np.float64]:
    """The prior's steps of a sensor between consecutive ``stamps_s`` of a stored run
    (:class:`~marsscene.runs.runlog.RunLog`): its ``odom.tum`` and gyro fed in time order, as
    a drive feeds the listener. (N - 1, 4, 4), the pose at stamp k in the sensor's frame at
    stamp k - 1; the odometry must have a pose at or before the first stamp."""
    prior = WheelGyroPrior(mount, gyro=gyro)
    odom, imu = run.odom, run.imu  # imu: t, accel xyz, gyro xyz
    wxyz = odom.quat_xyzw[:, [3, 0, 1, 2]]
    i = j = 0
    steps = []
    for t in np.asarray(stamps_s, dtype=np.float64):
        while i < len(odom) and odom.timestamps_s[i] <= t + 1e-9:
            prior.control(odom.timestamps_s[i], odom.xyz_m[i], wxyz[i])
            i += 1
        while j < len(imu) and imu[j, 0] <= t + 1e-9:
            prior.imu(imu[j, 0], imu[j, 4:7])
            j += 1
        steps.append(prior.step(t))
    return np.array(steps[1:], dtype=np.float64).reshape(-1, 4, 4)
