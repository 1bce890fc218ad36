"""``BatchNavEnv``: thousands of rovers navigating to goals, stepped together by MuJoCo Warp.

The task is :class:`~marsscene.env.nav.RoverNavEnv`'s, computed by the same functions
(:mod:`marsscene.env.taskmath`) on (N,) batches that stay on the device: the observation
(``observation`` vector and height scan), the reward terms, the failures and the time limit.
Each rover is on one of W worlds (:class:`~.worlds.WorldBatch`; a tile of the shared
heightfield, :mod:`.model`) and is reset on its own when its episode ends, to an episode drawn
from the batch's pool: a start, heading and goal drawn as the CPU environment draws them, the
rover settled there once for ``task.start_settle_s`` when the environment is made (a start where
it leans over ``task.start_max_tilt_deg`` is replaced by another of its world).

Differences from the CPU environment, by design: the sensors are noise-free (the IMU and wheel
encoders MuJoCo Warp computes; ``ObsConfig.noise_profile`` must be ``"none"``), the pose is the
ground truth (``pose_source="truth"``), rocks are relief of the terrain (a wheel "collides" with
a rock where it touches ground raised by one; the LiDAR sees that relief, the camera the rocks'
meshes), and images come channels first (:mod:`.sensing`). The height scan is privileged ground
truth (the terrain's heights read from the world, no sensor's): a policy meant for a real rover
observes ``depth`` or ``lidar_range`` instead (``ObsConfig(height_scan=None, ...)``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from array_api_compat import device

from marsscene._optional import quiet_warp
from marsscene.env import judgement, taskmath
from marsscene.env.batch.backend import Backend
from marsscene.env.batch.judge import RockContacts, collided
from marsscene.env.batch.model import WarpPhysics, tiled_model, warp_model
from marsscene.env.batch.pool import settle_pool
from marsscene.env.batch.sensing import BatchSensors, check_sensors, observation_spaces
from marsscene.env.batch.worlds import WorldBatch
from marsscene.env.observe import ObsConfig
from marsscene.env.reward import RewardConfig
from marsscene.env.state import RoverState
from marsscene.env.task import NavTask
from marsscene.env.terms import GOAL
from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import wheel_commands

__all__ = ["BatchNavEnv"]

#: Ground raised this much by a rock (m) counts as the rock (the ``collision`` term).
ROCK_CONTACT_M = 0.02
#: The batch's rover unless one is given: sphere wheels. MuJoCo Warp collides a sphere with
#: the heightfield's prisms 2.5 times as fast as a cylinder, and ends nearer MuJoCo C's
#: cylinder wheels at the 90th percentile (:doc:`/results/gym`).
BATCH_ROVER = RoverConfig(wheel_collision="sphere")


class BatchNavEnv:
    """N rovers on W worlds, one MuJoCo Warp batch; arrays in, arrays out.

    Parameters
    ----------
    worlds : WorldBatch, path, WorldSampler, folder or list of folders
        A batch (or its ``.npz``), or worlds to build one from (``pool`` episodes each).
    num_envs : int
        Rovers N.
    task, observations, reward, control_hz, physics_hz
        As :class:`~marsscene.env.nav.RoverNavEnv`'s (observations: the height scan, the
        camera's depth, a LiDAR; :mod:`.sensing`).
    rover : RoverConfig, optional
        Default: :data:`BATCH_ROVER` (sphere wheels; the CPU environment's have cylinders).
    device : str, optional
        Warp device (default: ``cuda:0`` where there is a GPU, else ``cpu``).
    library : {"torch", "numpy"}, optional
        Arrays returned (default: PyTorch where installed).
    seed : int
        Seed of the episode draws and the LiDAR's noise.
    physics : WarpPhysics, optional
        Heightfield posts, solver limits, buffers and determinism of MuJoCo Warp.
    final_sensors : bool
        Whether ``info["final_observation"]`` holds the camera's and LiDAR's keys too (cast
        twice a step: before the resets and after). False casts once a step (rsl-rl's PPO
        never reads the final observation: it bootstraps time-outs from its values).
    """

    def __init__(self, worlds: Any, *, num_envs: int = 1024, task: NavTask | None = None,
                 observations: ObsConfig | None = None, reward: RewardConfig | None = None,
                 rover: RoverConfig | None = None, control_hz: float = 5.0,
                 physics_hz: float = 100.0, device: str | None = None,
                 library: str | None = None, seed: int = 0, pool: int = 256,
                 physics: WarpPhysics | None = None, final_sensors: bool = True) -> None:
        import mujoco_warp as mjw
        import warp as wp

        self.task = task if task is not None else NavTask()
        self.obs_config = (observations if observations is not None
                           else ObsConfig(noise_profile="none"))
        self.reward_config = reward if reward is not None else RewardConfig()
        self.rover = rover if rover is not None else BATCH_ROVER
        _check(self.obs_config, num_envs, control_hz, physics_hz)
        self.num_envs, self.control_hz = int(num_envs), float(control_hz)
        self.final_sensors = bool(final_sensors)
        self.substeps = round(physics_hz / control_hz)
        self.steps_total = self.task.episode_steps(control_hz)
        self.batch = _batch(worlds, self.task, pool, seed)
        terrains = self.batch.rock_terrains()
        bare = [self.batch.heightfield(w) for w in range(self.batch.count)]
        self.physics = ph = physics if physics is not None else WarpPhysics()
        tiled = tiled_model(terrains, bare, rover=self.rover, physics_hz=physics_hz,
                            post_m=ph.post_m if ph.post_m is not None else self.batch.cell_m,
                            physics=ph)
        self.mj_model = tiled.model
        self.ids: dict[str, Any] = {  # index lists: numpy and PyTorch take them
            k: [int(i) for i in v] if isinstance(v, np.ndarray) else v
            for k, v in tiled.ids.items()}
        quiet_warp(wp).init()
        self.bk = bk = Backend(device or ("cuda:0" if wp.is_cuda_available() else "cpu"),
                               library, seed)
        self.device, self.xp = bk.device, bk.xp
        data = mujoco.MjData(self.mj_model)  # (not forwarded: the rover at qpos0 is in the ground)
        with wp.ScopedDevice(self.device):
            self.mjw_model = warp_model(self.mj_model, ph)
            self.mjw_data = mjw.put_data(self.mj_model, data, nworld=self.num_envs,
                                         nconmax=ph.nconmax, njmax=ph.njmax)
        self._mjw, self._graph = mjw, None
        self._v = {k: bk.view(getattr(self.mjw_data, k)) for k in
                   ("qpos", "qvel", "ctrl", "sensordata", "nacon")}
        con = self.mjw_data.contact
        self._con = {k: bk.view(getattr(con, k)) for k in ("geom", "worldid", "pos")}
        self._reset_mask = wp.zeros(self.num_envs, dtype=bool, device=self.device)
        self._task_arrays(terrains, tiled.offsets_xy_m)
        obs = self.obs_config
        self.sensors = (BatchSensors(self.mj_model, self.mjw_model, mjw, self.num_envs, obs,
                                     self.control_hz, seed, bk, batch=self.batch,
                                     offsets_xy_m=tiled.offsets_xy_m)
                        if obs.camera is not None or obs.lidar is not None else None)
        with bk.on_stream():
            self._pool, self.pool_level_fraction = settle_pool(
                self.batch, terrains, model=self.mj_model, warp_model=self.mjw_model, data=data,
                offsets_xy_m=self._offsets, qpos_root=int(self.ids["qpos_root"]),
                rover=self.rover, task=self.task, backend=bk, nconmax=ph.nconmax,
                njmax=ph.njmax)
            self._capture()
            self.reset()

    # ---- set-up ----------------------------------------------------------------------------
    def _task_arrays(self, terrains: list[Any], offsets: np.ndarray) -> None:
        bk, xp, n = self.bk, self.xp, self.num_envs
        scan = self.obs_config.height_scan
        fwd, left = taskmath.scan_grid_m(scan) if scan is not None else (np.zeros((0, 0)),) * 2
        self._fwd, self._left = bk.asarray(fwd), bk.asarray(left)
        grids = np.stack([t.z_m for t in terrains])
        self._grids = bk.asarray(grids)
        origins = bk.asarray(np.array([t.origin_xy_m for t in terrains], float))
        self._grid_origins, self._cell_m = origins, float(terrains[0].cell_size_m)
        bare = [self.batch.heightfield(w).sample(*np.meshgrid(
            t.origin_xy_m[0] + np.arange(t.z_m.shape[1]) * t.cell_size_m,
            t.origin_xy_m[1] + np.arange(t.z_m.shape[0]) * t.cell_size_m))
            for w, t in enumerate(terrains)]
        self._offsets = bk.asarray(offsets)
        self._rocks = RockContacts(
            chassis_geom=self.ids["chassis_geom"],
            wheel_geoms=[int(g) for g in self.ids["wheel_geoms"]],
            rock_cells=bk.asarray((grids - np.stack(bare)) > ROCK_CONTACT_M, xp.float32),
            grid_origins_xy_m=origins, cell_m=self._cell_m, offsets_xy_m=self._offsets)
        self._bounds = bk.asarray(self.batch.bounds_xy_m)
        self.world = xp.zeros(n, dtype=xp.int64, device=device(self._offsets))
        zeros2 = xp.zeros((n, 2), dtype=xp.float64, device=device(self._offsets))
        self.start_xy_m, self.goal_xy_m, self.last_action = zeros2, zeros2 * 1, zeros2 * 1
        self.steps_done = xp.zeros(n, dtype=xp.int64, device=device(self._offsets))
        self.last_distance_m = xp.zeros(n, dtype=xp.float64, device=device(self._offsets))
        self._stuck = taskmath.StuckClock(self._offsets, (n,),
                                          self.task.stuck_steps(self.control_hz),
                                          self.task.stuck_m)
        self.episodes = xp.zeros(2, dtype=xp.int64, device=device(self._offsets))  # ended, won

    # ---- episodes --------------------------------------------------------------------------
    def seed(self, seed: int) -> None:
        """Restart the episode draws and the LiDAR's noise from ``seed``."""
        self.bk.seed(seed)
        if self.sensors is not None:
            self.sensors.restart(seed)

    def spaces(self) -> dict[str, Any]:
        """The ``gymnasium.spaces`` of one rover's observation keys (:mod:`.sensing`)."""
        return observation_spaces(self.obs_config)

    def reset(self) -> dict[str, Any]:
        """Start a new episode on every rover; the observations."""
        with self.bk.on_stream():
            self._restart(self.xp.ones(self.num_envs, dtype=self.xp.bool,
                                       device=device(self._offsets)))
            return self.observe()

    def _restart(self, done: Any) -> None:
        """Put the rovers in ``done`` (N,) bool at a start drawn from the pool."""
        xp, bk, pool = self.xp, self.bk, self._pool
        bk.view(self._reset_mask)[...] = done
        self._mjw.reset_data(self.mjw_model, self.mjw_data, reset=self._reset_mask)
        pick = bk.randint(pool["qpos"].shape[0], self.num_envs)
        col = done[:, None]
        for key in ("qpos", "qvel", "sensordata"):
            self._v[key][...] = xp.where(col, pool[key][pick], self._v[key])
        self._v["ctrl"][...] = xp.where(col, self._v["ctrl"] * 0, self._v["ctrl"])
        self.world = xp.where(done, pool["world"][pick], self.world)
        self.start_xy_m = xp.where(col, pool["start"][pick], self.start_xy_m)
        self.goal_xy_m = xp.where(col, pool["goal"][pick], self.goal_xy_m)
        self.last_action = xp.where(col, self.last_action * 0, self.last_action)
        self.steps_done = xp.where(done, self.steps_done * 0, self.steps_done)
        gap = self.goal_xy_m - self.start_xy_m
        self.last_distance_m = xp.where(done, xp.hypot(gap[:, 0], gap[:, 1]),
                                        self.last_distance_m)
        self._stuck.restart(done)

    # ---- stepping --------------------------------------------------------------------------
    def _capture(self) -> None:
        """On a GPU, record one control period of physics as a CUDA graph (before the first
        reset: the warm-up step that compiles the kernels is then forgotten)."""
        wp, mjw = self.bk.wp, self._mjw
        if self.device.startswith("cuda"):
            with wp.ScopedDevice(self.device):
                mjw.step(self.mjw_model, self.mjw_data)
                with wp.ScopedCapture() as cap:
                    for _ in range(self.substeps):
                        mjw.step(self.mjw_model, self.mjw_data)
                self._graph = cap.graph

    def _physics(self) -> None:
        wp, mjw = self.bk.wp, self._mjw
        with wp.ScopedDevice(self.device):
            if self._graph is not None:
                wp.capture_launch(self._graph)
            else:
                for _ in range(self.substeps):
                    mjw.step(self.mjw_model, self.mjw_data)

    def step(self, action: Any) -> tuple[dict[str, Any], Any, Any, Any, dict[str, Any]]:
        """Apply ``action`` (N, 2) normalised ``[v, omega]`` for one control period; the
        observations (of the next episode where one ended), reward, terminated, truncated and
        info (``termination``: the code of :data:`~marsscene.env.terms.TERMINATIONS`, 0 none,
        1 goal, 2 + the index in :data:`~marsscene.env.terms.FAILURES`;
        ``final_observation`` of the rovers reset)."""
        xp = self.xp
        with self.bk.on_stream():
            a = xp.clip(xp.astype(xp.asarray(action), xp.float64), -1.0, 1.0)
            v, w = self.task.command(a)
            rates, steer = wheel_commands(v, w, self.rover)
            ctrl = self._v["ctrl"]
            ctrl[:, self.ids["drive_act"]] = xp.astype(rates, ctrl.dtype)
            ctrl[:, self.ids["steer_act"]] = xp.astype(steer, ctrl.dtype)
            self._physics()
            self.steps_done = self.steps_done + 1
            state = self.state()
            j = self._judge(state, a, self.task.moving(v, w))
            self.last_distance_m = j.distance_m
            final = self.observe(state, sensors=self.final_sensors)
            self.last_action = a
            done = j.terminated | j.truncated
            self.episodes = self.episodes + xp.stack([xp.sum(xp.astype(done, xp.int64)),
                                                      xp.sum(xp.astype(j.code == GOAL,
                                                                       xp.int64))])
            self._restart(done)
            obs = self.observe()
        return obs, j.reward, j.terminated, j.truncated, {"termination": j.code,
                                                          "final_observation": final}

    def state(self) -> RoverState:
        """The rovers now, as the task reads them (each world's frame; noise-free sensors,
        the true pose)."""
        v = self._v
        return RoverState.of_buffers(v["qpos"], v["qvel"], v["sensordata"], self.ids,
                                     self._offsets[self.world], self.rover)

    def observe(self, state: RoverState | None = None, *, sensors: bool = True
                ) -> dict[str, Any]:
        """The observations of the rovers in ``state`` (now, by default; the CPU environment's
        keys, images channels first). ``state`` must be the rovers' current state: the camera
        and LiDAR see ``mjw_data``'s (``sensors=False``: not cast)."""
        st = state if state is not None else self.state()
        out = st.observations(self.goal_xy_m, self.last_action)
        if self.obs_config.height_scan is not None:
            out["height_scan"] = taskmath.height_scan(
                self._grids, self._grid_origins, self._cell_m, st.xyz_m, st.yaw_rad,
                self._fwd, self._left, self.world)
        if self.sensors is not None and sensors:
            off = self._offsets[self.world]  # a reset rover may be on another world now
            bounds = self._bounds[self.world] + self.xp.concat([off, off], axis=1)
            out.update(self.sensors.observe(self.mjw_data, bounds, self.world))
        return out

    def _judge(self, state: RoverState, a: Any, moving: Any) -> judgement.Judgement:
        """The step's judgement (:func:`marsscene.env.judgement.judge_step`, the CPU
        environment's)."""
        hit = collided(self._con, self._v["nacon"], self.world, self._rocks, self.bk)
        return judgement.judge_step(
            state, start_xy_m=self.start_xy_m, goal_xy_m=self.goal_xy_m,
            bounds_xy_m=self._bounds[self.world], steps_left=self.steps_total - self.steps_done,
            action=a, last_action=self.last_action, last_distance_m=self.last_distance_m,
            collided=hit, moving=moving, stuck_clock=self._stuck, task=self.task,
            reward=self.reward_config, steps_total=self.steps_total)

    @property
    def success_rate(self) -> float:
        """Goals reached over episodes ended so far (host read)."""
        ended, won = (int(v) for v in self.bk.to_numpy(self.episodes))
        return won / ended if ended else float("nan")


def _check(obs: ObsConfig, num_envs: int, control_hz: float, physics_hz: float) -> None:
    check_sensors(obs)
    if obs.noise_profile != "none" or obs.pose_source != "truth":
        raise ConfigError("the batched environment's sensors are noise-free and its pose the "
                          "truth: use ObsConfig(noise_profile='none', pose_source='truth')")
    if not 1 <= int(num_envs) <= 1_000_000:
        raise ConfigError(f"num_envs = {num_envs}; give 1 to 1000000 rovers")
    ratio = physics_hz / control_hz
    if control_hz <= 0 or abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ConfigError(f"physics_hz = {physics_hz:g} is not a whole multiple of "
                          f"control_hz = {control_hz:g}")


def _batch(worlds: Any, task: NavTask, pool: int, seed: int) -> WorldBatch:
    if isinstance(worlds, WorldBatch):
        return worlds
    if isinstance(worlds, str | Path) and str(worlds).endswith(".npz"):
        return WorldBatch.load(worlds)
    return WorldBatch.build(worlds, task=task, pool=pool, seed=seed)
