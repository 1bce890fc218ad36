"""The batch's clock: N drives stepped together by MuJoCo Warp, pure pursuit on the device, the
sensors at their rates, every sample handed to the host sinks (:mod:`.sink`).

The schedule is the CPU session's (:mod:`marsscene.sim.session`): the physics advances in
ticks of the greatest common divisor of the control, IMU, LiDAR and camera periods; at a
control tick each drive's follower commands the rover (:class:`~.pursuit.DevicePursuit`) and the
control row is logged, then the IMU, LiDAR and camera sample. A drive ends as a CPU drive does:
at the control tick its follower stops (that row logged, no sensor after it), or past its time
limit; it then stands braked while the others drive on.
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from marsscene.errors import RuntimeSimError
from marsscene.rover.geometry import wheel_commands
from marsscene.rover.spawn import spawn_pose
from marsscene.sim.batch.pursuit import DevicePursuit
from marsscene.sim.batch.sink import Tick

__all__ = ["BatchLoop"]


def _period(rate_hz: float, dt_s: float) -> int:
    steps = 1.0 / (rate_hz * dt_s)
    if steps < 1.0 - 1e-9 or abs(steps - round(steps)) > 1e-6:
        raise RuntimeSimError(f"a rate of {rate_hz:g} Hz does not divide the "
                              f"{1.0 / dt_s:g} Hz physics rate")
    return round(steps)


class BatchLoop:
    """The drives of ``prepared`` on the tiled model ``tiled`` (:func:`.setup.batch_model`).

    Parameters
    ----------
    tiled : TiledModel
    prepared : list of PreparedDrive
    run : RunConfig
        Rates and sensors (one for the batch).
    backend : Backend
        The Warp device and its array library (:class:`marsscene.env.batch.backend.Backend`).
    physics : WarpPhysics
    pursuit : PursuitConfig
    settle_s : float
        The rovers settle braked this long at their starts.
    seed : int
        Seed of the LiDAR's noise (each drive's stream under it keyed by the drive's seed).
    """

    def __init__(self, tiled: Any, prepared: list[Any], *, run: Any, backend: Any,
                 physics: Any, pursuit: Any, settle_s: float, seed: int, rover: Any) -> None:
        import mujoco_warp as mjw

        from marsscene.env.batch.model import warp_model

        self.mjw, self.bk, self.run, self.n = mjw, backend, run, len(prepared)
        m = tiled.model
        self.dt_s = float(m.opt.timestep)
        self.ids, self.offsets = tiled.ids, tiled.offsets_xy_m
        self.root = int(self.ids["qpos_root"])
        wp, dev = backend.wp, backend.device
        with wp.ScopedDevice(dev):
            self.model = warp_model(m, physics)
            self.data = mjw.put_data(m, mujoco.MjData(m), nworld=self.n,
                                     nconmax=physics.nconmax, njmax=physics.njmax)
            self.pursuit = DevicePursuit([p.route for p in prepared], pursuit, device=dev,
                                         lookaheads_m=[p.drive.lookahead_m for p in prepared])
            self._offsets = wp.array(self.offsets, dtype=wp.float64)
            x0y0 = np.array([p.heightfield.bounds_xy_m for p in prepared])
            bounds = x0y0 + np.hstack([self.offsets, self.offsets])
            self.bounds = wp.array(bounds.astype(np.float32), dtype=float)
            self.camera, self.lidar = self._sensors(m, prepared, seed)
        self._place(m, prepared, rover, settle_s)
        self.limits = np.array([round(p.limit_s / self.dt_s) for p in prepared])
        self.periods = {"control": _period(run.control_hz, self.dt_s),
                        "imu": _period(run.imu_hz, self.dt_s)}
        if self.lidar is not None:
            self.periods["lidar"] = _period(run.lidar.spec.rate_hz, self.dt_s)
        self.trigger_m = run.camera.trigger_distance_m if run.camera is not None else None
        if self.camera is not None and self.trigger_m is None:
            self.periods["camera"] = _period(run.camera.rate_hz, self.dt_s)
        self._travel_m, self._next_frame_m = np.zeros(self.n), np.zeros(self.n)
        self._last_xy: np.ndarray | None = None
        self.tick = math.gcd(*self.periods.values())
        self._v = {k: backend.view(getattr(self.data, k)) for k in ("ctrl",)}
        self._graph: Any = None
        self.rover = rover

    def _sensors(self, m: Any, prepared: list[Any], seed: int) -> tuple[Any, Any]:
        from marsscene.sensors.batch import BatchLidar

        lidar = (BatchLidar(m, self.model, self.n, self.run.lidar, seed=seed,
                            streams=[int(p.drive.seed) for p in prepared])
                 if self.run.lidar is not None else None)
        return (self._camera(m, prepared, seed) if self.run.camera is not None else None), lidar

    def _camera(self, m: Any, prepared: list[Any], seed: int) -> Any:
        """The RGB-D camera of every drive, each on its scene's world with its lighting."""
        from marsscene.sensors.batch import BatchCamera
        from marsscene.sensors.batch.camera import NAVCAM
        from marsscene.sensors.batch.lidar import world_seeds
        from marsscene.sensors.batch.rgbd import scene_lights
        from marsscene.sim.batch.setup import camera_worlds

        cfg, wp = self.run.camera, self.bk.wp
        self.views = views = camera_worlds(prepared, self.offsets,
                                           reach_m=0.5 * cfg.terrain_window_m)
        lights: dict[tuple[Any, ...], Any] = {}
        per = []
        fixed = []
        for p in prepared:
            c = p.drive.lighting_of(cfg)
            key = (str(p.drive.scene), c.tau, c.sun_elevation_deg, c.sun_azimuth_deg,
                   c.irradiance_scale)
            if key not in lights:
                lights[key] = scene_lights(c, p.drive.scene)
            per.append(lights[key])
            fixed.append(c.exposure == "fixed")
        self.camera_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, NAVCAM)
        self._world = wp.array(views.world, dtype=int)
        self._shift = wp.array(views.shift_xy_m, dtype=wp.vec2)
        self._cam_xpos = wp.zeros(self.data.cam_xpos.shape, dtype=wp.vec3)
        return BatchCamera(views.batch, self.n, config=cfg, lighting=per,
                           offsets_xy_m=views.offsets_xy_m, seeds=views.seeds,
                           texture_seed=views.seeds[0], catalogue=views.catalogue,
                           assets=views.assets, fixed_exposure=fixed,
                           noise_seeds=world_seeds(seed, self.n, [int(p.drive.seed)
                                                                  for p in prepared], sensor=1))

    def _place(self, m: Any, prepared: list[Any], rover: Any, settle_s: float) -> None:
        """Each rover on its tile at its start, settled braked for ``settle_s``."""
        qpos = np.tile(m.qpos0, (self.n, 1))
        for i, p in enumerate(prepared):
            pose = spawn_pose(p.terrain, p.start_xy_m, p.start_yaw_rad, rover)
            pose[:2] += self.offsets[i]
            qpos[i, self.root: self.root + 7] = pose
        wp = self.bk.wp
        with wp.ScopedDevice(self.bk.device):
            wp.copy(self.data.qpos, wp.array(qpos.astype(np.float32), dtype=float))
            for _ in range(round(settle_s / self.dt_s)):
                self.mjw.step(self.model, self.data)
            self.mjw.kinematics(self.model, self.data)
        self.qpos0 = self.data.qpos.numpy().copy()  # a view on the CPU device

    # ---- one tick ----------------------------------------------------------------------
    def _command(self) -> np.ndarray:
        """The followers' ``(v, omega)`` applied to the wheels; (N, 2) host copy."""
        xp = self.bk.xp
        v, w = self.pursuit.command_qpos(self.data.qpos, self.root, self._offsets)
        rates, steer = wheel_commands(self.bk.view(v), self.bk.view(w), self.rover)
        ctrl = self._v["ctrl"]
        ctrl[:, self.ids["drive_act"]] = xp.astype(rates, ctrl.dtype)
        ctrl[:, self.ids["steer_act"]] = xp.astype(steer, ctrl.dtype)
        return np.column_stack([v.numpy(), w.numpy()])

    def _scan(self) -> tuple[np.ndarray, ...]:
        assert self.lidar is not None
        mjw, lid = self.mjw, self.lidar
        mjw.kinematics(self.model, self.data)
        mjw.com_pos(self.model, self.data)
        twist = None
        if lid.spec.motion_distortion:
            mjw.com_vel(self.model, self.data)
            twist = lid.site_twist(self.data)
        s = lid.scan(self.data, twist=twist, bounds_xy_m=self.bounds)
        return tuple(self._host(a) for a in (s.range_m, s.xyz_m, s.intensity, s.valid))

    def _frame(self) -> tuple[np.ndarray, np.ndarray | None]:
        """Every camera's RGB (N, 3, H, W) uint8 and planar depth (N, H, W) m (0: sky; None
        for a camera config without depth, as a CPU drive writes none)."""
        from marsscene.sim.batch._kernels import shift_cameras

        assert self.camera is not None
        wp, d = self.bk.wp, self.data
        self.mjw.kinematics(self.model, d)
        self.mjw.com_pos(self.model, d)
        self.mjw.camlight(self.model, d)
        wp.launch(shift_cameras, dim=d.cam_xpos.shape, inputs=[d.cam_xpos, self._shift],
                  outputs=[self._cam_xpos])
        rgb = self.camera.render(self._cam_xpos, d.cam_xmat, self._world,
                                 camera=self.camera_id)
        assert self.run.camera is not None
        return self._host(rgb), self._host(self.camera.depth) if self.run.camera.depth else None

    def _host(self, a: Any) -> np.ndarray:
        """A host array of ``a`` that the next tick does not overwrite: on Warp's CPU device
        ``numpy()`` is a view of the sensor's buffer, which the writer threads would read after
        the next render had changed it."""
        h = a.numpy()
        return h if self.bk.device.startswith("cuda") else h.copy()

    def _physics(self) -> None:
        wp, mjw = self.bk.wp, self.mjw
        if self.bk.device.startswith("cuda"):
            if self._graph is None:
                with wp.ScopedCapture() as cap:
                    for _ in range(self.tick):
                        mjw.step(self.model, self.data)
                self._graph = cap.graph
            wp.capture_launch(self._graph)
            return
        for _ in range(self.tick):
            mjw.step(self.model, self.data)

    def drive(self, put: Any) -> int:
        """Drive every drive to its end, handing each tick to ``put``; the ticks stepped."""
        per, k, next_flush = self.periods, 0, 1.0
        finished = np.zeros(self.n, dtype=bool)
        wp = self.bk.wp
        with wp.ScopedDevice(self.bk.device):
            while True:
                active = ~finished & (k <= self.limits)
                if not active.any():
                    return k
                t = k * self.dt_s
                control = k % per["control"] == 0
                cmd = self._command() if control else None
                stop = active & (self.pursuit.done.numpy() != 0) if control else active & False
                sense = active & ~stop
                imu = k % per["imu"] == 0
                due = {s: s in per and k % per[s] == 0 and bool(sense.any())
                       for s in ("lidar", "camera")}
                flush = t >= next_flush
                next_flush += 1.0 if flush else 0.0
                if control or imu:
                    qpos, qvel = self.data.qpos.numpy().copy(), self.data.qvel.numpy().copy()
                    sd = self.data.sensordata.numpy().copy()
                else:
                    qpos = qvel = sd = None
                frame_due = None
                if self.camera is not None and self.trigger_m is not None and control:
                    frame_due = self._triggered(qpos, sense)
                    due["camera"] = bool(frame_due.any())
                put(Tick(k=k, t_s=t, flush=flush, control=active if control else None,
                         sense=sense, imu=imu, cmd=cmd, qpos=qpos, qvel=qvel, sensordata=sd,
                         lidar=self._scan() if due["lidar"] else None,
                         frame=self._frame() if due["camera"] else None, frame_due=frame_due))
                finished |= stop
                self._physics()
                k += self.tick
                finished |= k > self.limits
                self._halt(finished)

    def _triggered(self, qpos: Any, sense: np.ndarray) -> np.ndarray:
        """(N,) bool: the drives whose distance driven (their position at each control step,
        as the CPU session sums it) reached their next multiple of ``trigger_distance_m``."""
        assert self.trigger_m is not None
        xy = np.asarray(qpos[:, self.root: self.root + 2], dtype=np.float64)
        last = self._last_xy if self._last_xy is not None else xy
        self._travel_m += np.hypot(xy[:, 0] - last[:, 0], xy[:, 1] - last[:, 1])
        self._last_xy = xy
        due = sense & (self._travel_m >= self._next_frame_m)
        self._next_frame_m[due] = (np.floor(self._travel_m[due] / self.trigger_m) + 1.0
                                   ) * self.trigger_m
        return due

    def _halt(self, finished: np.ndarray) -> None:
        """Finished drives' followers stop (their rovers stand braked)."""
        done = self.pursuit.done.numpy()
        if (finished & (done == 0)).any():
            new = np.where(finished, 1, done).astype(np.int32)
            self.bk.wp.copy(self.pursuit.done, self.bk.wp.array(new, dtype=int))
