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
        Seed of the LiDAR's noise (each drive's slot its own stream).
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
            self.pursuit = DevicePursuit([p.route for p in prepared], pursuit, device=dev)
            self._offsets = wp.array(self.offsets, dtype=wp.float64)
            x0y0 = np.array([p.heightfield.bounds_xy_m for p in prepared])
            bounds = x0y0 + np.hstack([self.offsets, self.offsets])
            self.bounds = wp.array(bounds.astype(np.float32), dtype=float)
            self.camera, self.lidar = self._sensors(m, seed)
        self._place(m, prepared, rover, settle_s)
        self.limits = np.array([round(p.limit_s / self.dt_s) for p in prepared])
        self.periods = {"control": _period(run.control_hz, self.dt_s),
                        "imu": _period(run.imu_hz, self.dt_s)}
        if self.lidar is not None:
            self.periods["lidar"] = _period(run.lidar.spec.rate_hz, self.dt_s)
        if self.camera is not None:
            self.periods["camera"] = _period(run.camera.rate_hz, self.dt_s)
        self.tick = math.gcd(*self.periods.values())
        self._v = {k: backend.view(getattr(self.data, k)) for k in ("ctrl",)}
        self._graph: Any = None
        self.rover = rover

    def _sensors(self, m: Any, seed: int) -> tuple[Any, Any]:
        from marsscene.sensors.batch import BatchDepthCamera, BatchLidar

        cam = (BatchDepthCamera(m, self.model, self.n, self.run.camera)
               if self.run.camera is not None else None)
        lidar = (BatchLidar(m, self.model, self.n, self.run.lidar, seed=seed,
                            render_context=cam.rc if cam is not None else None)
                 if self.run.lidar is not None else None)
        return cam, lidar

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
        self.qpos0 = self.data.qpos.numpy()

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
        return (s.range_m.numpy(), s.xyz_m.numpy(), s.intensity.numpy(), s.valid.numpy())

    def _depth(self) -> np.ndarray:
        assert self.camera is not None
        self.mjw.kinematics(self.model, self.data)
        self.mjw.com_pos(self.model, self.data)
        self.mjw.camlight(self.model, self.data)
        return np.array(self.camera.depth(self.data, bounds_xy_m=self.bounds).numpy())

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
                put(Tick(k=k, t_s=t, flush=flush, control=active if control else None,
                         sense=sense, imu=imu, cmd=cmd, qpos=qpos, qvel=qvel, sensordata=sd,
                         lidar=self._scan() if due["lidar"] else None,
                         depth=self._depth() if due["camera"] else None))
                finished |= stop
                self._physics()
                k += self.tick
                finished |= k > self.limits
                self._halt(finished)

    def _halt(self, finished: np.ndarray) -> None:
        """Finished drives' followers stop (their rovers stand braked)."""
        done = self.pursuit.done.numpy()
        if (finished & (done == 0)).any():
            new = np.where(finished, 1, done).astype(np.int32)
            self.bk.wp.copy(self.pursuit.done, self.bk.wp.array(new, dtype=int))
