"""What goes into each of the rover's state topics, composed once for the bag and the live topics.

The bag (:mod:`.bag_topics`, all of a run folder's samples at once) and the live publisher
(:class:`~.sample_messages.SampleMessages`, each sample as the drive makes it) both compute the
fields of ``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory`` and ``/rover/joint_states`` with
:class:`ControlFields` and build each message with :func:`tf`, :func:`odometry`,
:func:`ground_truth` and :func:`joint_states`; ``/rover/imu_noisy``'s covariances with
:func:`imu_variances` (``MessageBuilder.imu`` builds both IMU topics); ``/rover/wheel_soil``
with :func:`wheel_soil`; the latched topics with :func:`tf_static` and
:func:`robot_description`. Neither side computes a field itself; they differ only in the
samples they hand in:

* the bag passes the whole drive (:meth:`ControlRows.of_run`), vectorised;
* the live publisher passes the previous and the new sample and a :class:`Carry` that holds
  what the earlier samples added up to (the drive joints' angles, the odometry's pose
  covariance), and gets the new sample's fields.

Rates are differences over the rows given (``np.gradient``: central inside, one-sided at the
ends), so the bag's ground-truth twist and steering rates are central differences and the live
ones, which have no next sample, backward ones: one function on what each side knows. No
``rosbags`` import: the messages come from the :class:`~.bag_messages.MessageBuilder` passed in.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from marsscene.errors import RuntimeSimError
from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS
from marsscene.rover.odometry_covariance import (
    PoseCovarianceStep,
    pose_covariance,
    twist_covariance,
)
from marsscene.runs.export import bag_data as bd
from marsscene.runs.export.frames import StaticTransform, rover_urdf
from marsscene.runs.export.imu_noise import imu_noise_of

__all__ = ["JOINT_NAMES", "Carry", "ControlFields", "ControlRows", "ground_truth",
           "imu_variances", "joint_states", "odometry", "robot_description", "tf", "tf_static",
           "wheel_soil"]

#: ``/rover/joint_states`` names, in the order of its positions and velocities.
JOINT_NAMES = [*DRIVE_JOINTS, *STEER_JOINTS]

Float = NDArray[np.float64]


@dataclass(frozen=True)
class ControlRows:
    """Control-rate samples of a drive, one row each, on one clock (N first on every array).

    ``gt_*``: ``base_link`` in ``map`` (ground truth); ``odom_*``: the wheel odometry,
    ``base_link`` in ``odom``; quaternions x y z w; ``wheels`` holds the ``wheels.csv``
    columns (N, 11): stamp, the six drive rates (rad/s), the four steering angles (rad).
    """

    t_s: Float
    gt_xyz_m: Float
    gt_quat_xyzw: Float
    odom_xyz_m: Float
    odom_quat_xyzw: Float
    wheels: Float

    @classmethod
    def of_run(cls, run: Any) -> ControlRows:
        """The rows of a run folder (:class:`~marsscene.runs.runlog.RunLog`); its ground
        truth and odometry must share their stamps (one control clock)."""
        gt, od = run.gt, run.odom
        if len(gt) != len(od) or not np.allclose(gt.timestamps_s, od.timestamps_s, atol=1e-6):
            raise RuntimeSimError("gt.tum and odom.tum must have the same stamps (one control "
                                  "clock)")
        return cls(od.timestamps_s, gt.xyz_m, gt.quat_xyzw, od.xyz_m, od.quat_xyzw, run.wheels)

    @classmethod
    def of_samples(cls, samples: list[tuple[Any, ...]]) -> ControlRows:
        """Rows of live samples ``(t_s, gt_xyz_m, gt_quat_xyzw, odom_xyz_m, odom_quat_xyzw,
        rates_rad_s, steer_rad)``, oldest first."""
        t, gx, gq, ox, oq, rates, steer = (np.array(c, dtype=np.float64)
                                           for c in zip(*samples, strict=True))
        return cls(t, gx, gq, ox, oq, np.hstack([t[:, None], rates, steer]))


class Carry:
    """What a live stream's earlier samples add up to: the drive joints' angles (rad) and the
    odometry's pose covariance (:class:`~marsscene.rover.odometry_covariance.
    PoseCovarianceStep`, the sums of :func:`~marsscene.rover.odometry_covariance.
    pose_covariance` as running totals)."""

    def __init__(self) -> None:
        self.angle_rad = np.zeros(6)
        self.pose = PoseCovarianceStep()


class ControlFields:
    """Every field of ``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory`` and
    ``/rover/joint_states`` at each row (N first on every array).

    ``odom_*`` and ``gt_*``: the poses; ``twist``: the odometry's ``(v m/s, omega rad/s)``
    from the wheels; ``pose_cov`` / ``twist_cov``: ``/rover/odom``'s row-major 6 x 6
    covariances; ``joint_position`` / ``joint_velocity``: in :data:`JOINT_NAMES` order. These
    are computed at once (a live stream's integrals advance every sample); ``map_odom``
    (``map -> odom`` from ground truth) and ``gt_twist`` (the ground truth's body twist) when
    first read, so a live topic nobody takes costs nothing (the bag's message
    threads may read one at once: both compute the same arrays).

    Parameters
    ----------
    rows : ControlRows
        Without ``carry``: a whole drive from its first sample (fields of every row). With it:
        the previous and the new sample (or the first one alone).
    rover : RoverConfig
    noise : NoiseConfig
        The drive's simulated noise (the odometry's covariances).
    carry : Carry, optional
        A live stream's running integrals, advanced to the new sample; the fields are then
        the new sample's alone (N = 1).
    """

    def __init__(self, rows: ControlRows, rover: RoverConfig, noise: NoiseConfig,
                 carry: Carry | None = None) -> None:
        t, n = rows.t_s, len(rows.t_s)
        self.rows, self.new = rows, slice(0 if carry is None else n - 1, n)
        self._r_od = Rotation.from_quat(rows.odom_quat_xyzw)
        pos, vel, twist = bd.joint_states(rows.wheels, rover)
        tw = twist_covariance(rows.wheels[:, 1:7], rows.wheels[:, 7:11], noise, rover)
        yaw = self._r_od.as_euler("xyz")[:, 2]
        if carry is None:
            pose3 = pose_covariance(t, twist[:, 0], np.unwrap(yaw), tw)
        else:
            pose3 = np.zeros((1, 3, 3))
            if n == 2:  # the step from the previous sample, heading as it was there
                pose3[0] = carry.pose.step(float(t[1] - t[0]), float(twist[1, 0]),
                                           float(yaw[0]), tw[1])
            carry.angle_rad = carry.angle_rad + pos[-1, :6]  # the rows' integral starts at 0
            pos[-1, :6] = carry.angle_rad
        new = self.new
        self.pose_cov, self.twist_cov = bd.odometry_covariance_rows(pose3, tw[new])
        self.t_s, self.twist = t[new], twist[new]
        self.joint_position, self.joint_velocity = pos[new], vel[new]
        self.odom_xyz_m, self.odom_quat_xyzw = rows.odom_xyz_m[new], rows.odom_quat_xyzw[new]
        self.gt_xyz_m, self.gt_quat_xyzw = rows.gt_xyz_m[new], rows.gt_quat_xyzw[new]

    @cached_property
    def _r_gt(self) -> Rotation:
        return Rotation.from_quat(self.rows.gt_quat_xyzw)

    @cached_property
    def map_odom(self) -> tuple[Float, Float]:
        """``map -> odom``: translations (N, 3) and quaternions (N, 4)."""
        xyz, q = bd.map_to_odom(self.rows.gt_xyz_m, self._r_gt, self.rows.odom_xyz_m,
                                self._r_od)
        return xyz[self.new], q[self.new]

    @cached_property
    def gt_twist(self) -> tuple[Float, Float]:
        """The ground truth's body twist: linear (N, 3, m/s) and angular (N, 3, rad/s)."""
        lin, ang = bd.body_twist_from_poses(self.rows.t_s, self.rows.gt_xyz_m, self._r_gt)
        return lin[self.new], ang[self.new]


def tf(b: Any, f: ControlFields, i: int, map_tf: bool = True) -> Any:
    """``/tf`` at row ``i``: ``map -> odom`` (unless ``map_tf`` is false: a SLAM stack then
    publishes it) and ``odom -> base_link``."""
    od = (f.odom_xyz_m[i], f.odom_quat_xyzw[i])
    if map_tf:
        xyz, q = f.map_odom
        return b.state_tf(f.t_s[i], (xyz[i], q[i]), od)
    return b.tf_message([b.tf(f.t_s[i], "odom", "base_link", *od)])


def odometry(b: Any, f: ControlFields, i: int) -> Any:
    """``/rover/odom`` at row ``i``: the wheel odometry with its covariances."""
    return b.odometry(f.t_s[i], "odom", f.odom_xyz_m[i], f.odom_quat_xyzw[i],
                      (f.twist[i, 0], 0, 0), (0, 0, f.twist[i, 1]), f.pose_cov[i],
                      f.twist_cov[i])


def ground_truth(b: Any, f: ControlFields, i: int) -> Any:
    """``/rover/GT_Trajectory`` at row ``i``: ground truth in ``map``, its body twist."""
    lin, ang = f.gt_twist
    return b.odometry(f.t_s[i], "map", f.gt_xyz_m[i], f.gt_quat_xyzw[i], lin[i], ang[i])


def joint_states(b: Any, f: ControlFields, i: int) -> Any:
    """``/rover/joint_states`` at row ``i``."""
    return b.joint_state(f.t_s[i], JOINT_NAMES, f.joint_position[i], f.joint_velocity[i])


def wheel_soil(b: Any, t_s: float, sinkage_m: Any, slip: Any, load_n: Any) -> Any:
    """``/rover/wheel_soil``: sinkage, slip and load per drive wheel as a ``JointState``'s
    position, velocity and effort."""
    return b.joint_state(t_s, list(DRIVE_JOINTS), sinkage_m, slip, load_n)


def imu_variances(noise: dict[str, Any], rate_hz: float) -> tuple[float, float]:
    """Per-sample white-noise variances ``(gyro (rad/s)^2, accel (m/s^2)^2)`` of the simulated
    IMU sampled at ``rate_hz``: density^2 * rate (the density includes any per-sample sigma,
    :func:`~.imu_noise.imu_noise_of`). ``noise``: ``run.json``'s or ``asdict(NoiseConfig)``."""
    nd = imu_noise_of(noise, rate_hz)
    return (nd["gyroscope_noise_density"] ** 2 * nd["rate_hz"],
            nd["accelerometer_noise_density"] ** 2 * nd["rate_hz"])


def tf_static(b: Any, t_s: float, statics: list[StaticTransform]) -> Any:
    """``/tf_static``: the sensor mounts (:func:`~.frames.static_transforms`)."""
    return b.tf_message([b.tf(t_s, s.parent, s.child, s.xyz_m, s.quat_xyzw) for s in statics])


def robot_description(b: Any, rover: RoverConfig, statics: list[StaticTransform]) -> Any:
    """``/rover/robot_description``: the rover's URDF."""
    return b.T["std_msgs/msg/String"](data=rover_urdf(rover, statics))
