"""What goes into each of the rover's state topics, composed once for the bag and the live topics.

The bag (:mod:`.bag_topics`, all of a run folder's samples at once) and the live publisher
(:class:`~.sample_messages.SampleMessages`, each sample as the drive makes it) both compute the
fields of ``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory`` and ``/rover/joint_states`` with
:func:`control_fields` and build each message with :func:`tf`, :func:`odometry`,
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
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

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
from marsscene.runs.tum import Trajectory

__all__ = ["JOINT_NAMES", "Carry", "ControlFields", "ControlRows", "control_fields",
           "ground_truth", "imu_variances", "joint_states", "odometry",
           "robot_description", "tf", "tf_static", "wheel_soil"]

#: ``/rover/joint_states`` names, in the order of its positions and velocities.
JOINT_NAMES = [*DRIVE_JOINTS, *STEER_JOINTS]

Float = NDArray[np.float64]


@dataclass(frozen=True)
class ControlRows:
    """Control-rate samples of a drive, one row each, on one clock.

    ``gt`` (``base_link`` in ``map``) and ``odom`` (wheel odometry, ``base_link`` in ``odom``)
    are trajectories of the same stamps; ``wheels`` holds the ``wheels.csv`` columns (N, 11):
    stamp, the six drive rates (rad/s), the four steering angles (rad).
    """

    gt: Trajectory
    odom: Trajectory
    wheels: Float

    @classmethod
    def of_run(cls, run: Any) -> ControlRows:
        """The rows of a run folder (:class:`~marsscene.runs.runlog.RunLog`)."""
        return cls(run.gt, run.odom, run.wheels)

    @classmethod
    def of_samples(cls, samples: list[tuple[Any, ...]]) -> ControlRows:
        """Rows of live samples ``(t_s, gt_xyz_m, gt_quat_xyzw, odom_xyz_m, odom_quat_xyzw,
        rates_rad_s, steer_rad)``, oldest first."""
        t, gx, gq, ox, oq, rates, steer = (np.asarray(c, dtype=np.float64)
                                           for c in zip(*samples, strict=True))
        return cls(Trajectory(t, gx, gq), Trajectory(t, ox, oq),
                   np.hstack([t[:, None], rates.reshape(-1, 6), steer.reshape(-1, 4)]))


@dataclass(frozen=True)
class ControlFields:
    """Every field of the control-rate topics at each row (N first on every array).

    ``map_odom_*``: ``map -> odom`` (from ground truth); ``odom_*`` and ``gt_*``: the poses;
    ``twist``: the odometry's ``(v m/s, omega rad/s)`` from the wheels; ``pose_cov`` /
    ``twist_cov``: ``/rover/odom``'s row-major 6 x 6 covariances; ``gt_lin_m_s`` /
    ``gt_ang_rad_s``: the ground-truth body twist; ``joint_position`` / ``joint_velocity``: in
    :data:`JOINT_NAMES` order.
    """

    t_s: Float
    map_odom_xyz_m: Float
    map_odom_quat_xyzw: Float
    odom_xyz_m: Float
    odom_quat_xyzw: Float
    twist: Float
    pose_cov: Float
    twist_cov: Float
    gt_xyz_m: Float
    gt_quat_xyzw: Float
    gt_lin_m_s: Float
    gt_ang_rad_s: Float
    joint_position: Float
    joint_velocity: Float


class Carry:
    """What a live stream's earlier samples add up to: the drive joints' angles (rad) and the
    odometry's pose covariance (:class:`~marsscene.rover.odometry_covariance.
    PoseCovarianceStep`, the sums of :func:`~marsscene.rover.odometry_covariance.
    pose_covariance` as running totals)."""

    def __init__(self) -> None:
        self.angle_rad = np.zeros(6)
        self.pose = PoseCovarianceStep()


def control_fields(rows: ControlRows, rover: RoverConfig, noise: NoiseConfig,
                   carry: Carry | None = None) -> ControlFields:
    """The fields of ``/tf``, ``/rover/odom``, ``/rover/GT_Trajectory``, ``/rover/joint_states``.

    Parameters
    ----------
    rows : ControlRows
        Without ``carry``: a whole drive from its first sample (fields of every row). With it:
        the previous and the new sample (or the first one alone).
    rover : RoverConfig
    noise : NoiseConfig
        The drive's simulated noise (the odometry's covariances).
    carry : Carry, optional
        A live stream's running integrals, advanced to the new sample; then only the new
        sample's fields are returned (N = 1).
    """
    mo_xyz, mo_q = bd.map_to_odom(rows.gt, rows.odom)
    pos, vel, twist = bd.joint_states(rows.wheels, rover)
    gt_lin, gt_ang = bd.body_twist_from_poses(rows.gt)
    od, t = rows.odom, rows.odom.timestamps_s
    tw = twist_covariance(rows.wheels[:, 1:7], rows.wheels[:, 7:11], noise, rover)
    if carry is None:
        yaw = np.unwrap(Rotation.from_quat(od.quat_xyzw).as_euler("xyz")[:, 2])
        pose3 = pose_covariance(t, twist[:, 0], yaw, tw)
        pose_cov, twist_cov = bd.odometry_covariance_rows(pose3, tw)
        return ControlFields(t, mo_xyz, mo_q, od.xyz_m, od.quat_xyzw, twist, pose_cov,
                             twist_cov, rows.gt.xyz_m, rows.gt.quat_xyzw, gt_lin, gt_ang, pos, vel)
    pose3 = np.zeros((3, 3))
    if len(t) == 2:  # the step from the previous sample, heading as it was there
        yaw_prev = float(Rotation.from_quat(od.quat_xyzw[0]).as_euler("xyz")[2])
        pose3 = carry.pose.step(float(t[1] - t[0]), float(twist[1, 0]), yaw_prev, tw[1])
    carry.angle_rad = carry.angle_rad + pos[-1, :6]  # the rows' own integral starts at 0
    pos[-1, :6] = carry.angle_rad
    pose_cov, twist_cov = bd.odometry_covariance_rows(pose3[None], tw[-1:])
    new = slice(len(t) - 1, len(t))
    return ControlFields(t[new], mo_xyz[new], mo_q[new], od.xyz_m[new], od.quat_xyzw[new],
                         twist[new], pose_cov, twist_cov, rows.gt.xyz_m[new],
                         rows.gt.quat_xyzw[new], gt_lin[new], gt_ang[new], pos[new], vel[new])


def tf(b: Any, f: ControlFields, i: int, map_tf: bool = True) -> Any:
    """``/tf`` at row ``i``: ``map -> odom`` (unless ``map_tf`` is false: a SLAM stack then
    publishes it) and ``odom -> base_link``."""
    od = (f.odom_xyz_m[i], f.odom_quat_xyzw[i])
    if map_tf:
        return b.state_tf(f.t_s[i], (f.map_odom_xyz_m[i], f.map_odom_quat_xyzw[i]), od)
    return b.tf_message([b.tf(f.t_s[i], "odom", "base_link", *od)])


def odometry(b: Any, f: ControlFields, i: int) -> Any:
    """``/rover/odom`` at row ``i``: the wheel odometry with its covariances."""
    return b.odometry(f.t_s[i], "odom", f.odom_xyz_m[i], f.odom_quat_xyzw[i],
                      (f.twist[i, 0], 0, 0), (0, 0, f.twist[i, 1]), f.pose_cov[i],
                      f.twist_cov[i])


def ground_truth(b: Any, f: ControlFields, i: int) -> Any:
    """``/rover/GT_Trajectory`` at row ``i``: ground truth in ``map``, its body twist."""
    return b.odometry(f.t_s[i], "map", f.gt_xyz_m[i], f.gt_quat_xyzw[i], f.gt_lin_m_s[i],
                      f.gt_ang_rad_s[i])


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
