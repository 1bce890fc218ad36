"""An off-the-shelf LiDAR odometry tracks the default LiDAR: KISS-ICP (pip ``kiss-icp``, its
default configuration, run as ``kiss_icp_pipeline --topic /rover/lidar/points RUN/bag``) on an
8 m drive over a rocky plain, scored against the lidar_link ground truth."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("kiss_icp")
pytest.importorskip("rosbags")

import marsscene as ms
from marsscene.benchmark.slam.kiss_icp import (
    LiveKissIcp,
    lidar_ground_truth,
    lidar_mount,
    run_kiss_icp,
    score_lidar_odometry,
)
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.rover.lidar import LidarConfig
from marsscene.runs.export.bag import write_bag
from marsscene.runs.runlog import RunLog
from marsscene.seeding import stage_rng
from marsscene.sim.driver import drive_sim
from marsscene.sim.rover_sim import RoverSim
from marsscene.sim.session import SessionOptions


def test_kiss_icp_tracks_an_8_m_drive_within_1_percent(tmp_path):
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [80, 80], "post_m": 0.25,
                    "rms_height_m": 0.02},
        "craters": {"enabled": False}, "rocks": {"k": 0.15, "d_min_m": 0.15}})
    ms.write_scene(ms.build_scene(cfg, seed=4), tmp_path / "s", formats=("mjcf",))
    sim = RoverSim(tmp_path / "s", run=RunConfig(lidar=LidarConfig()), start_xy_m=(-5.0, 0.0),
                   contact_corridor_xy_m=np.array([[-5.0, 0.0], [5.0, 0.0]]),
                   contact_corridor_m=40.0)
    live = LiveKissIcp()  # the same odometry fed during the drive
    mount = lidar_mount(RoverConfig())
    primed = LiveKissIcp(wheel_prior=True, lidar_mount=mount)
    predictions = []  # the wheel step KISS-ICP is given before each scan
    register = primed._register_with_prior
    primed._register_with_prior = lambda xyz, t, step: (  # type: ignore[method-assign]
        predictions.append(np.eye(4) if step is None else step), register(xyz, t, step))[1]
    drive_sim(sim, command=(0.5, 0.0), seconds=16.0, out_dir=tmp_path / "r",
              rng=stage_rng(1, "sensors"), session=SessionOptions(listeners=(live, primed)))
    write_bag(tmp_path / "r", tmp_path / "r" / "bag")
    run = RunLog(tmp_path / "r")
    estimate = run_kiss_icp(tmp_path / "r" / "bag")
    score = score_lidar_odometry(estimate, run)
    assert score.status == "ok" and score.poses == len(run.lidar[0])
    assert score.path_m > 7.0
    assert score.ate_percent < 1.0, score
    assert abs(score.estimated_path_m / score.path_m - 1.0) < 0.3, score
    # the ground truth it is scored against is the lidar_link pose: the mast top
    gt = lidar_ground_truth(run.gt, run.rover)
    assert np.all(gt.xyz_m[:, 2] - run.gt.xyz_m[:, 2] > 1.0)
    # fed live, KISS-ICP gives the pipeline's estimate on the bag (which writes 4 decimals)
    traj = live.trajectory()
    assert traj is not None and len(traj) == len(estimate)
    np.testing.assert_allclose(traj.timestamps_s, estimate.timestamps_s, atol=6e-5)
    np.testing.assert_allclose(traj.xyz_m, estimate.xyz_m, atol=6e-5)
    dots = np.abs(np.sum(traj.quat_xyzw * estimate.quat_xyzw, axis=1))
    assert np.all(dots > 1.0 - 1e-6)

    # with the wheel prior: each scan's predicted step is the wheel odometry's travel between
    # the scans with the gyro's rotation (its logged samples integrated), in the lidar frame,
    # and it tracks as well
    from scipy.spatial.transform import Rotation

    odom = {round(float(t), 6): (x, q) for t, x, q in zip(run.odom.timestamps_s, run.odom.xyz_m,
                                                           run.odom.quat_xyzw, strict=True)}
    imu_t, gyro = run.imu[:, 0], run.imu[:, 4:7]
    attitude = [np.eye(3)]
    for j in range(1, len(imu_t)):
        turn = Rotation.from_rotvec(gyro[j] * (imu_t[j] - imu_t[j - 1])).as_matrix()
        attitude.append(attitude[-1] @ turn)

    def wheel_base(t):
        x, q = odom[round(float(t), 6)]
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = Rotation.from_quat(q).as_matrix(), x
        return pose

    def attitude_at(t):
        return attitude[int(np.searchsorted(imu_t, t + 1e-9, side="right")) - 1]

    stamps = run.lidar[0]
    planar_gap = 0.0
    for k in range(1, len(stamps)):
        base = np.linalg.inv(wheel_base(stamps[k - 1])) @ wheel_base(stamps[k])
        planar = np.linalg.inv(mount) @ base @ mount
        base[:3, :3] = attitude_at(stamps[k - 1]).T @ attitude_at(stamps[k])
        step = np.linalg.inv(mount) @ base @ mount
        np.testing.assert_allclose(predictions[k], step, atol=1e-5)  # imu.csv: 9 digits
        planar_gap = max(planar_gap, float(np.abs(planar[:3, :3] - step[:3, :3]).max()))
    assert planar_gap > 1e-3  # the ground's bumps tilt the rover: not the planar rotation
    assert np.linalg.norm(predictions[len(stamps) // 2][:3, 3]) > 0.03  # the rover moves
    primed_score = score_lidar_odometry(primed.trajectory(), run)
    assert primed_score.ate_percent < 1.0, primed_score
    # where the scans have structure most ICP steps pass the gate (77 % here; a scan-to-map
    # ICP's single steps scatter by a few cm): LiDAR odometry, not the wheel odometry again
    assert primed.icp_steps_kept > 0.6 * len(stamps), primed.icp_steps_kept
