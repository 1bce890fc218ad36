"""Frame tree and bag array helpers against MuJoCo and the scalar kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from marsscene.rover.geometry import body_twist_from_wheels, wheel_commands
from marsscene.runs.export.bag_data import body_twist_from_poses, joint_states, map_to_odom
from marsscene.runs.export.frames import frame_in_base, static_transforms
from marsscene.runtime import RoverConfig, Trajectory
from marsscene.sim.rover_sim import RoverSim


def test_sensor_frames_match_the_mujoco_camera_and_lidar_site(flat_scene) -> None:
    sim = RoverSim(flat_scene, start_yaw_rad=0.7)
    pos, quat_wxyz = sim.pose()
    world_base = np.eye(4)
    world_base[:3, :3] = Rotation.from_quat(quat_wxyz[[1, 2, 3, 0]]).as_matrix()
    world_base[:3, 3] = pos
    tfs = static_transforms(sim.rover)
    cam = world_base @ frame_in_base(tfs, "navcam_optical_frame")
    # MuJoCo cameras look along -z with y up; the optical frame is x right, y down, z forward
    mj = sim.data.cam_xmat[sim.camera_id].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
    np.testing.assert_allclose(cam[:3, :3], mj, atol=1e-6)
    np.testing.assert_allclose(cam[:3, 3], sim.data.cam_xpos[sim.camera_id], atol=1e-6)
    lidar = world_base @ frame_in_base(tfs, "lidar_link")
    np.testing.assert_allclose(lidar[:3, 3], sim.data.site_xpos[sim.lidar_site], atol=1e-6)
    np.testing.assert_allclose(lidar[:3, :3], sim.data.site_xmat[sim.lidar_site].reshape(3, 3),
                               atol=1e-6)


def test_joint_states_and_twists_from_wheels_match_the_kinematics() -> None:
    rover = RoverConfig()
    t = np.arange(50) * 0.02
    cmds = [(0.3, 0.1 * np.sin(k / 7)) for k in range(50)]
    rows = [np.concatenate([[ti], *wheel_commands(v, w, rover)])
            for ti, (v, w) in zip(t, cmds, strict=True)]
    pos, vel, twist = joint_states(np.array(rows), rover)
    np.testing.assert_allclose(twist, cmds, atol=1e-12)
    scalar = [body_twist_from_wheels(r[1:7], r[7:11], rover) for r in rows]
    np.testing.assert_allclose(twist, scalar, atol=1e-12)
    rates = np.array(rows)[:, 1:7]
    np.testing.assert_allclose(pos[-1, :6], (rates[1:] * 0.02).sum(axis=0), atol=1e-12)
    np.testing.assert_allclose(vel[:, :6], rates)


def test_map_to_odom_and_gt_twist() -> None:
    t = np.linspace(0.0, 4.0, 201)
    yaw = 0.2 * t
    v = 0.5
    xyz = np.column_stack([v / 0.2 * np.sin(yaw), v / 0.2 * (1 - np.cos(yaw)), 0 * t])
    gt = Trajectory(t, xyz, Rotation.from_euler("z", yaw[:, None]).as_quat())
    lin, ang = body_twist_from_poses(gt)
    np.testing.assert_allclose(lin[1:-1], np.tile([v, 0, 0], (199, 1)), atol=1e-4)
    np.testing.assert_allclose(ang[:, 2], 0.2, atol=1e-9)
    drift = Rotation.from_euler("z", 0.05)  # odometry rotated and shifted from the truth
    odom = Trajectory(t, drift.apply(xyz) + np.array([1.0, 2.0, 0.0]),
                      (drift * Rotation.from_euler("z", yaw[:, None])).as_quat())
    mo_xyz, mo_q = map_to_odom(gt, odom)
    back = Rotation.from_quat(mo_q).apply(odom.xyz_m) + mo_xyz
    np.testing.assert_allclose(back, xyz, atol=1e-9)
    with pytest.raises(Exception, match="same stamps"):
        map_to_odom(gt, Trajectory(t[:-1], xyz[:-1], gt.quat_xyzw[:-1]))
