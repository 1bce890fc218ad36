"""``RoverState``: the rover as the navigation task reads it, arrays of a batch shape: (N,) for
N rovers, () for one.

Both physics produce it: the CPU environment's :class:`~marsscene.sim.session.DriveSession`
observation (:meth:`RoverState.of_observation`, one rover, batch shape ``()``: noisy encoders and
IMU, the pose the policy sees from odometry or the ground truth; the same functions on 1-element
arrays cost a tenth more, 15-20 us a step) and the batched environment's MuJoCo Warp
buffers (:meth:`RoverState.of_buffers`, N rovers, noise-free; ``BatchNavEnv.state()``). The task's
functions (:mod:`.taskmath`, :mod:`.judgement`) read nothing else of the physics.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from marsscene._xp import namespace
from marsscene.env import taskmath
from marsscene.rover.geometry import body_twist_from_wheels, body_twists_from_wheels
from marsscene.transforms import yaw_of_quat
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["RoverState"]


@dataclass(frozen=True)
class RoverState:
    """The task's view of N rovers (numpy or PyTorch arrays of one namespace, float64); shapes
    below for a batch (N,), without the N for one rover.

    Attributes
    ----------
    xyz_m : (N, 3)
        Ground-truth ``base_link`` position in the task's (the world's) frame.
    quat_wxyz : (N, 4)
        Ground-truth orientation.
    yaw_rad : (N,)
        Ground-truth heading.
    pose_xy_m, pose_yaw_rad : (N, 2), (N,)
        The pose the policy observes (the ground truth, or the wheel odometry).
    twist : (N, 2)
        Body ``(v, omega)`` from the wheel encoders (m/s, rad/s).
    accel_m_s2, gyro_rad_s : (N, 3)
        The latest IMU sample (specific force incl. gravity, angular rate; body frame).
    """

    xyz_m: Any
    quat_wxyz: Any
    yaw_rad: Any
    pose_xy_m: Any
    pose_yaw_rad: Any
    twist: Any
    accel_m_s2: Any
    gyro_rad_s: Any

    @property
    def xy_m(self) -> Any:
        """(N, 2) ground-truth position."""
        return self.xyz_m[..., :2]

    @classmethod
    def of_observation(cls, obs: Any, rover: Any, pose_source: str = "truth") -> RoverState:
        """One rover (batch shape ``()``) from a :class:`~marsscene.sim.control.Observation`;
        ``rover`` (a :class:`~marsscene.rover.config.RoverConfig`) turns wheel rates into the
        body twist,
        ``pose_source`` ``"truth"`` or ``"odom"`` picks the observed pose. Before the first IMU
        sample the IMU reads gravity at rest."""
        if pose_source == "truth":
            xy, yaw = obs.gt_xyz_m[:2], obs.gt_yaw_rad
        else:
            xy, yaw = obs.odom_xyz_m[:2], obs.odom_yaw_rad
        twist = body_twist_from_wheels(obs.wheel_rates_rad_s, obs.steer_rad, rover)
        acc = obs.accel_m_s2 if obs.accel_m_s2 is not None else (0.0, 0.0, MARS_GRAVITY_M_S2)
        gyr = obs.gyro_rad_s if obs.gyro_rad_s is not None else (0.0, 0.0, 0.0)
        f64 = lambda v: np.asarray(v, dtype=np.float64)  # noqa: E731
        return cls(xyz_m=f64(obs.gt_xyz_m), quat_wxyz=f64(obs.gt_quat_wxyz),
                   yaw_rad=f64(obs.gt_yaw_rad), pose_xy_m=f64(xy), pose_yaw_rad=f64(yaw),
                   twist=f64(twist), accel_m_s2=f64(acc), gyro_rad_s=f64(gyr))

    @classmethod
    def of_buffers(cls, qpos: Any, qvel: Any, sensordata: Any, ids: dict[str, Any],
                   offsets_xy_m: Any, rover: Any) -> RoverState:
        """N rovers from MuJoCo Warp's buffers (arrays (N, ...) of the batch's namespace):
        ``ids`` the tiled model's indices (``qpos_root``, ``drive_dof``, ``steer_qpos``,
        ``_acc_adr``, ``_gyr_adr``), ``offsets_xy_m`` (N, 2) each rover's tile offset (the
        state is in each world's frame); noise-free sensors, the true pose observed."""
        xp = namespace(qpos)
        r = ids["qpos_root"]
        xyz = xp.astype(qpos[:, r: r + 3], xp.float64)
        xyz = xp.concat([xyz[:, :2] - offsets_xy_m, xyz[:, 2:]], axis=1)
        quat = xp.astype(qpos[:, r + 3: r + 7], xp.float64)
        yaw = yaw_of_quat(quat)
        twist = body_twists_from_wheels(qvel[:, ids["drive_dof"]], qpos[:, ids["steer_qpos"]],
                                        rover)
        acc, gyr = ids["_acc_adr"], ids["_gyr_adr"]
        return cls(xyz_m=xyz, quat_wxyz=quat, yaw_rad=yaw, pose_xy_m=xyz[:, :2],
                   pose_yaw_rad=yaw, twist=twist,
                   accel_m_s2=xp.astype(sensordata[:, acc: acc + 3], xp.float64),
                   gyro_rad_s=xp.astype(sensordata[:, gyr: gyr + 3], xp.float64))

    def observations(self, goal_xy_m: Any, last_action: Any) -> dict[str, Any]:
        """The observation dict's entries of the task, (N, ...) each: ``observation`` (the
        vector), ``achieved_goal`` (the position) and ``desired_goal`` (the goal), float32;
        the environments add their sensors' (height scan, camera, LiDAR)."""
        return {"observation": self.observation_vector(goal_xy_m, last_action),
                "achieved_goal": _float32(self.xy_m), "desired_goal": _float32(goal_xy_m)}

    def observation_vector(self, goal_xy_m: Any, last_action: Any) -> Any:
        """The ``observation`` vector (N, 17) float32 (layout in :mod:`.observe`) towards goals
        ``goal_xy_m`` (N, 2), after ``last_action`` (N, 2)."""
        return taskmath.observation_vector(self.pose_xy_m, self.pose_yaw_rad, goal_xy_m,
                                           self.twist, self.accel_m_s2, self.gyro_rad_s,
                                           last_action)


def _float32(x: Any) -> Any:
    """``x`` as float32 (numpy's own ``astype`` for numpy arrays)."""
    if isinstance(x, np.ndarray):
        return x.astype(np.float32)
    xp = namespace(x)
    return xp.astype(x, xp.float32)
