"""The host side of a batch of drives: each drive's sensor noise, wheel odometry and run folder,
fed from host copies of the batch's state by worker threads.

A drive's folder is the CPU drive's (:class:`~marsscene.sim.run_writer.RunWriter`, layout in
:mod:`marsscene.runs.logs`): the same noise streams drawn in the same order (the IMU's turn-on
biases, then per control step the wheel encoders and per IMU sample the IMU,
:mod:`marsscene.sim.session`), the same odometry, the same files. Worker ``j`` of ``K`` owns the
drives ``i % K == j`` and takes every tick in order from a bounded queue: the simulation waits
for the slowest worker rather than piling ticks up, so memory stays flat over a long drive.
"""

from __future__ import annotations

import queue
import threading
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.runs.logs import depth_mm
from marsscene.seeding import stage_rng
from marsscene.sensors.imu import ImuNoise
from marsscene.sensors.odometry import WheelOdometry, measure_wheels
from marsscene.sim.cross_track import cross_track_m
from marsscene.sim.driver import _goal_reached, _imu_bias, _read_back
from marsscene.sim.run_writer import RunWriter

__all__ = ["DriveSink", "SinkPool", "Tick"]


@dataclass(frozen=True, eq=False)
class Tick:
    """What the batch hands the sinks at one physics tick (host arrays, one row a drive).

    ``control``/``sense``: (N,) bool, the drives that log a control row / sample their sensors
    at this tick (None: none do). ``lidar``: ``range_m, xyz_m, intensity, valid`` of a scan.
    """

    k: int
    t_s: float
    flush: bool
    control: Any = None
    sense: Any = None
    imu: bool = False
    cmd: Any = None
    qpos: Any = None
    qvel: Any = None
    sensordata: Any = None
    lidar: Any = None
    depth: Any = None


class DriveSink:
    """Drive ``slot``'s noise, odometry and run folder."""

    def __init__(self, slot: int, *, sim: Any, out: Path, seed: int, ids: dict[str, Any],
                 offset_xy_m: Any, qpos0: Any, meta: dict[str, Any], lidar: Any, camera: bool,
                 route: Any) -> None:
        run = sim.run
        self.slot, self.sim, self.ids, self.route = slot, sim, ids, route
        self.offset = np.asarray(offset_xy_m, dtype=np.float64)
        self.rng = stage_rng(seed, "sensors")
        self.imu_noise = ImuNoise(run.noise, run.imu_hz, rng=self.rng)  # draws the turn-on biases
        pos0, yaw0 = self._pose_yaw(qpos0)
        self.odo = WheelOdometry(sim.rover, pos0[0], pos0[1], pos0[2], yaw0)
        self.lidar = lidar  # (ring, t_s) of the rays, or None
        self.writer = RunWriter(out, sim, lidar=lidar is not None, camera=camera, stereo=False,
                                meta=meta)
        self.dt_control_s = sim.dt_physics_s * round(1.0 / (run.control_hz * sim.dt_physics_s))
        self.n_control = self.n_lidar = self.n_cam = 0

    def _pose_yaw(self, qpos: Any) -> tuple[np.ndarray, float]:
        r = int(self.ids["qpos_root"])
        q = np.asarray(qpos[r: r + 7], dtype=np.float64)
        pos = q[:3] - np.array([*self.offset, 0.0])
        w, x, y, z = q[3:7]
        return pos, float(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))

    def take(self, tick: Tick) -> None:
        """Log what this drive samples at ``tick`` (the CPU session's order)."""
        i = self.slot
        if tick.control is not None and tick.control[i]:
            self._control(tick)
        if tick.sense is None or not tick.sense[i]:
            return
        if tick.imu:
            self._imu(tick)
        if tick.lidar is not None:
            self._scan(tick)
        if tick.depth is not None:
            self._depth(tick)
        if tick.flush:
            self.writer.flush()

    def _control(self, tick: Tick) -> None:
        i, ids = self.slot, self.ids
        rates, steer = measure_wheels(tick.qvel[i, ids["drive_dof"]].astype(np.float64),
                                      tick.qpos[i, ids["steer_qpos"]].astype(np.float64),
                                      self.sim.run.noise, rng=self.rng)
        if tick.k > 0:
            self.odo.update(rates, steer, self.dt_control_s)
        pos, _ = self._pose_yaw(tick.qpos[i])
        r = int(ids["qpos_root"])
        quat = tick.qpos[i, r + 3: r + 7].astype(np.float64)
        v, w = (float(x) for x in tick.cmd[i])
        self.writer.control(tick.t_s, v, w, rates, steer, (pos, quat), self.odo.pose())
        self.n_control += 1

    def _imu(self, tick: Tick) -> None:
        s, a, g = tick.sensordata[self.slot], self.ids["_acc_adr"], self.ids["_gyr_adr"]
        acc_true, gyr_true = s[a: a + 3].astype(np.float64), s[g: g + 3].astype(np.float64)
        acc, gyr = self.imu_noise.measure(acc_true, gyr_true)
        bias = (*self.imu_noise.gyro_bias_rad_s, *self.imu_noise.accel_bias_m_s2)
        self.writer.imu(tick.t_s, acc, gyr, acc_true, gyr_true, bias)

    def _scan(self, tick: Tick) -> None:
        """The scan as :meth:`marsscene.sensors.lidar.Lidar.scan` returns it (returns only, in
        firing order; :meth:`marsscene.sensors.batch.BatchScan.returns`)."""
        range_m, xyz_m, intensity, valid = (a[self.slot] for a in tick.lidar)
        ring, t_s = self.lidar
        idx = np.flatnonzero(valid)
        scan = {"xyz_m": xyz_m.reshape(-1, 3)[idx], "intensity": intensity[idx],
                "ring": ring[idx], "t_s": t_s[idx], "range_m": range_m[idx]}
        self.writer.lidar(tick.t_s, self.n_lidar, scan)
        self.n_lidar += 1

    def _depth(self, tick: Tick) -> None:
        """A depth frame: ``camera/depth/NNNNNN.png`` in the run's millimetres (the batch's
        camera renders no colour: the stamps' ``rgb`` column is empty)."""
        w = self.writer
        name = f"{self.n_cam:06d}.png"
        w.images.submit(w._dir("camera", "depth") / name, depth_mm(tick.depth[self.slot]))
        w.logs["camera"].row(tick.t_s, ("", "depth/" + name))
        self.n_cam += 1

    def finish(self, status: str = "complete") -> dict[str, Any]:
        """Close the folder and write its summary (the CPU drive's keys); the summary."""
        w = self.writer
        w.close()
        assert w.out is not None
        gt, _, _ = _read_back(w.out)
        summary: dict[str, Any] = {
            "status": status,
            "sim_time_s": round(float(gt.timestamps_s[-1]), 6),
            "poses": len(gt),
            "path_length_m": round(gt.path_length_m(), 6),
            "lidar_scans": self.n_lidar,
            "camera_frames": self.n_cam,
            "goal_reached": _goal_reached(gt, None, self.route),
            "imu_bias": _imu_bias(self.imu_noise),
        }
        ct = cross_track_m(self.route, gt.xyz_m[:, :2])
        summary["cross_track_rms_m"] = round(float(np.sqrt(np.mean(ct**2))), 6)
        summary["cross_track_max_m"] = round(float(ct.max()), 6)
        w.finish(summary)
        return summary


class SinkPool:
    """``workers`` threads, each feeding its share of the sinks every tick in order.

    ``put`` blocks while a worker is ``depth`` ticks behind; the first error of a worker is
    raised by the next ``put`` or by :meth:`close`.
    """

    def __init__(self, sinks: list[DriveSink], workers: int, depth: int = 4) -> None:
        self.sinks = sinks
        k = max(1, min(int(workers), len(sinks)))
        self._queues: list[queue.Queue[Tick | None]] = [queue.Queue(depth) for _ in range(k)]
        self._errors: list[BaseException] = []
        self._threads = [threading.Thread(target=self._work, args=(j,), daemon=True,
                                          name=f"marsscene-batch-writer-{j}") for j in range(k)]
        for t in self._threads:
            t.start()

    def _work(self, j: int) -> None:
        mine = self.sinks[j:: len(self._queues)]
        q = self._queues[j]
        while (tick := q.get()) is not None:
            if self._errors:
                continue  # drain: the caller raises
            try:
                for sink in mine:
                    sink.take(tick)
            except BaseException as err:  # handed to the caller
                self._errors.append(err)

    def _raise(self) -> None:
        if self._errors:
            raise self._errors[0]

    def put(self, tick: Tick) -> None:
        self._raise()
        for q in self._queues:
            q.put(tick)

    def close(self) -> None:
        """Wait for every tick to be written."""
        for q in self._queues:
            q.put(None)
        for t in self._threads:
            t.join()
        self._raise()


def meta_of(config: Any, device: str, slot: int, drives: int, rover: Any) -> dict[str, Any]:
    """``run.json``'s entries of a batch drive: its follower and how it was simulated."""
    return {"pursuit": asdict(config),
            "batch": {"engine": "mujoco_warp", "device": device, "slot": slot,
                      "drives": drives, "wheel_collision": rover.wheel_collision}}
