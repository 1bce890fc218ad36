"""The batched environment's camera and LiDAR observations (marsscene.env.batch.sensing) on
Warp's CPU device: shapes, dtypes and spaces; a rover's depth on flat ground against the range
to the plane from the rover's camera mount; the LiDAR image against the batch LiDAR's scan of
the same state; a reset rover's sensors on its new world; the same seed giving the same bytes.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

import warp as wp

from marsscene.env.batch import BatchNavEnv, BatchVectorEnv, WorldBatch
from marsscene.env.batch.adapters import groups
from marsscene.env.observe import HeightScan, ObsConfig
from marsscene.errors import ConfigError
from marsscene.rover.geometry import navcam_mount
from marsscene.sensors.batch import BatchLidar
from marsscene.sensors.lidar import beam_geometry

N, PX = 3, 16
SENSED = ObsConfig(noise_profile="none", camera=(PX, PX), depth=True, lidar="simple",
                   height_scan=HeightScan(size_m=1.0, resolution_m=0.5))


@pytest.fixture(scope="module")
def env(batch: WorldBatch) -> BatchNavEnv:
    return BatchNavEnv(batch, num_envs=N, device="cpu", library="numpy", seed=1,
                       observations=SENSED)


def _model_bounds(env: BatchNavEnv) -> np.ndarray:
    off = env._offsets[env.world]
    return np.asarray(env._bounds[env.world] + np.concatenate([off, off], axis=1))


def _scan_image(env: BatchNavEnv, bounds: np.ndarray) -> np.ndarray:
    """A fresh BatchLidar's scan of the environment's current data, as (N, 1, beams, cols)."""
    with wp.ScopedDevice("cpu"):
        lidar = BatchLidar(env.mj_model, env.mjw_model, N, env.obs_config.lidar_config(),
                           seed=1)
        scan = lidar.scan(env.mjw_data, twist=lidar.site_twist(env.mjw_data),
                          bounds_xy_m=wp.array(bounds.astype(np.float32), dtype=float))
    s = lidar.spec
    rng = scan.range_m.numpy().reshape(N, s.horizontal_samples, s.channels)
    return rng.transpose(0, 2, 1)[:, None]


def test_shapes_dtypes_and_spaces(env: BatchNavEnv) -> None:
    vec = BatchVectorEnv(env)
    obs, _ = vec.reset(seed=2)
    space = vec.single_observation_space
    channels, columns = SENSED.lidar_shape  # type: ignore[misc]
    assert obs["depth"].shape == (N, 1, PX, PX) and obs["depth"].dtype == np.float32
    assert obs["rgb"].shape == (N, 3, PX, PX) and obs["rgb"].dtype == np.uint8
    assert obs["lidar_range"].shape == (N, 1, channels, columns) == (N, 1, 16, 360)
    assert obs["lidar_range"].dtype == np.float32 and obs["lidar_mask"].dtype == np.int8
    assert space.spaces["rgb"].shape == (3, PX, PX) and space.spaces["rgb"].dtype == np.uint8
    assert set(obs) == set(space.spaces)
    for key, box in space.spaces.items():
        assert box.shape == obs[key].shape[1:] and box.dtype == obs[key].dtype, key
        assert all(box.contains(obs[key][i]) for i in range(N)), key
    assert vec.observation_space["depth"].shape == (N, 1, PX, PX)
    assert vec.observation_space["rgb"].shape == (N, 3, PX, PX)
    np.testing.assert_array_equal(obs["lidar_mask"] == 1, obs["lidar_range"] > 0)
    assert 0.1 < obs["lidar_mask"].mean() < 0.9 and 0.2 < (obs["depth"] > 0).mean() < 0.95
    *_, info = vec.step(np.zeros((N, 2), np.float32))
    assert info["final_obs"]["depth"].shape == (N, 1, PX, PX)
    grouped = groups(obs)
    assert grouped["depth"] is obs["depth"]
    np.testing.assert_array_equal(grouped["rgb"] * 255.0, obs["rgb"])
    assert grouped["lidar"].shape == (N, 2, 16, 360) and grouped["lidar"].dtype == np.float32
    np.testing.assert_array_equal(grouped["lidar"][:, 1], obs["lidar_mask"][:, 0])
    assert grouped["policy"].shape == (N, 17 + 9)


def test_the_lidar_image_is_the_batch_lidars_scan_of_the_state(env: BatchNavEnv) -> None:
    env.reset()
    for _ in range(2):
        obs, *_ = env.step(np.tile([0.8, 0.3], (N, 1)))
    expect = _scan_image(env, _model_bounds(env))
    np.testing.assert_array_equal(obs["lidar_range"], expect)
    # the mask's rays are the scan's returns; the depth image is a copy the next step keeps
    kept = obs["depth"].copy()
    env.step(np.tile([0.8, 0.3], (N, 1)))
    np.testing.assert_array_equal(obs["depth"], kept)


def test_a_reset_rovers_sensors_see_its_new_world(env: BatchNavEnv, monkeypatch: Any) -> None:
    env.reset()
    env.step(np.zeros((N, 2)))
    old = int(env.world[1])
    pick = int(np.flatnonzero(env._pool["world"] != old)[0])  # an episode on the other world
    monkeypatch.setattr(env.bk, "randint", lambda high, n: np.full(n, pick))
    env.goal_xy_m[1] = env.state().xyz_m[1, :2]  # rover 1 stands on its goal: it is reset
    obs, _r, terminated, _t, info = env.step(np.zeros((N, 2)))
    assert bool(terminated[1]) and int(env.world[1]) != old
    bounds = _model_bounds(env)
    np.testing.assert_array_equal(obs["lidar_range"], _scan_image(env, bounds))
    # every return of rover 1 lies over its new world (the points, in the model frame)
    lidar = env.sensors.lidar
    dirs = beam_geometry(lidar.spec)[0]  # firing order
    rng = obs["lidar_range"][1, 0].T.ravel()  # (beams, columns) back to firing order
    site = env.mjw_data.site_xpos.numpy()[1, lidar.site]
    rot = env.mjw_data.site_xmat.numpy()[1, lidar.site].reshape(3, 3)
    pts = site + (dirs[rng > 0] * rng[rng > 0, None]) @ rot.T
    x0, y0, x1, y1 = bounds[1]
    slack = 0.1  # the sweep's motion (a reset rover barely moves) and the distortion model
    assert len(pts) > 500
    assert (pts[:, 0] > x0 - slack).all() and (pts[:, 0] < x1 + slack).all()
    assert (pts[:, 1] > y0 - slack).all() and (pts[:, 1] < y1 + slack).all()
    assert info["final_observation"]["lidar_range"].shape == obs["lidar_range"].shape


def test_depth_on_flat_ground_is_the_range_to_the_plane(batch: WorldBatch) -> None:
    flat = dataclasses.replace(
        batch, posts_z_m=np.zeros_like(batch.posts_z_m),
        rock_xy_m=np.zeros((0, 2)), rock_radius_m=np.zeros(0), rock_height_m=np.zeros(0),
        rock_world=np.zeros(0, np.int64), catalogue_rocks=np.zeros((0, 6)),
        catalogue_world=np.zeros(0, np.int64))
    obs_cfg = dataclasses.replace(SENSED, lidar=None)
    env = BatchNavEnv(flat, num_envs=2, device="cpu", library="numpy", seed=0,
                      observations=obs_cfg)
    depth = env.reset()["depth"][:, 0]
    st = env.state()
    pos, mount = navcam_mount(env.rover)  # the mount on the chassis, from the rover config
    x_axis, y_axis = np.array(mount[:3]), np.array(mount[3:])
    cam_body = np.column_stack([x_axis, y_axis, np.cross(x_axis, y_axis)])
    fy = 0.5 * PX / math.tan(math.radians(env.sensors.camera.config.fovy_deg) / 2)
    row = PX // 2
    for i in range(2):
        w, x, y, z = st.quat_wxyz[i]
        base = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
        cam_z_m = st.xyz_m[i, 2] + (base @ np.array(pos))[2]  # the ground is z = 0
        assert 1.8 < cam_z_m < 2.1  # the mast's height
        cols = np.arange(PX)
        rays = np.stack([(cols + 0.5 - PX / 2) / fy, np.full(PX, -(row + 0.5 - PX / 2) / fy),
                         -np.ones(PX)], axis=-1) @ (base @ cam_body).T
        expect = -cam_z_m / rays[:, 2]  # planar depth: the ray's optical-axis component is 1
        np.testing.assert_allclose(depth[i, row], expect, rtol=2e-3)
        pitch_deg = math.degrees(math.asin(-(base @ cam_body)[2, 2]))
        assert abs(abs(pitch_deg) - 20.0) < 2.0  # the mount's tilt, the rover near level
    assert (depth[:, 0] == 0).all()  # the top row sees the sky


def test_same_seed_same_bytes_and_bad_input(batch: WorldBatch) -> None:
    obs_cfg = dataclasses.replace(SENSED, lidar="vlp16")  # with range noise
    runs = []
    for _ in range(2):
        e = BatchNavEnv(batch, num_envs=2, device="cpu", library="numpy", seed=5,
                        observations=obs_cfg)
        rng = np.random.default_rng(3)
        runs.append([b"".join(o[k].tobytes() for k in ("rgb", "depth", "lidar_range",
                                                       "lidar_mask"))
                     for o in (e.step(rng.uniform(-1, 1, (2, 2)))[0] for _ in range(2))])
    assert runs[0] == runs[1]
    with pytest.raises(ConfigError, match="needs camera"):
        BatchNavEnv(batch, num_envs=1, device="cpu",
                    observations=ObsConfig(depth=True, noise_profile="none"))


def test_depth_only_observes_the_same_depth_without_rgb(env: BatchNavEnv,
                                                       batch: WorldBatch) -> None:
    """``ObsConfig(rgb=False)``: no ``"rgb"`` key or space, the same depth as with it; and
    ``rgb=False`` without depth is a one-line error."""
    alone = BatchNavEnv(batch, num_envs=N, device="cpu", library="numpy", seed=1,
                        observations=dataclasses.replace(SENSED, rgb=False))
    depths = []
    for e in (env, alone):
        e.seed(6)
        e.reset()
        rng = np.random.default_rng(2)
        obs = [e.step(rng.uniform(-1, 1, (N, 2)))[0] for _ in range(2)]
        depths.append(b"".join(o["depth"].tobytes() for o in obs))
        assert ("rgb" in obs[-1]) == (e is env)
    assert depths[0] == depths[1]
    assert "rgb" not in BatchVectorEnv(alone).single_observation_space.spaces
    with pytest.raises(ConfigError, match="rgb = false needs depth"):
        ObsConfig(camera=(PX, PX), rgb=False)


def test_final_sensors_off_casts_once_a_step_and_changes_no_observation(
        env: BatchNavEnv, monkeypatch: Any) -> None:
    sensors = env.sensors
    assert sensors is not None
    calls, cast = [], sensors.observe

    def counted(*args: Any) -> dict[str, Any]:
        calls.append(1)
        return cast(*args)

    monkeypatch.setattr(sensors, "observe", counted)
    runs, finals = [], []
    for final_sensors in (True, False):
        env.final_sensors = final_sensors
        env.seed(9)
        env.reset()
        calls.clear()
        rng = np.random.default_rng(4)
        steps = [env.step(rng.uniform(-1, 1, (N, 2))) for _ in range(3)]
        runs.append(b"".join(s[0][k].tobytes() for s in steps
                             for k in ("observation", "depth", "lidar_range")))
        finals.append((len(calls), set(steps[-1][4]["final_observation"])))
    env.final_sensors = True
    assert runs[0] == runs[1]
    assert finals[0][0] == 6 and finals[1][0] == 3
    assert {"depth", "lidar_range", "lidar_mask"} <= finals[0][1]
    assert finals[1][1] == {"observation", "achieved_goal", "desired_goal", "height_scan"}
