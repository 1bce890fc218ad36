"""``RoverNavEnv``: drive the MuJoCo rover to a goal on generated Mars worlds (Gymnasium).

Each step applies one ``cmd_vel`` (normalised to [-1, 1] by default: up to
``NavTask.ACTION_SCALE``, :data:`~marsscene.rover.config.V_MAX_M_S` and
:data:`~marsscene.rover.config.OMEGA_MAX_RAD_S`, the rover's route-following bounds) for one
control period (``control_hz``, 5 Hz by default) of physics at ``physics_hz`` (100 Hz by
default: the same route within centimetres of the 500 Hz reference, ~4x faster; :doc:`/gym`).

The class is an adapter between Gymnasium and two parts, as dm_control's ``composer`` and
Gymnasium-Robotics split an environment: the **physics** -- a world loaded and kept compiled
(:class:`~marsscene.env.loaded.LoadedWorld`: the simulator, height scanner, camera, LiDAR)
driven by a :class:`~marsscene.sim.session.DriveSession` (wheel odometry, encoders and the IMU
with a noise profile) -- and the **task** (:class:`~marsscene.env.episode.NavEpisode`: the
random stream, the start, the observation, reward, termination and truncation). ``info``
holds every reward term, the reason an episode ended, and what :meth:`RoverNavEnv.
compute_reward`, :meth:`~RoverNavEnv.compute_terminated` and :meth:`~RoverNavEnv.
compute_truncated` need.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from marsscene.env.episode import NavEpisode
from marsscene.env.loaded import LoadedWorld
from marsscene.env.observe import ObsConfig
from marsscene.env.reward import RewardConfig
from marsscene.env.task import NavTask
from marsscene.env.worlds import WorldSampler, world_paths
from marsscene.errors import ConfigError
from marsscene.rover.config import NoiseConfig, RoverConfig, RunConfig
from marsscene.sim.session import DriveSession, SessionOptions
from marsscene.sim.wheel_soil import soil_map_of

__all__ = ["CONTROL_HZ", "RoverNavEnv"]

#: The default control rate (actions per second; RLRoverLab's).
CONTROL_HZ = 5.0
#: The default physics rate (steps per second).
PHYSICS_HZ = 100.0
#: :meth:`RoverNavEnv.render`'s image size (width, height) px without a camera observation.
_RENDER_PX = (256, 192)
#: The environment's sessions sample the camera and LiDAR at each observation.
_SENSORS_AT_OBSERVE = SessionOptions(sensors_at_observe=True)


class RoverNavEnv(gym.Env[dict[str, np.ndarray], np.ndarray]):
    """Point-goal navigation of the Perseverance-class rover on marsscene worlds.

    Parameters
    ----------
    worlds : path, list of paths or WorldSampler, optional
        Scene folders, or scenes drawn and built on demand (default: the ``plain`` world kind,
        8 worlds with the rock abundance k drawn in [0.05, 0.15]).
    task : NavTask
        Goal distances and tolerance, time limit, start placement, termination thresholds.
    observations : ObsConfig
        Height scan, camera, LiDAR, the pose source, the noise profile.
    reward : RewardConfig
        ``dense`` (RLRoverLab's terms) or ``sparse``.
    control_hz, physics_hz : float
        Actions per second (each held one period) and physics steps per second.
    normalized_actions : bool
        Actions in [-1, 1] (scaled to the rover's limits) rather than m/s and rad/s.
    rover : RoverConfig, optional
    soil : str or sequence of str, optional
        Deformable soil under the wheels (``RunConfig.soil``): one soil's name, or several, one
        drawn per episode from the environment's seeded stream (``info["soil"]``). None: rigid
        ground.
    max_worlds_loaded : int
        Worlds kept compiled in memory (least recently used dropped).
    render_mode : {"rgb_array"}, optional
        :meth:`render` returns the navcam's view (256 x 192).

    Examples
    --------
    One world of the ``plain`` kind (60 m x 60 m, built on first use into ``cache_dir``) and
    goals 5–8 m away; ``gym.make("marsscene/RoverNav-v0", ...)`` takes the same keywords:

    >>> import tempfile
    >>> import numpy as np
    >>> from marsscene.env import NavTask, RoverNavEnv, WorldSampler
    >>> worlds = WorldSampler(base="plain", count=1, cache_dir=tempfile.mkdtemp())
    >>> env = RoverNavEnv(worlds, task=NavTask(distance_m=(5.0, 8.0)))
    >>> obs, info = env.reset(seed=0)
    >>> sorted(obs)
    ['achieved_goal', 'desired_goal', 'height_scan', 'observation']
    >>> obs["height_scan"].shape, env.action_space.shape
    ((51, 51), (2,))

    Full speed ahead for one control period (0.2 s):

    >>> obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
    >>> terminated, truncated, bool(5.0 < info["distance_m"] < 9.0)
    (False, False, True)
    >>> env.close()
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 5}  # noqa: RUF012 (gymnasium's)

    def __init__(self, worlds: Any = None, *, task: NavTask | None = None,
                 observations: ObsConfig | None = None, reward: RewardConfig | None = None,
                 control_hz: float = CONTROL_HZ, physics_hz: float = PHYSICS_HZ,
                 normalized_actions: bool = True, rover: RoverConfig | None = None,
                 soil: str | Sequence[str] | None = None, max_worlds_loaded: int = 4,
                 render_mode: str | None = None) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ConfigError(f"render_mode = {render_mode!r}; use None or 'rgb_array'")
        self.task = task if task is not None else NavTask()
        self.obs_config = observations if observations is not None else ObsConfig()
        self.reward_config = reward if reward is not None else RewardConfig()
        self.rover = rover if rover is not None else RoverConfig()
        self.worlds = worlds if worlds is not None else WorldSampler(
            base="plain", vary={"rocks.k": [0.05, 0.15]}, count=8)
        self.n_worlds, self._path = world_paths(self.worlds)
        self.soils = (() if soil is None or soil == "rigid" else
                      (soil,) if isinstance(soil, str) else tuple(soil))
        for name in self.soils:
            soil_map_of(name)  # one-line error for an unknown soil
        if len(self.soils) > 1 and "rigid" in self.soils:
            raise ConfigError("soil: 'rigid' cannot be drawn beside deformable soils (use "
                              "firm_regolith for firm ground)")
        self.run = RunConfig(control_hz=control_hz, imu_hz=2 * control_hz,
                             physics_hz=physics_hz, soil=self.soils[0] if self.soils else None,
                             noise=NoiseConfig(profile=self.obs_config.noise_profile),
                             camera=self.obs_config.camera_config(control_hz),
                             lidar=self.obs_config.lidar_config())
        self.control_hz = float(control_hz)
        self.episode = NavEpisode(self.task, self.obs_config, self.reward_config, self.rover,
                                  control_hz=self.control_hz)
        self.render_mode, self.normalized = render_mode, bool(normalized_actions)
        self.max_worlds_loaded = int(max_worlds_loaded)
        self.observation_space = spaces.Dict(self.obs_config.spaces())  # type: ignore[assignment]
        self._scale = np.array(self.task.ACTION_SCALE)
        self._hi = np.ones(2, np.float32) if self.normalized else self._scale.astype(np.float32)
        self.action_space = spaces.Box(-self._hi, self._hi, dtype=np.float32)
        self._loaded: OrderedDict[int, LoadedWorld] = OrderedDict()
        self._session: DriveSession | None = None
        self._world: LoadedWorld | None = None

    @property
    def steps_total(self) -> int:
        """Steps of a full episode (truncated after them)."""
        return self.episode.steps_total

    @property
    def lidar_shape(self) -> tuple[int, int] | None:
        """The LiDAR range image's (channels, columns) (None: no LiDAR observed)."""
        return self.obs_config.lidar_shape

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

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Start an episode. ``options``: ``world`` (index), ``start`` (x, y), ``yaw`` (rad),
        ``goal`` (x, y); the rest is drawn from the task's stream, seeded by ``seed``."""
        super().reset(seed=seed)
        opts = dict(options or {})
        self.episode.seed(seed)
        index = self.episode.draw_world(self.n_worlds, opts)
        world = self._load(index)
        extra = {}
        if len(self.soils) > 1:
            extra["soil"] = self.soils[int(self.np_random.integers(len(self.soils)))]
            drawn, wheels = soil_map_of(extra["soil"]), world.sim.wheel_soil
            assert drawn is not None and wheels is not None  # a deformable soil was asked for
            wheels.use(drawn)
        self._end_session()
        noise = self.episode.begin(world, opts)
        self._session = DriveSession(world.sim, rng=noise, renderer=world.renderer,
                                     lidar=world.lidar, options=_SENSORS_AT_OBSERVE)
        world.renderer = self._session.renderer or world.renderer  # kept for the next episode
        world.lidar = self._session.lidar
        self._world = world
        obs = self._session.observe()
        return self.episode.observe(obs), {
            **self.episode.info(obs, {}, "", world_index=index), **extra}

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool,
                                         dict[str, Any]]:
        if self._session is None or self._world is None:
            raise ConfigError("call reset() before step()")
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(2), -self._hi, self._hi)
        v, w = (a * self._scale) if self.normalized else a
        self._session.act(float(v), float(w))
        self._session.advance()
        obs = self._session.observe()
        a_norm = a if self.normalized else a / self._scale
        return self.episode.step(obs, a_norm, float(v), float(w))

    def compute_reward(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised reward of goal pairs, for hindsight relabelling (:mod:`.reward`)."""
        return self.episode.compute_reward(achieved_goal, desired_goal, info)

    def compute_terminated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised ``terminated`` of goal pairs, for hindsight relabelling
        (:mod:`.terminate`)."""
        return self.episode.compute_terminated(achieved_goal, desired_goal, info)

    def compute_truncated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised ``truncated`` of goal pairs (:mod:`.terminate`)."""
        return self.episode.compute_truncated(achieved_goal, desired_goal, info)

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self._world is None:
            return None
        renderer = self._world.camera(self.obs_config.camera or _RENDER_PX)
        rgb, _ = self._world.sim.render(renderer)
        return rgb

    def _end_session(self) -> None:
        """Close the episode's session, keeping its camera and LiDAR with their world."""
        if self._session is not None:
            self._session.close(release=False)
            self._session = None

    def close(self) -> None:
        self._end_session()
        for world in self._loaded.values():
            world.close()
        self._loaded.clear()
        self._world = None
