"""Frame tree and bag array helpers against MuJoCo and the scalar kinematics."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from marsscene.rover.geometry import body_twist_from_wheels, wheel_commands
from marsscene.runs.export.bag_data import (
    body_twist_from_poses,
    joint_states,
    map_to_odom,
    rate_of_change,
)
from marsscene.runs.export.compose_state import ControlRows
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
    rot = Rotation.from_euler("z", yaw[:, None])
    lin, ang = body_twist_from_poses(t, xyz, rot)
    np.testing.assert_allclose(lin[1:-1], np.tile([v, 0, 0], (199, 1)), atol=1e-4)
    np.testing.assert_allclose(ang[:, 2], 0.2, atol=1e-9)
    # two poses: the backward difference at the second (what a live stream knows)
    lin2, ang2 = body_twist_from_poses(t[-2:], xyz[-2:], rot[-2:])
    np.testing.assert_allclose(lin2[1], rot[-1].inv().apply((xyz[-1] - xyz[-2]) / (t[-1] - t[-2])),
                               rtol=1e-12)
    np.testing.assert_allclose(ang2[1], [0.0, 0.0, 0.2], atol=1e-9)
    assert body_twist_from_poses(t[:1], xyz[:1], rot[:1])[0].tolist() == [[0.0, 0.0, 0.0]]
    drift = Rotation.from_euler("z", 0.05)  # odometry rotated and shifted from the truth
    od_xyz = drift.apply(xyz) + np.array([1.0, 2.0, 0.0])
    mo_xyz, mo_q = map_to_odom(xyz, rot, od_xyz, drift * rot)
    back = Rotation.from_quat(mo_q).apply(od_xyz) + mo_xyz
    np.testing.assert_allclose(back, xyz, atol=1e-9)
    np.testing.assert_allclose(mo_xyz, np.tile(mo_xyz[0], (201, 1)), atol=1e-9)  # one offset
    run = SimpleNamespace(gt=Trajectory(t, xyz, rot.as_quat()),
                          odom=Trajectory(t[:-1], od_xyz[:-1], rot.as_quat()[:-1]), wheels=None)
    with pytest.raises(Exception, match="same stamps"):
        ControlRows.of_run(run)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3), min_size=6, max_size=6),
       st.floats(0.0, 1e4), st.floats(1e-4, 10.0))
def test_rate_of_change_of_two_rows_is_numpys_gradient_bit_for_bit(v, t0, dt):
    """The two-row shortcut (a live stream's step) gives np.gradient's very floats."""
    values, t = np.array(v).reshape(2, 3), np.array([t0, t0 + dt])
    assert rate_of_change(values, t).tobytes() == np.gradient(values, t, axis=0).tobytes()
