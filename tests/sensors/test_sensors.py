"""Wheel odometry, IMU, LiDAR and camera: noise statistics, geometry, logs, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.errors import RuntimeSimError
from marsscene.runtime import (
    CameraConfig,
    LidarConfig,
    NoiseConfig,
    RoverConfig,
    RunConfig,
    ate,
    read_tum,
)
from marsscene.seeding import stage_rng
from marsscene.sensors.lidar import Lidar
from marsscene.sensors.odometry import WheelOdometry, measure_wheels
from marsscene.sim.driver import drive_sim
from marsscene.sim.rover_sim import RoverSim
from marsscene.sim.session import SessionOptions
from marsscene.transforms import quat_to_matrix
from tests.support.drive import step


def _straight_then_turn(t: float) -> tuple[float, float]:
    return (0.4, 0.0) if t < 8.0 else (0.3, 0.15)


def test_noise_free_odometry_matches_gt_on_flat(flat_scene) -> None:
    sim = RoverSim(flat_scene, start_xy_m=(-6.0, -3.0), start_yaw_rad=0.2)
    res = drive_sim(sim, command=_straight_then_turn, seconds=16.0, rng=stage_rng(0, "sensors"))
    dist = res.gt.path_length_m()
    assert dist > 5.0
    err = ate(res.odom, res.gt, align="none").stats
    assert err.max < 0.02 * dist  # within 2 % of the distance travelled
    assert res.odom.xyz_m[0] == pytest.approx(res.gt.xyz_m[0])


def test_wheel_noise_drift_statistics() -> None:
    """Final along-track error std = r * sigma / sqrt(6) * dt * sqrt(N) (6 wheels averaged)."""
    cfg = RoverConfig()
    sigma, dt, n, trials = 0.2, 0.02, 200, 200
    noise = NoiseConfig(wheel_rate_sigma_rad_s=sigma)
    rng = np.random.default_rng(2024)
    rates, steer = np.full(6, 1.0), np.zeros(4)
    final = np.zeros(trials)
    for k in range(trials):
        odo = WheelOdometry(cfg, 0.0, 0.0, 0.0, 0.0)
        for _ in range(n):
            odo.update(*measure_wheels(rates, steer, noise, rng=rng), dt)
        final[k] = odo.x_m
    truth = cfg.wheel_radius_m * 1.0 * dt * n
    expected_sd = cfg.wheel_radius_m * sigma / math.sqrt(6) * dt * math.sqrt(n)
    assert final.std(ddof=1) == pytest.approx(expected_sd, rel=0.15)  # 5 % standard error
    assert abs(final.mean() - truth) < 4 * expected_sd / math.sqrt(trials)


def test_slip_scales_odometry_distance() -> None:
    cfg = RoverConfig()
    odo = WheelOdometry(cfg, 0.0, 0.0, 0.0, 0.0)
    noise = NoiseConfig(slip_mean=0.1)
    rng = np.random.default_rng(0)
    for _ in range(100):
        odo.update(*measure_wheels(np.full(6, 2.0), np.zeros(4), noise, rng=rng), 0.02)
    assert odo.x_m == pytest.approx(1.1 * cfg.wheel_radius_m * 2.0 * 2.0, rel=1e-12)


@pytest.mark.parametrize("bias_z", [0.0, 0.1])
def test_imu_at_rest_reads_mars_gravity(flat_scene, bias_z: float) -> None:
    sigma = 0.05
    noise = NoiseConfig(
        accel_sigma_m_s2=sigma, gyro_sigma_rad_s=0.01, accel_bias_m_s2=(0.0, 0.0, bias_z)
    )
    sim = RoverSim(flat_scene, run=RunConfig(noise=noise, imu_hz=250.0))
    res = drive_sim(
        sim, command=(0.0, 0.0), seconds=2.0, rng=stage_rng(1, "sensors"),
        session=SessionOptions(keep_sensors=True),
    )
    acc, gyr = res.imu[:, 1:4], res.imu[:, 4:7]
    n = len(acc)
    assert n == 501
    assert acc[:, 2].mean() == pytest.approx(3.72 + bias_z, abs=4 * sigma / math.sqrt(n) + 0.005)
    assert np.abs(acc[:, :2].mean(0)).max() < 4 * sigma / math.sqrt(n) + 0.005
    assert acc[:, 2].std(ddof=1) == pytest.approx(sigma, rel=0.15)
    assert np.abs(gyr.mean(0)).max() < 4 * 0.01 / math.sqrt(n) + 1e-3


def test_lidar_hits_flat_ground_and_dust_only_dims(flat_scene) -> None:
    sim = RoverSim(flat_scene)
    clear = Lidar(LidarConfig(model="simple", channels=16, horizontal_samples=90))
    dusty = Lidar(LidarConfig(model="simple", channels=16, horizontal_samples=90,
                              dust_extinction_per_m=0.02))
    a = clear.scan(sim.model, sim.data, sim.lidar_site, sim.heightfield)
    b = dusty.scan(sim.model, sim.data, sim.lidar_site, sim.heightfield)
    c = clear.scan(sim.model, sim.data, sim.lidar_site)  # MuJoCo's own ray-hfield test
    np.testing.assert_allclose(a["range_m"], c["range_m"], rtol=1e-4)
    # sensor frame -> world: every return lies on the z = 0 ground
    rot = sim.data.site_xmat[sim.lidar_site].reshape(3, 3)
    world = a["xyz_m"].astype(np.float64) @ rot.T + sim.data.site_xpos[sim.lidar_site]
    assert len(world) > 0
    assert np.abs(world[:, 2]).max() < 1e-3
    assert set(np.unique(a["ring"])) <= set(range(8))  # only downward channels hit
    # LiDAR height ~ 2.1 m: a ring at elevation e reaches r = h / sin(-e)
    h = sim.data.site_xpos[sim.lidar_site][2]
    e = np.radians(np.linspace(-15, 15, 16))[a["ring"]]
    np.testing.assert_allclose(a["range_m"], h / np.sin(-e), rtol=0.02)
    np.testing.assert_array_equal(a["range_m"], b["range_m"])  # dust never changes range
    np.testing.assert_allclose(
        b["intensity"] / a["intensity"], np.exp(-2 * 0.02 * a["range_m"]), rtol=1e-5
    )


def test_camera_rgbd(flat_scene) -> None:
    sim = RoverSim(flat_scene, run=RunConfig(camera=CameraConfig(width_px=64, height_px=48)))
    try:
        renderer = sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
    rgb, depth = sim.render(renderer)
    renderer.close()
    assert rgb.shape == (48, 64, 3) and rgb.dtype == np.uint8
    assert depth is not None and depth.shape == (48, 64)
    assert rgb[-1].mean() > 30  # ground is lit (lower rows see the terrain)
    # the optical axis hits the ground at depth = ray distance along it
    import mujoco

    cam = sim.camera_id
    fwd = -sim.data.cam_xmat[cam].reshape(3, 3)[:, 2]
    dist = mujoco.mj_ray(
        sim.model,
        sim.data,
        sim.data.cam_xpos[cam],
        fwd,
        np.array([1, 1, 0, 1, 0, 0], np.uint8),
        1,
        -1,
        np.zeros(1, np.int32),
    )
    centre = depth[23:25, 31:33].mean()
    assert centre == pytest.approx(dist, rel=0.03)


def test_logs_layout_and_determinism(gentle_scene, tmp_path) -> None:
    noise = NoiseConfig(
        wheel_rate_sigma_rad_s=0.05, slip_sigma=0.02, accel_sigma_m_s2=0.02, gyro_sigma_rad_s=0.002
    )
    run = RunConfig(noise=noise, lidar=LidarConfig(horizontal_samples=90))
    outs = []
    for k in range(2):
        sim = RoverSim(gentle_scene, run=run)
        drive_sim(
            sim,
            command=(0.3, 0.05),
            seconds=1.0,
            out_dir=tmp_path / f"r{k}",
            rng=stage_rng(7, "sensors"),
        )
        outs.append(tmp_path / f"r{k}")
    for name in (
        "gt.tum",
        "odom.tum",
        "imu.csv",
        "wheels.csv",
        "cmd.csv",
        "run.json",
        "lidar/stamps.csv",
        "lidar/000005.ply",
    ):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    gt = read_tum(outs[0] / "gt.tum")
    assert len(gt) == 51 and gt.timestamps_s[-1] == pytest.approx(1.0)
    assert len((outs[0] / "imu.csv").read_text().splitlines()) == 1 + 101
    ply = (outs[0] / "lidar" / "000000.ply").read_bytes()
    head, body = ply.split(b"end_header\n")
    n = int(head.split(b"element vertex ")[1].split()[0])
    rec = np.frombuffer(body, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("i", "<f4"),
                                     ("t", "<u4"), ("r", "<u2")])
    assert len(rec) == n > 0
    assert np.all((rec["i"] >= 0) & (rec["i"] <= 1))
    assert np.all(np.diff(rec["t"].astype(np.int64)) >= 0) and rec["t"].max() < 100_000_000
    # other seed -> other noise
    sim = RoverSim(gentle_scene, run=run)
    drive_sim(
        sim, command=(0.3, 0.05), seconds=1.0, out_dir=tmp_path / "r2", rng=stage_rng(8, "sensors")
    )
    assert (tmp_path / "r2" / "imu.csv").read_bytes() != (outs[0] / "imu.csv").read_bytes()


def test_quat_matrix_roundtrip() -> None:
    from marsscene.transforms import matrix_to_quat

    q = np.random.default_rng(3).normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q *= np.sign(q[:, :1])
    np.testing.assert_allclose(matrix_to_quat(quat_to_matrix(q)), q, atol=1e-9)


def test_noise_config_validation_and_file(tmp_path) -> None:
    from marsscene.errors import ConfigError

    with pytest.raises(ConfigError, match="wheel_rate_sigma_rad_s"):
        NoiseConfig(wheel_rate_sigma_rad_s=-1.0)
    p = tmp_path / "noise.toml"
    p.write_text("[noise]\nwheel_rate_sigma_rad_s = 0.1\ngyro_bias_rad_s = [0, 0, 0.001]\n")
    cfg = NoiseConfig.from_toml(p)
    assert cfg.wheel_rate_sigma_rad_s == 0.1 and cfg.gyro_bias_rad_s == (0.0, 0.0, 0.001)
    p.write_text("[noise]\nwheel_sigma = 0.1\n")
    with pytest.raises(ConfigError, match=r"unknown key noise\.wheel_sigma"):
        NoiseConfig.from_toml(p)


def test_camera_terrain_window_matches_full_render(gentle_scene) -> None:
    """The windowed terrain (fast on big scenes) renders the near field exactly as the full one."""
    depths = {}
    for window in (20.0, 1e4):
        run = RunConfig(camera=CameraConfig(width_px=80, height_px=60, terrain_window_m=window))
        sim = RoverSim(gentle_scene, run=run, start_xy_m=(5.0, 3.0))
        for _ in range(25):
            step(sim, 0.5, 0.1)
        try:
            cam = sim.make_renderer()
        except RuntimeSimError as err:
            pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
        assert cam.windowed == (window < 40)
        depths[window] = sim.render(cam)[1]
        cam.close()
    near = slice(40, 60)  # lower rows: terrain within a few metres
    np.testing.assert_allclose(depths[20.0][near], depths[1e4][near], rtol=1e-3)


def test_far_window_bounds_replays_the_cameras_window(gentle_scene) -> None:
    """``far_window_bounds`` (what the VPR landmark measure uses to know which meshes the
    camera drew) gives the camera's own terrain window at every frame of a drive that moves
    the window several times."""
    from marsscene.sensors.camera_ground import far_window_bounds

    run = RunConfig(camera=CameraConfig(width_px=32, height_px=24, terrain_window_m=12.0))
    sim = RoverSim(gentle_scene, run=run, start_xy_m=(-12.0, -3.0))
    try:
        cam = sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")
    xy, bounds = [sim.pose()[0][:2].copy()], []  # placed where the camera was made
    for _ in range(60):  # ~15 m at 0.5 m/s, turning
        for _ in range(25):
            step(sim, 1.0, 0.15)
        sim.render(cam)
        xy.append(sim.pose()[0][:2].copy())
        bounds.append(cam.world.window_bounds_xy_m())
    cam.close()
    got = np.asarray(bounds)
    assert len({tuple(b) for b in bounds}) >= 3  # the window moved
    replay = far_window_bounds(sim.heightfield, 12.0, np.asarray(xy))
    np.testing.assert_allclose(replay[1:], got, atol=1e-9)
