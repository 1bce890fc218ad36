"""``NavEpisode``: the navigation task's side of an episode -- its random stream, the start,
the observation, the reward, termination and truncation.

The split follows dm_control's ``composer.Task`` (``initialize_episode``, ``get_observation``,
``get_reward``, ``should_terminate_episode``) and Gymnasium-Robotics' goal environments
(``compute_reward`` / ``compute_terminated`` / ``compute_truncated`` of achieved and desired
goals): :class:`~marsscene.env.nav.RoverNavEnv` holds the physics (a
:class:`~marsscene.sim.session.DriveSession` on a :class:`~marsscene.env.loaded.LoadedWorld`)
and hands each control step's :class:`~marsscene.sim.control.Observation` to the episode, which
decides everything else.

The episode's random stream is ``numpy.random.default_rng(seed)`` of the seed given to
``reset`` (Gymnasium's ``np_random`` of that seed; ``seed=None`` continues the stream). Each
reset draws from it, in order: the world (unless given), the start, heading and goal, then one
integer that seeds the physics session's noise (IMU, wheels) and the sensors' streams.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.env import judgement
from marsscene.env.loaded import LoadedWorld
from marsscene.env.observe import ObsConfig, lidar_image
from marsscene.env.reward import RewardConfig, compute_reward
from marsscene.env.state import RoverState
from marsscene.env.task import NavTask
from marsscene.env.taskmath import StuckClock, up_z
from marsscene.env.terminate import compute_terminated, compute_truncated
from marsscene.env.terms import GOAL, GOAL_TERMS, TERMINATIONS, reward_terms
from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig

__all__ = ["RESET_OPTIONS", "NavEpisode"]

#: The keys ``reset(options=...)`` takes.
RESET_OPTIONS = ("world", "start", "yaw", "goal")


class NavEpisode:
    """The task of :class:`~marsscene.env.nav.RoverNavEnv`, one episode at a time.

    Parameters
    ----------
    task : NavTask
        Goal distances and tolerance, time limit, start placement, termination thresholds.
    observations : ObsConfig
    reward : RewardConfig
    rover : RoverConfig
        Its geometry turns wheel rates into the body speed of the observation.
    control_hz : float
        Steps per second: the episode lasts ``task.episode_steps(control_hz)`` steps.
    """

    def __init__(self, task: NavTask, observations: ObsConfig, reward: RewardConfig,
                 rover: RoverConfig, *, control_hz: float) -> None:
        self.task, self.obs_config, self.reward_config = task, observations, reward
        self.rover, self.lidar_shape = rover, observations.lidar_shape
        self.steps_total = task.episode_steps(control_hz)
        self.control_hz = float(control_hz)
        self.rng: np.random.Generator | None = None
        self.world: LoadedWorld | None = None
        self.start_xy_m = self.goal_xy_m = np.zeros(2)
        self.steps_done, self.last_action = 0, np.zeros(2)
        self.last_distance_m = 0.0  # the goal distance at the last step (the progress term)
        self.bounds_xy_m = np.zeros(4)
        self.stuck_clock: StuckClock | None = None

    # ---- the start -----------------------------------------------------------------------
    def seed(self, seed: int | None) -> None:
        """Restart the stream from ``seed`` (None: go on; at the first reset: fresh entropy)."""
        if seed is not None or self.rng is None:
            self.rng = np.random.default_rng(seed)

    def draw_world(self, n_worlds: int, options: dict[str, Any]) -> int:
        """Check ``options`` and draw the episode's world index (or take
        ``options["world"]``)."""
        assert self.rng is not None, "seed() before draw_world()"
        unknown = sorted(set(options) - set(RESET_OPTIONS))
        if unknown:
            raise ConfigError(f"reset options {unknown} are unknown; use "
                              f"{', '.join(RESET_OPTIONS)}")
        index = int(options.get("world", self.rng.integers(n_worlds)))
        if not 0 <= index < n_worlds:
            raise ConfigError(f"world = {index}; there are {n_worlds} worlds")
        return index

    def begin(self, world: LoadedWorld, options: dict[str, Any]) -> np.random.Generator:
        """Place the rover on ``world`` and start the episode; the stream of the episode's
        physics and sensor noise is returned (the last draw of the reset)."""
        assert self.rng is not None, "draw_world() before begin()"
        start, _, goal = self._place(world, options)
        self.world, self.start_xy_m, self.goal_xy_m = world, start, goal
        self.steps_done, self.last_action = 0, np.zeros(2)
        self.last_distance_m = float(np.hypot(*(goal - start)))
        self.restart_judge(world.sim.heightfield.bounds_xy_m)
        return np.random.default_rng(self.rng.integers(2**63))

    def _place(self, world: LoadedWorld, opts: dict[str, Any], tries: int = 20
               ) -> tuple[NDArray[np.float64], float, NDArray[np.float64]]:
        """Draw (or take from ``opts``) start, heading and goal, and settle the rover there;
        a start where the settled rover leans over ``task.start_max_tilt_deg`` or touches a
        rock is drawn again."""
        assert self.rng is not None
        task, given = self.task, "start" in opts or "goal" in opts
        level = math.cos(math.radians(task.start_max_tilt_deg))
        for _ in range(1 if given else tries):
            start, yaw, goal = world.task_map.draw(self.rng)
            if given:
                start = np.asarray(opts.get("start", start), dtype=np.float64).reshape(2)
                goal = np.asarray(opts.get("goal", goal), dtype=np.float64).reshape(2)
                world.task_map.check(start, goal)
            yaw = float(opts.get("yaw", yaw))
            world.sim.settle_s = task.start_settle_s
            world.sim.reset(xy_m=(float(start[0]), float(start[1])), yaw_rad=yaw)
            if float(up_z(world.sim.pose()[1])) > level and not world.collided():
                return start, yaw, goal
        where = "the given start" if given else f"{tries} drawn starts"
        raise ConfigError(f"the rover does not stand level and clear of rocks at {where}")

    def restart_judge(self, bounds_xy_m: Any) -> None:
        """Start judging an episode on a terrain of ``bounds_xy_m`` (``x0, y0, x1, y1``): the
        stuck clock restarts."""
        self.bounds_xy_m = np.asarray(bounds_xy_m, dtype=np.float64)
        self.stuck_clock = StuckClock(np.zeros(1), (), self.task.stuck_steps(self.control_hz),
                                      self.task.stuck_m)

    # ---- each step -----------------------------------------------------------------------
    def state(self, obs: Any) -> RoverState:
        """The rover's :class:`~marsscene.env.state.RoverState` (one rover: batch shape
        ``()``) at ``obs``."""
        return RoverState.of_observation(obs, self.rover, self.obs_config.pose_source)

    def step(self, obs: Any, action: NDArray[np.float64], v_m_s: float, omega_rad_s: float
             ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """Judge the step that ``action`` (normalised; ``v_m_s``, ``omega_rad_s`` as applied)
        led to (:func:`~marsscene.env.judgement.judge_step` of one rover): observation, reward,
        terminated, truncated, info."""
        assert self.world is not None and self.stuck_clock is not None, "begin() first"
        self.steps_done += 1
        state = self.state(obs)
        j = judgement.judge_step(
            state, start_xy_m=self.start_xy_m, goal_xy_m=self.goal_xy_m,
            bounds_xy_m=self.bounds_xy_m, steps_left=np.asarray(self.steps_total - self.steps_done),
            action=np.asarray(action, dtype=np.float64),
            last_action=np.asarray(self.last_action, dtype=np.float64),
            last_distance_m=np.asarray(self.last_distance_m),
            collided=np.asarray(self.world.collided()),
            moving=np.asarray(self.task.moving(v_m_s, omega_rad_s)),
            stuck_clock=self.stuck_clock, task=self.task, reward=self.reward_config,
            steps_total=self.steps_total)
        self.last_distance_m = float(j.distance_m)
        terms = {k: float(v) for k, v in j.terms.items()}
        info = self.info(obs, terms, TERMINATIONS[int(j.code)])
        self.last_action = action
        obs_dict = self.observe(obs, state)
        return obs_dict, float(j.reward), bool(j.terminated), bool(j.truncated), info

    def _goals(self, obs: Any) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """``achieved_goal`` and ``desired_goal``: the rover's and the goal's x, y."""
        return obs.gt_xyz_m[:2].astype(np.float32), self.goal_xy_m.astype(np.float32)

    def info(self, obs: Any, terms: dict[str, float], reason: str, **extra: Any
             ) -> dict[str, Any]:
        """The step's info: goals, distance, heading, steps left, every reward term (``terms``:
        the step's, each a float, in table order; ``{}``: the goal terms only, at a reset), why
        the episode ended (``termination``; ``""``: it goes on) and ``extra``."""
        ag, dg = self._goals(obs)
        left = self.steps_total - self.steps_done
        if not terms:
            q = judgement.goal_quantities(
                np.asarray(obs.gt_xyz_m[:2], dtype=np.float64),
                np.asarray(obs.gt_yaw_rad, dtype=np.float64), self.goal_xy_m,
                np.asarray(left), tolerance_m=self.task.goal_tolerance_m,
                steps_total=self.steps_total)
            terms = {k: float(v)
                     for k, v in reward_terms(q, self.reward_config, goal=True).items()}
        goal_free = [v for k, v in terms.items() if k not in GOAL_TERMS]
        return {"achieved_goal": ag, "desired_goal": dg,
                "distance_m": float(np.hypot(*(ag - self.goal_xy_m))),
                "yaw_rad": float(obs.gt_yaw_rad), "steps_left": left,
                "reward_other": float(sum(goal_free)),
                "reward_terms": terms,
                "is_success": reason == TERMINATIONS[GOAL], "termination": reason,
                "t_s": obs.t_s, **extra}

    def observe(self, obs: Any, state: RoverState | None = None) -> dict[str, np.ndarray]:
        """The observation dict: the vector (of ``state``, the rover's at ``obs`` by default),
        the goals, the height scan, and the camera frame and LiDAR scan the session took at
        ``obs``."""
        world = self.world
        assert world is not None
        state = state if state is not None else self.state(obs)
        out: dict[str, np.ndarray] = state.observations(
            self.goal_xy_m, np.asarray(self.last_action, dtype=np.float64))
        if world.scanner is not None:
            out["height_scan"] = world.scanner(obs.gt_xyz_m, obs.gt_yaw_rad)
        if self.obs_config.camera is not None:
            if self.obs_config.rgb:
                out["rgb"] = obs.camera.rgb
            if self.obs_config.depth and obs.camera.depth_m is not None:
                out["depth"] = np.nan_to_num(obs.camera.depth_m, nan=0.0,
                                             posinf=0.0).astype(np.float32)
        if self.lidar_shape is not None:
            out["lidar_range"], out["lidar_mask"] = lidar_image(obs.lidar, self.lidar_shape)
        return out

    # ---- goal relabelling ------------------------------------------------------------------
    def compute_reward(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised reward of goal pairs (:func:`~marsscene.env.reward.compute_reward`)."""
        return compute_reward(achieved_goal, desired_goal, info, cfg=self.reward_config,
                              tolerance_m=self.task.goal_tolerance_m,
                              steps_total=self.steps_total)

    def compute_terminated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised ``terminated`` of goal pairs (:func:`.terminate.compute_terminated`)."""
        return compute_terminated(achieved_goal, desired_goal, info,
                                  tolerance_m=self.task.goal_tolerance_m)

    def compute_truncated(self, achieved_goal: Any, desired_goal: Any, info: Any) -> Any:
        """Vectorised ``truncated`` of goal pairs (:func:`.terminate.compute_truncated`)."""
        return compute_truncated(achieved_goal, desired_goal, info,
                                 tolerance_m=self.task.goal_tolerance_m)
