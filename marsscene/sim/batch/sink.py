"""The host side of a batch of drives: the sensor noise, wheel odometry and logs of every drive
computed at once per tick (:class:`BatchSink`), each drive's run folder written by worker
threads (:class:`DriveSink`, :class:`SinkPool`).

A drive's folder is the CPU drive's (:class:`~marsscene.sim.run_writer.RunWriter`, layout in
:mod:`marsscene.runs.logs`): the same noise streams drawn in the same order
(:class:`~.noise.BatchNoise`), the same odometry, the same files. Per tick :class:`BatchSink`
turns the host copies of the batch's state into every drive's log rows in a few array
operations and keeps them; once a simulated second it hands the second's rows to the workers
as one :class:`Block` (each drive's rows formatted and written at once, then flushed), as it
hands them each LiDAR scan and camera frame. Worker ``j`` of ``K`` owns the drives ``i % K == j``
and takes every item in order from a bounded queue: the simulation waits for the slowest worker
rather than piling items up, so memory stays flat over a long drive.
"""

from __future__ import annotations

import queue
import threading
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.sensors.odometry import BatchWheelOdometry
from marsscene.sim.cross_track import cross_track_m
from marsscene.sim.driver import _goal_reached, _read_back
from marsscene.sim.run_writer import RunWriter

__all__ = ["BatchSink", "Block", "DriveSink", "SinkPool", "Tick"]


@dataclass(frozen=True, eq=False)
class Tick:
    """What the batch hands the sinks at one physics tick (host arrays, one row a drive).

    ``control``/``sense``: (N,) bool, the drives that log a control row / sample their sensors
    at this tick (None: none do). ``lidar``: ``range_m, xyz_m, intensity, valid`` of a scan;
    ``frame``: the cameras' ``rgb`` (N, 3, H, W) uint8 and ``depth`` (N, H, W) m;
    ``frame_due``: (N,) bool, the drives that keep it (None: every sensing drive; a
    distance-triggered camera's).
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
    frame: Any = None
    frame_due: Any = None


@dataclass(frozen=True, eq=False)
class Block:
    """A simulated second of every drive's log rows: per log, ``(t_s (R,), rows (R, N) bool,
    values (R, N, C))``, the rows a drive logged where ``rows`` is true."""

    logs: dict[str, tuple[Any, Any, Any]]


class BatchSink:
    """Every drive's noise, odometry and log rows, tick by tick, for ``pool``'s sinks.

    Parameters
    ----------
    pool : SinkPool
    noise : BatchNoise
    ids : dict
        The rover's indices in the batch model (:func:`~marsscene.sim.rover_sim.rover_indices`).
    offsets_xy_m : ndarray (N, 2)
    qpos0 : ndarray (N, nq)
        The settled start state (the odometry's start poses).
    rover : RoverConfig
    dt_control_s : float
    """

    LOGS = ("gt", "odom", "cmd", "wheels", "imu", "imu_true", "imu_bias")

    def __init__(self, pool: SinkPool, noise: Any, *, ids: dict[str, Any], offsets_xy_m: Any,
                 qpos0: Any, rover: Any, dt_control_s: float) -> None:
        self.pool, self.noise, self.ids, self.dt_control_s = pool, noise, ids, dt_control_s
        self.r = int(ids["qpos_root"])
        self.offset = np.column_stack([np.asarray(offsets_xy_m, dtype=np.float64),
                                       np.zeros(len(offsets_xy_m))])
        pos0, yaw0 = self._pose_yaw(np.asarray(qpos0))
        self.odo = BatchWheelOdometry(rover, pos0, yaw0)
        self._rows: dict[str, list[tuple[float, Any, Any]]] = {k: [] for k in self.LOGS}

    def _pose_yaw(self, qpos: Any) -> tuple[np.ndarray, np.ndarray]:
        q = np.asarray(qpos[:, self.r: self.r + 7], dtype=np.float64)
        w, x, y, z = q[:, 3], q[:, 4], q[:, 5], q[:, 6]
        return q[:, :3] - self.offset, np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))

    def put(self, tick: Tick) -> None:
        """Log ``tick`` (the CPU session's order: control, IMU, LiDAR, camera, flush)."""
        if tick.control is not None and tick.control.any():
            self._control(tick)
        sense = tick.sense is not None and bool(tick.sense.any())
        if sense and tick.imu:
            self._imu(tick)
        if sense and (tick.lidar is not None or tick.frame is not None):
            self.pool.put(tick)
        if tick.flush:
            self._hand(flush=True)

    def _control(self, tick: Tick) -> None:
        ids, mask = self.ids, tick.control
        rates, steer = self.noise.wheels(tick.qvel[:, ids["drive_dof"]],
                                         tick.qpos[:, ids["steer_qpos"]])
        if tick.k > 0:
            self.odo.update(rates, steer, self.dt_control_s, mask)
        pos, _ = self._pose_yaw(tick.qpos)
        quat = np.asarray(tick.qpos[:, self.r + 3: self.r + 7], dtype=np.float64)
        opos, oquat = self.odo.pose()
        t = tick.t_s
        for name, values in (("gt", np.hstack([pos, quat])), ("odom", np.hstack([opos, oquat])),
                             ("cmd", np.asarray(tick.cmd, dtype=np.float64)),
                             ("wheels", np.hstack([rates, steer]))):
            self._rows[name].append((t, mask, values))

    def _imu(self, tick: Tick) -> None:
        s, a, g = tick.sensordata, self.ids["_acc_adr"], self.ids["_gyr_adr"]
        acc_true = np.asarray(s[:, a: a + 3], dtype=np.float64)
        gyr_true = np.asarray(s[:, g: g + 3], dtype=np.float64)
        acc, gyr, bias = self.noise.imu(acc_true, gyr_true, tick.sense)
        for name, values in (("imu", np.hstack([acc, gyr])),
                             ("imu_true", np.hstack([acc_true, gyr_true])), ("imu_bias", bias)):
            self._rows[name].append((tick.t_s, tick.sense, values))

    def _hand(self, flush: bool) -> None:
        logs = {k: (np.array([r[0] for r in rows]), np.stack([r[1] for r in rows]),
                    np.stack([r[2] for r in rows])) for k, rows in self._rows.items() if rows}
        self._rows = {k: [] for k in self.LOGS}
        if logs or flush:
            self.pool.put(Block(logs))

    def close(self) -> None:
        """Hand the last rows over and wait for every item to be written."""
        self._hand(flush=False)
        self.pool.close()


class DriveSink:
    """Drive ``slot``'s run folder: its share of each :class:`Block`, its scans and frames."""

    def __init__(self, slot: int, *, sim: Any, out: Path, meta: dict[str, Any], lidar: Any,
                 camera: bool, route: Any) -> None:
        self.slot, self.sim, self.route = slot, sim, route
        self.lidar = lidar  # (ring, t_s) of the rays, or None
        self.writer = RunWriter(out, sim, lidar=lidar is not None, camera=camera, stereo=False,
                                meta=meta)
        self.writer.park()  # thousands of drives: no files held open between blocks
        self.n_lidar = self.n_cam = 0

    def take(self, item: Tick | Block) -> None:
        """Write this drive's part of ``item``."""
        if isinstance(item, Block):
            self._block(item)
            return
        if not item.sense[self.slot]:
            return
        if item.lidar is not None and self.lidar is not None:
            self._scan(item)
        if item.frame is not None and (item.frame_due is None or item.frame_due[self.slot]):
            self._frame(item)

    def _block(self, block: Block) -> None:
        i, w = self.slot, self.writer
        for name, (t, rows, values) in block.logs.items():
            mine = rows[:, i]
            if not mine.any():
                continue
            v = values[mine, i]
            if name in ("gt", "odom"):
                w.poses[name].rows(t[mine], v[:, :3], v[:, 3:])
            else:
                w.logs[name].rows(t[mine], v)
        w.park()

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

    def _frame(self, tick: Tick) -> None:
        """A camera frame: ``camera/rgb/NNNNNN.png`` and ``camera/depth/NNNNNN.png`` (the
        run's millimetres), as a CPU drive writes them."""
        rgb, depth = tick.frame
        self.writer.camera(tick.t_s, self.n_cam, np.ascontiguousarray(
            rgb[self.slot].transpose(1, 2, 0)), None if depth is None else depth[self.slot])
        self.n_cam += 1

    def finish(self, imu_bias: dict[str, Any], status: str = "complete") -> dict[str, Any]:
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
            "imu_bias": imu_bias,
        }
        ct = cross_track_m(self.route, gt.xyz_m[:, :2])
        summary["cross_track_rms_m"] = round(float(np.sqrt(np.mean(ct**2))), 6)
        summary["cross_track_max_m"] = round(float(ct.max()), 6)
        w.finish(summary)
        return summary


class SinkPool:
    """``workers`` threads, each feeding its share of the sinks every tick in order.

    ``put`` blocks while a worker is ``depth`` items behind; the first error of a worker is
    raised by the next ``put`` or by :meth:`close`.
    """

    def __init__(self, sinks: list[DriveSink], workers: int, depth: int = 8) -> None:
        self.sinks = sinks
        k = max(1, min(int(workers), len(sinks)))
        self._queues: list[queue.Queue[Tick | Block | None]] = [
            queue.Queue(depth) for _ in range(k)]
        self._errors: list[BaseException] = []
        self._threads = [threading.Thread(target=self._work, args=(j,), daemon=True,
                                          name=f"marsscene-batch-writer-{j}") for j in range(k)]
        for t in self._threads:
            t.start()

    def _work(self, j: int) -> None:
        mine = self.sinks[j:: len(self._queues)]
        q = self._queues[j]
        while (item := q.get()) is not None:
            if self._errors:
                continue  # drain: the caller raises
            try:
                for sink in mine:
                    sink.take(item)
            except BaseException as err:  # handed to the caller
                self._errors.append(err)

    def _raise(self) -> None:
        if self._errors:
            raise self._errors[0]

    def put(self, item: Tick | Block) -> None:
        self._raise()
        for q in self._queues:
            q.put(item)

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
