"""The batched MuJoCo Warp environment on Warp's CPU device (no GPU): the CPU environment's
episode code, given each batched rover's state, gives the same observation and reward; rovers
reset alone; the same seed gives the same bytes; the vector and world-batch interfaces."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from marsscene.env import NavEpisode, RoverNavEnv, judgement
from marsscene.env.batch import BatchNavEnv, BatchVectorEnv, WarpPhysics, WorldBatch
from marsscene.env.batch.judge import collided
from marsscene.env.batch.model import tiled_model, warp_model
from marsscene.env.observe import HeightScanner, ObsConfig
from marsscene.env.reward import RewardConfig
from marsscene.errors import ConfigError
from marsscene.rover.config import OMEGA_MAX_RAD_S, V_MAX_M_S, RoverConfig

N = 3


@pytest.fixture(scope="module")
def env(batch: WorldBatch) -> BatchNavEnv:
    return BatchNavEnv(batch, num_envs=N, device="cpu", library="numpy", seed=1,
                       reward=RewardConfig(progress=0.5))


def _cpu_episode(env: BatchNavEnv, i: int, coll: list[bool]) -> NavEpisode:
    """The CPU environment's episode of rover ``i``, at the batch's start and goal."""
    ep = NavEpisode(env.task, env.obs_config, env.reward_config, env.rover,
                    control_hz=env.control_hz)
    w = int(env.world[i])
    scanner = HeightScanner(env.obs_config.height_scan, env.batch.heightfield(w),
                            env.batch.obstacles(w))
    ep.world = SimpleNamespace(scanner=scanner, collided=lambda: coll[0], lidar=None)
    ep.start_xy_m, ep.goal_xy_m = env.start_xy_m[i].copy(), env.goal_xy_m[i].copy()
    ep.last_distance_m = float(np.hypot(*(ep.goal_xy_m - ep.start_xy_m)))
    ep.restart_judge(env.batch.bounds_xy_m[w])
    return ep


def _observation(env: BatchNavEnv, i: int, k: int) -> Any:
    """Rover ``i``'s state as the CPU session's Observation holds it (noise-free)."""
    ids = env.ids
    st = env.state()
    w, x, y, z = st.quat_wxyz[i]
    return SimpleNamespace(
        gt_xyz_m=st.xyz_m[i], gt_quat_wxyz=st.quat_wxyz[i],
        gt_yaw_rad=math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)),
        wheel_rates_rad_s=env._v["qvel"][i, ids["drive_dof"]].astype(np.float64),
        steer_rad=env._v["qpos"][i, ids["steer_qpos"]].astype(np.float64),
        accel_m_s2=st.accel_m_s2[i], gyro_rad_s=st.gyro_rad_s[i], t_s=k / env.control_hz)


def test_cpu_episode_gives_the_same_observation_and_reward(env: BatchNavEnv) -> None:
    env.bk.seed(7)
    env.reset()
    coll = [[False] for _ in range(N)]
    episodes = [_cpu_episode(env, i, coll[i]) for i in range(N)]
    rng = np.random.default_rng(0)
    checked = 0
    for k in range(1, 6):
        action = rng.uniform(-1, 1, (N, 2))
        action[:, 0] = np.abs(action[:, 0])
        obs, reward, terminated, truncated, _info = env.step(action)
        assert not (terminated | truncated).any(), "no episode may end in these steps"
        hit = collided(env._con, env._v["nacon"], env.world, env._rocks, env.bk)
        for i in range(N):
            coll[i][0] = bool(hit[i])
            a = np.clip(action[i], -1, 1)
            cpu_obs, cpu_reward, cpu_te, cpu_tr, _cpu_info = episodes[i].step(
                _observation(env, i, k), a, a[0] * V_MAX_M_S, a[1] * OMEGA_MAX_RAD_S)
            np.testing.assert_allclose(obs["observation"][i], cpu_obs["observation"],
                                       rtol=1e-6, atol=1e-6)
            np.testing.assert_allclose(obs["height_scan"][i], cpu_obs["height_scan"],
                                       atol=1e-6)
            np.testing.assert_array_equal(obs["achieved_goal"][i], cpu_obs["achieved_goal"])
            np.testing.assert_array_equal(obs["desired_goal"][i], cpu_obs["desired_goal"])
            assert reward[i] == pytest.approx(cpu_reward, rel=1e-12, abs=1e-12)
            assert (bool(terminated[i]), bool(truncated[i])) == (cpu_te, cpu_tr)
            checked += 1
    assert checked == 5 * N
    assert float(np.abs(obs["observation"][:, 5]).max()) > 0.05  # the rovers drove


def test_the_cpu_environment_and_the_batch_call_one_judgement(env: BatchNavEnv, nav_world: Any,
                                                             monkeypatch: Any) -> None:
    one, calls = judgement.judge_step, []

    def spy(state: Any, **kw: Any) -> judgement.Judgement:
        calls.append(state.xyz_m.shape[:-1])
        return one(state, **kw)

    monkeypatch.setattr(judgement, "judge_step", spy)
    cpu = RoverNavEnv(nav_world, control_hz=5.0, physics_hz=100.0)
    try:
        cpu.reset(seed=0)
        *_, info = cpu.step(np.zeros(2, np.float32))
    finally:
        cpu.close()
    env.reset()
    env.step(np.zeros((N, 2)))
    assert calls == [(), (N,)]  # one rover, then the batch of N: the same function
    assert info["termination"] == ""


def test_a_rover_reaching_its_goal_is_reset_alone(env: BatchNavEnv) -> None:
    env.reset()
    for _ in range(2):
        env.step(np.tile([0.6, 0.0], (N, 1)))
    before = env.state().xyz_m.copy()
    env.goal_xy_m[1] = before[1, :2]  # rover 1 stands on its goal
    obs, reward, terminated, truncated, info = env.step(np.tile([0.6, 0.0], (N, 1)))
    assert list(info["termination"]) == [0, 1, 0]
    assert list(terminated) == [False, True, False] and not truncated.any()
    assert reward[1] > 9.0  # the goal bonus: 5 x 2 x (time left)
    assert list(env.steps_done) == [3, 0, 3]
    assert info["final_observation"]["observation"][1, 2] < env.task.goal_tolerance_m
    after = env.state().xyz_m
    moved = np.hypot(*(after[:, :2] - before[:, :2]).T)
    assert moved[0] < 0.2 and moved[2] < 0.2  # the others drove on, 0.12 m in a step
    starts = env._pool["start"]
    assert np.hypot(*(starts - after[1, :2]).T).min() < 0.3  # rover 1: at a drawn start
    assert obs["observation"][1, 2] > env.task.distance_m[0] - 0.5


def test_same_seed_same_bytes(batch: WorldBatch, env: BatchNavEnv) -> None:
    runs = []
    for _ in range(2):
        e = BatchNavEnv(batch, num_envs=N, device="cpu", library="numpy", seed=4)
        rng = np.random.default_rng(2)
        out = [e.step(rng.uniform(-1, 1, (N, 2)))[0]["observation"].tobytes()
               for _ in range(3)]
        runs.append(out)
    assert runs[0] == runs[1]


def test_gymnasium_vector_api(env: BatchNavEnv) -> None:
    vec = BatchVectorEnv(env)
    obs, _ = vec.reset(seed=3)
    assert obs["observation"].shape == (N, 17)
    assert vec.single_observation_space["height_scan"].shape == obs["height_scan"].shape[1:]
    assert vec.action_space.shape == (N, 2)
    obs, reward, _terminated, _truncated, info = vec.step(vec.action_space.sample())
    assert reward.shape == (N,) and "final_obs" in info and info["_final_obs"].shape == (N,)


def test_world_batch_round_trip_and_bad_input(batch: WorldBatch, tmp_path: Any) -> None:
    path = batch.save(tmp_path / "b.npz")
    back = WorldBatch.load(path)
    for name in ("posts_z_m", "rock_xy_m", "starts_xy_m", "goals_xy_m", "yaws_rad",
                 "catalogue_rocks", "catalogue_world"):
        np.testing.assert_array_equal(getattr(back, name), getattr(batch, name))
    assert back.cell_m == batch.cell_m and back.bounds_xy_m.shape == (2, 4)
    # the camera's catalogue rocks: each world's rows of its scene's catalogue (not MJCF)
    cats = batch.catalogues()
    assert len(cats) == 2 and all(len(c) > 0 for c in cats)
    assert not np.array_equal(cats[0][:, 1:3].mean(0), cats[1][:, 1:3].mean(0))
    with np.load(path) as z:  # a batch saved before the catalogue loads with none
        old = {k: z[k] for k in z.files if not k.startswith("catalogue")}
    with open(tmp_path / "old.npz", "wb") as f:
        np.savez(f, **old)
    assert WorldBatch.load(tmp_path / "old.npz").catalogues()[0].shape == (0, 6)
    (tmp_path / "bad.npz").write_bytes(b"not a batch")
    with pytest.raises(ConfigError, match="not a world batch"):
        WorldBatch.load(tmp_path / "bad.npz")
    with pytest.raises(ConfigError, match="noise-free"):
        BatchNavEnv(batch, num_envs=1, device="cpu", observations=ObsConfig())


def test_physics_settings_reach_mujoco_warp(batch: WorldBatch, env: BatchNavEnv) -> None:
    import mujoco
    import mujoco_warp as mjw
    import warp as wp

    wheels = env.mj_model.geom_type[env.ids["wheel_geoms"]]
    assert (wheels == mujoco.mjtGeom.mjGEOM_SPHERE).all()  # the batch's default rover
    assert env.mj_model.opt.iterations == 100 and env.mjw_model.opt.deterministic == 0
    physics = WarpPhysics(iterations=20, ls_iterations=10, deterministic=True)
    terrains = batch.rock_terrains()
    tiled = tiled_model(terrains, [batch.heightfield(w) for w in range(batch.count)],
                        rover=RoverConfig(wheel_collision="cylinder"), physics_hz=100.0,
                        post_m=batch.cell_m, physics=physics)
    wheels = tiled.model.geom_type[tiled.ids["wheel_geoms"]]
    assert (wheels == mujoco.mjtGeom.mjGEOM_CYLINDER).all()
    assert (tiled.model.opt.iterations, tiled.model.opt.ls_iterations) == (20, 10)
    with wp.ScopedDevice("cpu"):
        assert warp_model(tiled.model, physics).opt.deterministic == int(
            mjw.DeterminismType.ALL)
    for bad in ({"iterations": 0}, {"njmax": -1}, {"post_m": 0.0}):
        with pytest.raises(ConfigError, match="WarpPhysics"):
            WarpPhysics(**bad)  # type: ignore[arg-type]
