"""The Gymnasium navigation environment: the API checks, determinism, vector envs, rewards,
terminations, the classical navigator, and one-line errors for bad options."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import marsscene.env as me
from marsscene._xp import namespace
from marsscene.env.reward import RewardConfig, compute_reward, goal_terms
from marsscene.env.terms import Quantities, reward_terms
from marsscene.errors import ConfigError

FAST = {"control_hz": 5.0, "physics_hz": 100.0}


def _env(world: Path, **kw: object) -> me.RoverNavEnv:
    return me.RoverNavEnv(world, **{**FAST, **kw})  # type: ignore[arg-type]


@pytest.mark.parametrize("env_id", sorted(i for i in gym.registry if i.startswith("marsscene/")))
def test_every_registered_id_passes_gymnasiums_checker(env_id, nav_world):
    env = gym.make(env_id, worlds=nav_world)
    try:
        check_env(env.unwrapped, skip_render_check=True)
        obs, _ = env.reset(seed=1)
        assert env.observation_space.contains(obs)
    finally:
        env.close()
    assert env_id in ("marsscene/RoverNav-v0", "marsscene/RoverNavSparse-v0",
                      "marsscene/RoverNavCamera-v0", "marsscene/RoverNavLidar-v0")


def _rollout(env: me.RoverNavEnv, seed: int, n: int = 25) -> tuple[list, list]:
    obs, _ = env.reset(seed=seed)
    actions = np.random.default_rng(seed).uniform(-1, 1, (n, 2)).astype(np.float32)
    seen, rewards = [obs], []
    for a in actions:
        obs, r, term, trunc, _ = env.step(a)
        seen.append(obs)
        rewards.append(r)
        if term or trunc:
            break
    return seen, rewards


def _same(a: list, b: list) -> bool:
    return len(a) == len(b) and all(
        all(np.array_equal(x[k], y[k]) for k in x) for x, y in zip(a, b, strict=True))


def test_same_seed_same_observations_and_trajectory(nav_world):
    env = _env(nav_world, observations=me.ObsConfig(lidar="vlp16"))
    try:
        first, r1 = _rollout(env, seed=4)
        _rollout(env, seed=9)  # another episode between: nothing carries over
        again, r2 = _rollout(env, seed=4)
        other, _ = _rollout(env, seed=5)
    finally:
        env.close()
    assert _same(first, again) and r1 == r2
    assert not np.array_equal(first[0]["desired_goal"], other[0]["desired_goal"])
    assert first[-1]["lidar_mask"].sum() > 1000  # the VLP-16 sees the ground


def test_the_sensors_are_the_sessions_sampled_at_each_observation(nav_world):
    env = _env(nav_world, observations=me.ObsConfig(lidar="vlp16", camera=(32, 24)))
    try:
        env.reset(seed=2)
        world, session = env._world, env._session
        lidar, camera = session.lidar, session.renderer
        for _ in range(3):
            obs, *_ = env.step(np.array([0.5, 0.1], np.float32))
            stamp = session.k * world.sim.dt_physics_s
            assert session.latest_scan()["t"] == stamp and session._frame.t_s == stamp
            assert np.array_equal(obs["rgb"], session._frame.rgb)
        assert session.n_lidar == session.n_cam == 4  # the reset's and each step's, no more
        env.reset(seed=3)  # the next episode's session keeps the world's camera and LiDAR
        assert env._session.lidar is lidar is world.lidar
        assert env._session.renderer is camera is world.renderer
    finally:
        env.close()


def test_a_vector_env_of_two_equals_two_single_envs(nav_world):
    vec = gym.vector.SyncVectorEnv([lambda: _env(nav_world) for _ in range(2)])
    singles = [_env(nav_world) for _ in range(2)]
    try:
        obs, _ = vec.reset(seed=[11, 12])
        one = [e.reset(seed=s)[0] for e, s in zip(singles, (11, 12), strict=True)]
        act = np.array([[0.8, 0.2], [0.5, -0.4]], np.float32)
        for _ in range(5):
            obs, rew, *_ = vec.step(act)
            steps = [e.step(a) for e, a in zip(singles, act, strict=True)]
        for i in range(2):
            for key in obs:
                np.testing.assert_array_equal(obs[key][i], steps[i][0][key])
            assert rew[i] == steps[i][1]
        assert not np.array_equal(one[0]["desired_goal"], one[1]["desired_goal"])
    finally:
        vec.close()
        for e in singles:
            e.close()


def _step_terms(action: np.ndarray, last: np.ndarray, *, collided: bool, strayed: bool,
                cfg: RewardConfig) -> dict[str, float]:
    """The goal-free terms of one step of a 200-step episode (the table's)."""
    zero = np.zeros(1)
    q = Quantities(xp=namespace(zero), zero=zero, dist_m=zero, bearing_rad=zero,
                   reached=zero > 0, steps_left=zero, steps_total=200.0, action=action[None],
                   last_action=last[None], collided=np.array([collided]),
                   strayed=np.array([strayed]), progress_m=zero)
    return {k: float(v[0]) for k, v in reward_terms(q, cfg, goal=False).items()}


def test_reward_terms_signs_and_zero_cases():
    cfg = RewardConfig()
    near = goal_terms([0.0, 0.0], [0.2, 0.0], yaw_rad=0.0, steps_left=100, steps_total=200,
                      tolerance_m=0.5, cfg=cfg)
    far = goal_terms([0.0, 0.0], [-20.0, 0.0], yaw_rad=0.0, steps_left=100, steps_total=200,
                     tolerance_m=0.5, cfg=cfg)
    assert near["goal"] == pytest.approx(5.0 * 2 * 100 / 200) and far["goal"] == 0
    assert near["distance"] > far["distance"] > 0 and near["bearing"] > far["bearing"] > 0
    assert far["heading_away"] < 0 and near["heading_away"] == 0  # the goal behind: > 2 rad
    calm = _step_terms(np.array([0.5, 0.0]), np.array([0.5, 0.0]), collided=False,
                       strayed=False, cfg=cfg)
    assert all(v == 0 for v in calm.values())
    rough = _step_terms(np.array([-0.5, 1.0]), np.array([0.5, -1.0]), collided=True,
                        strayed=True, cfg=cfg)
    assert all(rough[k] < 0 for k in ("oscillation", "reverse", "collision", "stray"))
    sparse = RewardConfig(kind="sparse")
    ag = np.array([[0.0, 0.0], [0.1, 0.0], [5.0, 5.0]])
    info = {"yaw_rad": np.zeros(3), "steps_left": np.zeros(3), "reward_other": np.zeros(3)}
    np.testing.assert_array_equal(
        compute_reward(ag, np.zeros((3, 2)), info, cfg=sparse, tolerance_m=0.5,
                       steps_total=10), [0.0, 0.0, -1.0])


def test_compute_reward_is_the_step_reward_and_relabels(nav_world):
    env = _env(nav_world)
    try:
        env.reset(seed=2)
        infos, rewards, goals = [], [], []
        for _ in range(6):
            obs, r, _, _, info = env.step(np.array([1.0, 0.3], np.float32))
            infos.append(info)
            rewards.append(r)
            goals.append(obs["achieved_goal"])
        ag = np.array([i["achieved_goal"] for i in infos])
        dg = np.array([i["desired_goal"] for i in infos])
        np.testing.assert_allclose(env.compute_reward(ag, dg, infos), rewards, rtol=1e-6)
        her = env.compute_reward(ag, ag, infos)  # relabelled: the goal is where it got
        assert np.all(her > np.asarray(rewards))
    finally:
        env.close()


def test_goal_and_tip_over_end_the_episode(flat_scene, slope_scene):
    env = _env(flat_scene)
    try:
        _, info = env.reset(seed=0, options={"start": [0.0, 0.0], "goal": [3.0, 0.0],
                                                "yaw": 0.0})
        assert info["distance_m"] == pytest.approx(3.0, abs=0.1)
        for _ in range(60):
            _, r, term, _, info = env.step(np.array([1.0, 0.0], np.float32))
            if term:
                break
        assert info["termination"] == "goal" and info["is_success"] and r > 1.0
    finally:
        env.close()
    tilt = _env(slope_scene, task=me.NavTask(max_tilt_deg=10.0, distance_m=(2.0, 6.0)))
    try:
        tilt.reset(seed=0, options={"start": [-5.0, 0.0], "goal": [0.0, 0.0], "yaw": 0.0})
        *_, term, _, info = tilt.step(np.zeros(2, np.float32))
        assert term and info["termination"] == "tipped"  # 15 deg slope, 10 deg limit
    finally:
        tilt.close()


def _with_wall(flat_scene: Path, tmp: Path) -> Path:
    """The flat scene with a 2 m tall, 4 m wide block 4 m east of the origin."""
    out = tmp / "walled"
    shutil.copytree(flat_scene, out)
    xml = out / "mjcf" / "scene.xml"
    text = xml.read_text()
    wall = '<geom name="rock_wall" type="box" size="0.5 2 1" pos="4 0 1" rgba="0.5 0.4 0.3 1"/>'
    xml.write_text(text.replace("</worldbody>", wall + "</worldbody>", 1))
    return out


def test_stuck_against_a_rock_and_leaving_the_world_end_the_episode(flat_scene, tmp_path):
    env = _env(_with_wall(flat_scene, tmp_path), task=me.NavTask(stuck_s=4.0,
                                                                   distance_m=(2.0, 20.0)))
    try:
        env.reset(seed=0, options={"start": [0.0, 0.0], "goal": [8.0, 4.5], "yaw": 0.0})
        reasons, collided = [], False
        for _ in range(100):
            *_, term, _, info = env.step(np.array([1.0, 0.0], np.float32))
            collided |= info["reward_terms"]["collision"] < 0
            if term:
                reasons.append(info["termination"])
                break
        assert reasons == ["stuck"] and collided
        env.reset(seed=0, options={"start": [-10.0, 0.0], "goal": [-6.0, 0.0], "yaw": math.pi})
        for _ in range(100):
            *_, term, _, info = env.step(np.array([1.0, 0.0], np.float32))
            if term:
                break
        assert info["termination"] == "left_world"
    finally:
        env.close()


def test_a_rover_bogged_in_sand_is_stuck_and_soils_are_drawn_per_episode(slope_scene):
    """Up a 15 deg slope of megaripple sand the wheels spin in place: the episode ends stuck
    (on rigid ground the same drive climbs); a list of soils is drawn from the seeded stream."""
    task = me.NavTask(stuck_s=4.0, distance_m=(2.0, 30.0))
    start = {"start": [-12.0, 0.0], "goal": [12.0, 0.0], "yaw": 0.0}
    ends = {}
    for soil in ("rigid", "megaripple_sand"):
        env = _env(slope_scene, task=task, soil=soil)
        try:
            env.reset(seed=0, options=start)
            for _ in range(40):
                *_, term, _, info = env.step(np.array([1.0, 0.0], np.float32))
                if term:
                    break
            ends[soil] = (info["termination"], info["distance_m"])
        finally:
            env.close()
    assert ends["megaripple_sand"][0] == "stuck"
    assert ends["rigid"][0] != "stuck" and ends["rigid"][1] < ends["megaripple_sand"][1] - 2.0
    env = _env(slope_scene, soil=("firm_regolith", "dry_sand"))
    try:
        drawn = [env.reset(seed=s, options=start)[1]["soil"] for s in range(8)]
        assert set(drawn) == {"firm_regolith", "dry_sand"}
        assert drawn == [env.reset(seed=s, options=start)[1]["soil"] for s in range(8)]
    finally:
        env.close()


def test_the_arc_navigator_reaches_a_goal_20_m_away_through_rocks(tmp_path):
    scan = me.HeightScan(size_m=10.0, resolution_m=0.1)
    sampler = me.WorldSampler(base="rocks", count=1, seed=1, cache_dir=str(tmp_path))
    env = me.RoverNavEnv(sampler, observations=me.ObsConfig(height_scan=scan),
                         task=me.NavTask(distance_m=(19.0, 21.0), max_episode_s=90.0))
    nav = me.ArcNavigator(scan)
    try:
        obs, info = env.reset(seed=3)
        start = np.array(obs["achieved_goal"])
        assert 19.0 <= np.hypot(*(start - obs["desired_goal"])) <= 21.0
        rocks_near_line = _rocks_near(env, start, np.array(obs["desired_goal"]))
        for _ in range(450):
            obs, _, term, trunc, info = env.step(nav(obs))
            if term or trunc:
                break
    finally:
        env.close()
    assert info["termination"] == "goal", info
    assert rocks_near_line > 0  # the straight line to the goal passes tall rocks


def _rocks_near(env: me.RoverNavEnv, a: np.ndarray, b: np.ndarray) -> int:
    from marsscene.sim.world import scene_obstacles

    o = scene_obstacles(env._world.sim)  # type: ignore[union-attr]
    tall = o.height_m > 0.3
    seg = b - a
    s = np.clip(((o.xy_m - a) @ seg) / (seg @ seg), 0, 1)
    d = np.hypot(*(o.xy_m - a - s[:, None] * seg).T)
    return int((tall & (d < o.radius_m + 1.2)).sum())


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"options": {"start": [0.0, 0.0], "goal": [100.0, 0.0]}}, "not on traversable ground"),
    ({"options": {"world": 5}}, "there are 1 worlds"),
    ({"options": {"sart": [0, 0]}}, "unknown"),
])
def test_bad_reset_options_are_one_line_errors(nav_world, kwargs, message):
    env = _env(nav_world)
    try:
        with pytest.raises(ConfigError, match=message) as err:
            env.reset(seed=0, **kwargs)
        assert "\n" not in str(err.value)
    finally:
        env.close()


@pytest.mark.parametrize(("make", "message"), [
    (lambda w: me.ObsConfig(pose_source="gps"), "pose_source"),
    (lambda w: me.ObsConfig(depth=True), "needs camera"),
    (lambda w: me.NavTask(distance_m=(10.0, 5.0)), "distance_m"),
    (lambda w: me.WorldSampler(base="moon"), "unknown"),
    (lambda w: me.WorldSampler(vary={"rocks.k": [2.0, 3.0]}), "rocks.k"),
    (lambda w: me.RoverNavEnv(w, control_hz=7.0), "divide"),
    (lambda w: me.RoverNavEnv(w.parent), "not a built scene"),
    (lambda w: me.RoverNavEnv(w, soil=["dry_sand", "quicksand"]), "quicksand"),
    (lambda w: me.RoverNavEnv(w, soil=["dry_sand", "rigid"]), "rigid"),
])
def test_bad_configs_are_one_line_errors(nav_world, make, message):
    with pytest.raises(ConfigError, match=message) as err:
        make(nav_world)
    assert "\n" not in str(err.value)
