"""``RoverNavEnv``: drive the MuJoCo rover to a goal on generated Mars worlds (Gymnasium).

Each step applies one ``cmd_vel`` (normalised to [-1, 1] by default: ``v`` up to 0.5 m/s,
``omega`` up to 0.2 rad/s, the rover's route-following bounds) for one control period
(``control_hz``, 5 Hz by default) of physics at ``physics_hz`` (100 Hz by default: the same
route within centimetres of the 500 Hz reference, ~4x faster; ``docs/gym.md``). Wheel odometry,
encoders and the IMU come from the run side's sensor models (:class:`~marsscene.sim.session.
DriveSession`, with a noise profile); the height scan, camera and LiDAR are sampled at the
observation's time.

Episodes end (``terminated``) at the goal, when the rover tips over, is stuck, leaves the
world or strays from the start-goal corridor; they are truncated at ``task.max_episode_s``.
``info`` holds every reward term, the reason an episode ended, and what
:meth:`RoverNavEnv.compute_reward` needs.
"""

from __future__ import annotations

import math
from collections import OrderedDict, deque
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from marsscene.env.loaded import LoadedWorld
from marsscene.env.observe import ObsConfig, lidar_image, observation_vector
from marsscene.env.reward import RewardConfig, compute_reward, goal_terms, step_terms
from marsscene.env.task import NavTask
from marsscene.env.worlds import WorldSampler, world_paths
from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig, LidarConfig, NoiseConfig, RoverConfig, RunConfig
from marsscene.sim.session import DriveSession

__all__ = ["RoverNavEnv"]

V_MAX_M_S, OMEGA_MAX_RAD_S = 0.5, 0.2


def _up_z(q_wxyz: Any) -> float:
    """The z component of the body's up axis in the world (cosine of the tilt)."""
    _, x, y, _ = q_wxyz
    return float(1.0 - 2.0 * (x * x + y * y))


class RoverNavEnv(gym.Env[dict[str, np.ndarray], np.ndarray]):
    """Point-goal navigation of the Perseverance-class rover on marsscene worlds.

    Parameters
    ----------
    worlds : path, list of paths or WorldSampler, optional
        Scene folders, or scenes drawn and built on demand (default: the ``plain`` world kind,
        8 worlds with the rock abundance k drawn in [0.05, 0.15]).
    task : NavTask
        Goal distances and tolerance, time limit, termination thresholds.
    observations : ObsConfig
        Height scan, camera, LiDAR, the pose source, the noise profile.
    reward : RewardConfig
        ``dense`` (RLRoverLab's terms) or ``sparse``.
    control_hz, physics_hz : float
        Actions per second (each held one period) and physics steps per second.
    normalized_actions : bool
        Actions in [-1, 1] (scaled to the rover's limits) rather than m/s and rad/s.
    rover : RoverConfig, optional
    max_worlds_loaded : int
        Worlds kept compiled in memory (least recently used dropped).
    render_mode : {"rgb_array"}, optional
        :meth:`render` returns the navcam's view (256 x 192).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 5}  # noqa: RUF012 (gymnasium's)

    def __init__(self, worlds: Any = None, *, task: NavTask | None = None,
                 observations: ObsConfig | None = None, reward: RewardConfig | None = None,
                 control_hz: float = 5.0, physics_hz: float = 100.0,
                 normalized_actions: bool = True, rover: RoverConfig | None = None,
                 max_worlds_loaded: int = 4, render_mode: str | None = None) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ConfigError(f"render_mode = {render_mode!r}; use None or 'rgb_array'")
        self.task = task if task is not None else NavTask()
        self.obs_config = observations if observations is not None else ObsConfig()
        self.reward_config = reward if reward is not None else RewardConfig()
        self.rover = rover if rover is not None else RoverConfig()
        self.worlds = worlds if worlds is not None else WorldSampler(
            base="plain", vary={"rocks.k": [0.05, 0.15]}, count=8)
        self.n_worlds, self._path = world_paths(self.worlds)
        self.run = RunConfig(control_hz=control_hz, imu_hz=2 * control_hz,
                             physics_hz=physics_hz,
                             noise=NoiseConfig(profile=self.obs_config.noise_profile))
        self.control_hz = float(control_hz)
        self.steps_total = max(1, round(self.task.max_episode_s * control_hz))
        self.render_mode, self.normalized = render_mode, bool(normalized_actions)
        self.max_worlds_loaded = int(max_worlds_loaded)
        self._lidar_config = (LidarConfig(model=self.obs_config.lidar,
                                          rate_hz=self.obs_config.lidar_rate_hz)
                              if self.obs_config.lidar else None)
        spec = self._lidar_config.spec if self._lidar_config else None
        self.lidar_shape = (spec.channels, spec.horizontal_samples) if spec else None
        self.observation_space = spaces.Dict(  # type: ignore[assignment]
            self.obs_config.spaces(self.lidar_shape))
        self._hi = np.ones(2, np.float32) if self.normalized else np.array(
            [V_MAX_M_S, OMEGA_MAX_RAD_S], np.float32)
        self.action_space = spaces.Box(-self._hi, self._hi, dtype=np.float32)
        self._loaded: OrderedDict[int, LoadedWorld] = OrderedDict()
        self._session: DriveSession | None = None
        self._world: LoadedWorld | None = None

    # ---- worlds ------------------------------------------------------------------------------
    def _load(self, index: int) -> LoadedWorld:
        if index in self._loaded:
            self._loaded.move_to_end(index)
            return self._loaded[index]
        world = LoadedWorld(self._path(index), self.run, self.rover, self.task, self.obs_config)
        self._loaded[index] = world
        while len(self._loaded) > self.max_worlds_loaded:
            _, old = self._loaded.popitem(last=False)
            old.close()
        return world

    def _camera(self, world: LoadedWorld, size: tuple[int, int]) -> Any:
        if world.renderer is None:
            from marsscene.sensors.camera import MastCamera

            cam = CameraConfig(width_px=size[0], height_px=size[1], rate_hz=self.control_hz,
                               depth=self.obs_config.depth, shadows=self.obs_config.shadows,
                               texture_px=1024)
            world.renderer = MastCamera(world.sim, config=cam)
        return world.renderer

    # ---- the episode -------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start an episode. ``options``: ``world`` (index), ``start`` (x, y), ``yaw`` (rad),
        ``goal`` (x, y); the rest is drawn from the seeded stream."""
        super().reset(seed=seed)
        opts = dict(options or {})
        unknown = sorted(set(opts) - {"world", "start", "yaw", "goal"})
        if unknown:
            raise ConfigError(f"reset options {unknown} are unknown; use world, start, yaw, goal")
        index = int(opts.get("world", self.np_random.integers(self.n_worlds)))
        if not 0 <= index < self.n_worlds:
            raise ConfigError(f"world = {index}; there are {self.n_worlds} worlds")
        world = self._load(index)
        if self._session is not None:
            self._session.close(release=False)
        start, _yaw, goal = self._place(world, opts)
        rng = np.random.default_rng(self.np_random.integers(2**63))
        lidar_rng, camera_rng = rng.spawn(2)  # the sensors' own streams, fixed per episode
        self._session = DriveSession(world.sim, rng=rng)
        if self._lidar_config is not None:
            if world.lidar is None:
                from marsscene.sensors.camera_world import read_rock_catalog
                from marsscene.sensors.lidar import Lidar

                world.lidar = Lidar(self._lidar_config, rng=lidar_rng,
                                    rocks=read_rock_catalog(world.sim.scene_dir))
            world.lidar.rng = lidar_rng
        if self.obs_config.camera is not None:
            self._camera(world, self.obs_config.camera).restart(world.sim, rng=camera_rng)
        self._world, self._goal, self._start = world, goal, start
        self._step, self._last_action = 0, np.zeros(2)
        self._track: deque[tuple[float, float, float]] = deque()
        obs = self._session.observe()
        self._obs = obs
        return self._observation(obs), self._info(obs, {}, "", world_index=index)

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool,
                                         dict[str, Any]]:
        if self._session is None or self._world is None:
            raise ConfigError("call reset() before step()")
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(2), -self._hi, self._hi)
        v, w = (a * [V_MAX_M_S, OMEGA_MAX_RAD_S]) if self.normalized else a
        session, world = self._session, self._world
        session.act(float(v), float(w))
        session.advance()
        obs = self._obs = session.observe()
        self._step += 1
        a_norm = a if self.normalized else a / [V_MAX_M_S, OMEGA_MAX_RAD_S]
        reason = self._ended(obs, bool(abs(v) > 0.05 or abs(w) > 0.05))
        terms = step_terms(a_norm, self._last_action, collided=world.collided(),
                           strayed=reason == "strayed", steps_total=self.steps_total,
                           cfg=self.reward_config)
        info = self._info(obs, terms, reason)
        reward = sum(info["reward_terms"].values())  # = compute_reward(ag, dg, info)
        self._last_action = a_norm
        truncated = not reason and self._step >= self.steps_total
        return self._observation(obs), float(reward), bool(reason), truncated, info

    def compute_reward(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised reward of goal pairs, for hindsight relabelling (:mod:`.reward`)."""
        return compute_reward(achieved_goal, desired_goal, info, cfg=self.reward_config,
                              tolerance_m=self.task.goal_tolerance_m,
                              steps_total=self.steps_total)

    # ---- helpers -----------------------------------------------------------------------------
    def _place(self, world: LoadedWorld, opts: dict[str, Any], tries: int = 20
               ) -> tuple[np.ndarray, float, np.ndarray]:
        """Draw (or take from ``opts``) start, heading and goal, and settle the rover there;
        a start where the settled rover leans over 20 deg or touches a rock is drawn again."""
        given = "start" in opts or "goal" in opts
        for _ in range(1 if given else tries):
            start, yaw, goal = world.task_map.draw(self.np_random)
            if given:
                start = np.asarray(opts.get("start", start), dtype=np.float64).reshape(2)
                goal = np.asarray(opts.get("goal", goal), dtype=np.float64).reshape(2)
                world.task_map.check(start, goal)
            yaw = float(opts.get("yaw", yaw))
            world.sim.settle_s = 3.0
            world.sim.reset(xy_m=(float(start[0]), float(start[1])), yaw_rad=yaw)
            if _up_z(world.sim.pose()[1]) > math.cos(math.radians(20.0)) \
                    and not world.collided():
                return start, yaw, goal
        where = "the given start" if given else f"{tries} drawn starts"
        raise ConfigError(f"the rover does not stand level and clear of rocks at {where}")

    def _ended(self, obs: Any, moving: bool) -> str:
        """Why the episode ends at this step ("" if it goes on)."""
        task, sim = self.task, self._world.sim  # type: ignore[union-attr]
        xy = obs.gt_xyz_m[:2]
        if math.hypot(*(xy - self._goal)) < task.goal_tolerance_m:
            return "goal"
        if _up_z(obs.gt_quat_wxyz) < math.cos(math.radians(task.max_tilt_deg)):
            return "tipped"
        x0, y0, x1, y1 = sim.heightfield.bounds_xy_m
        if min(xy[0] - x0, x1 - xy[0], xy[1] - y0, y1 - xy[1]) < 2.0:
            return "left_world"
        seg = self._goal - self._start
        s = np.clip(np.dot(xy - self._start, seg) / max(np.dot(seg, seg), 1e-9), 0.0, 1.0)
        if math.hypot(*(xy - self._start - s * seg)) > task.max_stray_m:
            return "strayed"
        if not moving:  # a pause restarts the stuck clock
            self._track.clear()
            return ""
        self._track.append((obs.t_s, float(xy[0]), float(xy[1])))
        while obs.t_s - self._track[0][0] > task.stuck_s + 1e-9:
            self._track.popleft()
        t0, x0_, y0_ = self._track[0]
        if obs.t_s - t0 >= task.stuck_s - 1e-9 and \
                math.hypot(xy[0] - x0_, xy[1] - y0_) < task.stuck_m:
            return "stuck"
        return ""

    def _info(self, obs: Any, terms: dict[str, float], reason: str, **extra: Any
              ) -> dict[str, Any]:
        ag = obs.gt_xyz_m[:2].astype(np.float32)
        left = self.steps_total - self._step
        goal = goal_terms(ag, self._goal, yaw_rad=obs.gt_yaw_rad, steps_left=left,
                          steps_total=self.steps_total, tolerance_m=self.task.goal_tolerance_m,
                          cfg=self.reward_config)
        return {"achieved_goal": ag, "desired_goal": self._goal.astype(np.float32),
                "distance_m": float(np.hypot(*(ag - self._goal))),
                "yaw_rad": float(obs.gt_yaw_rad), "steps_left": left,
                "reward_other": float(sum(terms.values())),
                "reward_terms": {**{k: float(v) for k, v in goal.items()}, **terms},
                "is_success": reason == "goal", "termination": reason, "t_s": obs.t_s,
                **extra}

    def _observation(self, obs: Any) -> dict[str, np.ndarray]:
        world = self._world
        assert world is not None
        out = {"observation": observation_vector(obs, self.rover, self._goal,
                                                 self.obs_config.pose_source,
                                                 self._last_action),
               "achieved_goal": obs.gt_xyz_m[:2].astype(np.float32),
               "desired_goal": self._goal.astype(np.float32)}
        if world.scanner is not None:
            out["height_scan"] = world.scanner(obs.gt_xyz_m, obs.gt_yaw_rad)
        if self.obs_config.camera is not None:
            rgb, depth = world.sim.render(world.renderer)
            out["rgb"] = rgb
            if self.obs_config.depth and depth is not None:
                out["depth"] = np.nan_to_num(depth, nan=0.0, posinf=0.0).astype(np.float32)
        if world.lidar is not None and self.lidar_shape is not None:
            sim = world.sim
            scan = world.lidar.scan(sim.model, sim.data, sim.lidar_site, sim.heightfield,
                                    twist=sim.site_twist(sim.lidar_site))
            out["lidar_range"], out["lidar_mask"] = lidar_image(scan, self.lidar_shape)
        return out

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self._world is None:
            return None
        size = self.obs_config.camera or (256, 192)
        renderer = self._camera(self._world, size)
        rgb, _ = self._world.sim.render(renderer)
        return rgb

    def close(self) -> None:
        if self._session is not None:
            self._session.close(release=False)
            self._session = None
        for world in self._loaded.values():
            world.close()
        self._loaded.clear()
        self._world = None
