"""``drive``: run the rover along a route (or a fixed command) and write the logs.

Every sensor is sampled on one simulation clock. The loop advances the physics in ticks of the
greatest common divisor of all sensor periods; the controller (pure pursuit on the ground-truth
pose, the MarsLab protocol) runs at ``run.control_hz``.

With a run folder, every log streams to disk as it is sampled (:mod:`marsscene.sim.run_writer`):
memory stays flat however long the drive, and an interrupted drive (Ctrl-C, or SIGTERM turned
into one by the command line) ends in :class:`DriveInterrupted` after writing a complete run
folder up to that moment (``summary.status = "interrupted"``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from marsscene._validate import plain
from marsscene.errors import RuntimeSimError
from marsscene.runs.runlog import read_numeric_csv
from marsscene.runs.tum import Trajectory, read_tum, write_tum
from marsscene.sensors.camera_world import read_rock_catalog
from marsscene.sensors.imu import ImuNoise
from marsscene.sensors.lidar import Lidar
from marsscene.sensors.odometry import WheelOdometry, measure_wheels
from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Route, cross_track_m
from marsscene.sim.run_writer import GT_HEADER, ODOM_HEADER, RunWriter

if TYPE_CHECKING:
    from marsscene.runs.export.bag_images import JpegCache

__all__ = ["DriveInterrupted", "DriveProgress", "DriveResult", "drive"]


@dataclass(frozen=True)
class DriveProgress:
    """Where a drive stands, passed to ``drive(progress=...)`` once per simulated second.

    ``route_done_m`` is the progress along the route (the follower's nearest route point), and
    ``route_length_m`` the route's length; both are None without a route.
    """

    sim_time_s: float
    limit_s: float
    distance_m: float
    route_done_m: float | None = None
    route_length_m: float | None = None

    @property
    def fraction(self) -> float:
        """Share of the drive done (route progress, else sim time over the limit), 0..1."""
        if self.route_length_m:
            return min(1.0, max(0.0, (self.route_done_m or 0.0) / self.route_length_m))
        return min(1.0, self.sim_time_s / self.limit_s) if self.limit_s > 0 else 1.0


class DriveResult:
    """What a drive produced: trajectories, commands and summary statistics."""

    def __init__(
        self,
        gt: Trajectory,
        odom: Trajectory,
        cmd: np.ndarray,
        summary: dict[str, Any],
        lidar: list[dict[str, Any]],
        images: list[tuple[np.ndarray, np.ndarray | None]],
    ):
        self.gt, self.odom, self.cmd, self.summary = gt, odom, cmd, summary
        self.lidar_scans, self.images = lidar, images
        self.imu: np.ndarray = np.zeros((0, 7))
        self.stereo_images: list[tuple[np.ndarray, np.ndarray]] = []


class DriveInterrupted(KeyboardInterrupt):
    """A drive stopped by Ctrl-C (or SIGTERM via the command line); the run folder was
    finished up to that moment. ``result`` is the :class:`DriveResult` of the prefix."""

    def __init__(self, result: DriveResult):
        super().__init__(f"drive interrupted at {result.summary['sim_time_s']:.2f} sim s")
        self.result = result


def _period(sim: Any, rate_hz: float) -> int:
    return round(1.0 / (rate_hz * sim.dt_physics_s))


def _time_limit_s(route: Route | None, command: Any, seconds: float | None) -> float:
    if route is None and command is None:
        raise RuntimeSimError("drive needs a route or a command")
    limit = (seconds if seconds is not None
             else (2.0 * route.length_m / 0.1 + 60.0 if route is not None else None))
    if limit is None or limit <= 0:
        raise RuntimeSimError(
            f"seconds = {plain(seconds)!r} must be > 0 when driving without a route")
    return float(limit)


class _Loop:
    """One drive's state: the sensors, their periods on the physics clock, the rows kept."""

    def __init__(self, sim: Any, route: Route | None, command: Any, pursuit: PursuitConfig | None,
                 rng: np.random.Generator, keep: bool, writer_out: Path | None,
                 jpeg_cache: Any = None):
        run = sim.run
        self.sim, self.command, self.rng, self.keep = sim, command, rng, keep
        self.follower = PurePursuit(route, pursuit) if route is not None else None
        self.periods = {"control": _period(sim, run.control_hz), "imu": _period(sim, run.imu_hz)}
        self.renderer = None
        self.trigger_m = run.camera.trigger_distance_m if run.camera is not None else None
        self.next_frame_m = 0.0
        if run.camera is not None:
            if self.trigger_m is None:
                self.periods["camera"] = _period(sim, run.camera.rate_hz)
            self.renderer = sim.make_renderer(rng=rng.spawn(1)[0])
        self.lidar = None
        if run.lidar is not None:  # its own stream: LiDAR noise never moves IMU/wheel noise
            self.periods["lidar"] = _period(sim, run.lidar.spec.rate_hz)
            self.lidar = Lidar(run.lidar, rng=rng.spawn(1)[0],
                               rocks=read_rock_catalog(Path(sim.scene_dir)))
        self.stereo = self.renderer is not None and self.renderer.stereo_ids is not None
        self.writer = RunWriter(writer_out, sim, lidar=self.lidar is not None,
                                camera=self.renderer is not None, stereo=self.stereo,
                                pursuit=self.follower.config if self.follower else None,
                                jpeg_cache=jpeg_cache)
        pos0, _ = sim.pose()
        self.odo = WheelOdometry(sim.rover, pos0[0], pos0[1], pos0[2], sim.yaw_rad())
        self.streamed = writer_out is not None  # else the rows are kept here
        self.gt_rows: list[np.ndarray] = []
        self.od_rows: list[np.ndarray] = []
        self.cmd_rows: list[tuple[float, float, float]] = []
        self.distance_m, self._last_xy = 0.0, (float(pos0[0]), float(pos0[1]))
        self.n_control = 0
        self.imu_rows: list[np.ndarray] = []
        self.scans: list[dict[str, Any]] = []
        self.images: list[tuple[np.ndarray, np.ndarray | None]] = []
        self.stereo_images: list[tuple[np.ndarray, np.ndarray]] = []
        self.n_lidar = self.n_cam = 0
        self._lidar_pool: ThreadPoolExecutor | None = None
        self._pending: tuple[float, Future[dict[str, Any]]] | None = None
        self.imu_noise = ImuNoise(run.noise, run.imu_hz, rng=rng)  # draws the turn-on biases

    def control(self, k: int, t: float) -> bool:
        """Log ground truth and odometry, command the rover; True once the route is done."""
        sim = self.sim
        pos, quat = sim.pose()
        rates, steer = measure_wheels(sim.wheel_rates(), sim.steer_angles(), sim.run.noise,
                                      rng=self.rng)
        if k > 0:
            self.odo.update(rates, steer, self.periods["control"] * sim.dt_physics_s)
        opos, oquat = self.odo.pose()
        if self.follower is not None:
            v, w = self.follower.command(pos[0], pos[1], sim.yaw_rad())
        else:
            v, w = self.command(t) if callable(self.command) else self.command
        sim.apply(v, w)
        self.distance_m += math.hypot(pos[0] - self._last_xy[0], pos[1] - self._last_xy[1])
        self._last_xy = (float(pos[0]), float(pos[1]))
        if self.streamed:
            self.writer.control(t, v, w, rates, steer, (pos, quat), (opos, oquat))
        else:
            self.gt_rows.append(np.concatenate([[t], pos, quat]))
            self.od_rows.append(np.concatenate([[t], opos, oquat]))
            self.cmd_rows.append((t, v, w))
        self.n_control += 1
        return self.follower is not None and self.follower.done

    def imu(self, t: float) -> None:
        acc_true, gyr_true = self.sim.imu_true()
        acc, gyr = self.imu_noise.measure(acc_true, gyr_true)
        bias = (*self.imu_noise.gyro_bias_rad_s, *self.imu_noise.accel_bias_m_s2)
        self.writer.imu(t, acc, gyr, acc_true, gyr_true, bias)
        if self.keep:
            self.imu_rows.append(np.concatenate([[t], acc, gyr]))

    def scan(self, t: float) -> None:
        """Read the LiDAR's pose now; cast on the helper thread while the simulation goes on
        (the previous scan is collected first, so scans are written in order)."""
        assert self.lidar is not None
        sim = self.sim
        cast = self.lidar.prepare(sim.model, sim.data, sim.lidar_site, sim.heightfield,
                                  twist=sim.site_twist(sim.lidar_site))
        self.collect_scan()
        if self._lidar_pool is None:
            self._lidar_pool = ThreadPoolExecutor(1, thread_name_prefix="marsscene-lidar")
        self._pending = (t, self._lidar_pool.submit(cast))

    def collect_scan(self) -> None:
        """Wait for the scan on the helper thread (if any) and write it."""
        if self._pending is None:
            return
        t, future = self._pending
        self._pending = None
        scan = future.result()
        self.writer.lidar(t, self.n_lidar, scan)
        if self.keep:
            self.scans.append({"t": t, **scan})
        self.n_lidar += 1

    def frame(self, t: float) -> None:
        assert self.renderer is not None
        rgb, depth = self.sim.render(self.renderer)
        self.writer.camera(t, self.n_cam, rgb, depth)
        if self.stereo:
            pair = self.renderer.render_stereo(self.sim)
            self.writer.stereo(t, self.n_cam, pair)
            if self.keep:
                self.stereo_images.append(pair)
        if self.keep:
            self.images.append((rgb, depth))
        self.n_cam += 1

    def camera_due(self, k: int) -> bool:
        """A frame at this physics step: every camera period, or (``trigger_distance_m``) at
        the first control step at or past the next multiple of the trigger distance."""
        if self.trigger_m is None:
            return k % self.periods["camera"] == 0
        if k % self.periods["control"] != 0 or self.distance_m < self.next_frame_m:
            return False
        self.next_frame_m = (math.floor(self.distance_m / self.trigger_m) + 1) * self.trigger_m
        return True

    def report(self, t: float, limit_s: float) -> DriveProgress:
        f = self.follower
        return DriveProgress(t, limit_s, self.distance_m,
                             float(f.s[f.index]) if f is not None else None,
                             float(f.s[-1]) if f is not None else None)

    def run(self, limit_s: float, progress: Callable[[DriveProgress], None] | None) -> None:
        """Step the physics in ticks of the sensors' common period until done or the limit."""
        sim, periods = self.sim, self.periods
        tick = math.gcd(*periods.values())
        steps_limit = round(limit_s / sim.dt_physics_s)
        k, next_report = 0, 1.0
        self.t_s = 0.0
        while k <= steps_limit:
            t = k * sim.dt_physics_s
            if k % periods["control"] == 0 and self.control(k, t):
                break
            if k % periods["imu"] == 0:
                self.imu(t)
            if self.lidar is not None and k % periods["lidar"] == 0:
                self.scan(t)
            if self.renderer is not None and self.camera_due(k):
                self.frame(t)
            if t >= next_report:
                self.writer.flush()
                if progress is not None:
                    progress(self.report(t, limit_s))
                next_report += 1.0
            self.t_s = t
            sim.advance(tick)
            k += tick

    def trajectories(self) -> tuple[Trajectory, Trajectory, np.ndarray]:
        """Ground truth, odometry and commands, read back from the run folder when streamed
        (cut to their common length: an interruption may fall between two rows)."""
        if not self.streamed:
            gt_a, od_a = np.array(self.gt_rows), np.array(self.od_rows)
            gt = Trajectory.from_wxyz(gt_a[:, 0], gt_a[:, 1:4], gt_a[:, 4:8])
            odom = Trajectory.from_wxyz(od_a[:, 0], od_a[:, 1:4], od_a[:, 4:8])
            return gt, odom, np.array(self.cmd_rows).reshape(-1, 3)
        out = self.writer.out
        assert out is not None
        gt, odom = read_tum(out / "gt.tum"), read_tum(out / "odom.tum")
        n = min(len(gt), len(odom))
        for name, traj, head in (("gt", gt, GT_HEADER), ("odom", odom, ODOM_HEADER)):
            if len(traj) > n:
                write_tum(out / f"{name}.tum", traj.head(n), header=head)  # cut mid-period
        return gt.head(n), odom.head(n), read_numeric_csv(out / "cmd.csv", 3)

    def result(self, route: Route | None, status: str) -> DriveResult:
        """Close the writers and the renderer; the trajectories and the summary."""
        self.collect_scan()
        if self._lidar_pool is not None:
            self._lidar_pool.shutdown()
        self.writer.close()
        summary_camera = {}
        if self.renderer is not None:
            summary_camera = {"exposure_gain_last": self.renderer.exposure.gain}
            self.renderer.close()
        gt, odom, cmd = self.trajectories()
        summary: dict[str, Any] = {
            "status": status,
            "sim_time_s": round(float(gt.timestamps_s[-1]), 6),
            "poses": len(gt),
            "path_length_m": round(gt.path_length_m(), 6),
            "lidar_scans": self.n_lidar,
            "camera_frames": self.n_cam,
            "goal_reached": bool(self.follower.done) if self.follower is not None else None,
            **summary_camera,
            "imu_bias": _imu_bias(self.imu_noise),
        }
        if route is not None:
            ct = cross_track_m(route, gt.xyz_m[:, :2])
            summary["cross_track_rms_m"] = round(float(np.sqrt(np.mean(ct**2))), 6)
            summary["cross_track_max_m"] = round(float(ct.max()), 6)
        self.writer.finish(summary)
        res = DriveResult(gt, odom, cmd, summary, self.scans, self.images)
        res.stereo_images = self.stereo_images
        if self.keep and self.imu_rows:
            res.imu = np.array(self.imu_rows)
        return res


def _imu_bias(imu: ImuNoise) -> dict[str, list[float]]:
    """The run's IMU biases: turn-on (constant part) and at the end (after the random walk)."""
    return {k: [float(x) for x in v] for k, v in (
        ("gyro_start_rad_s", imu.gyro_turn_on_rad_s), ("gyro_end_rad_s", imu.gyro_bias_rad_s),
        ("accel_start_m_s2", imu.accel_turn_on_m_s2), ("accel_end_m_s2", imu.accel_bias_m_s2))}


def drive(
    sim: Any,
    *,
    route: Route | None = None,
    command: tuple[float, float] | Callable[[float], tuple[float, float]] | None = None,
    seconds: float | None = None,
    out_dir: str | Path | None = None,
    rng: np.random.Generator,
    pursuit: PursuitConfig | None = None,
    keep_sensors: bool = False,
    progress: Callable[[DriveProgress], None] | None = None,
    jpeg_cache: JpegCache | None = None,
) -> DriveResult:
    """Drive ``sim`` and log every sensor.

    Parameters
    ----------
    sim : RoverSim
    route : Route, optional
        Followed with pure pursuit until the goal (or ``seconds``).
    command : (v, omega) or callable t -> (v, omega), optional
        Open-loop command instead of a route.
    seconds : float, optional
        Sim-time limit (required without a route).
    out_dir : path, optional
        Run folder (layout in :mod:`marsscene.runs.logs`); nothing is written if omitted.
    rng : numpy.random.Generator
        Sensor noise stream (e.g. ``stage_rng(seed, "sensors")``).
    keep_sensors : bool
        Keep LiDAR scans, images and IMU samples in memory in the result.
    progress : callable, optional
        ``progress(DriveProgress)`` called once per simulated second.
    jpeg_cache : JpegCache, optional
        Also JPEG-encode every colour frame into this cache (for a bag written right after:
        :func:`~marsscene.runs.export.bag.write_bag` reads it instead of decoding the PNGs).

    Raises
    ------
    DriveInterrupted
        On Ctrl-C (a :class:`KeyboardInterrupt`), after finishing the run folder up to the
        interruption; its ``result`` holds the prefix.
    """
    limit_s = _time_limit_s(route, command, seconds)
    out = Path(out_dir) if out_dir is not None else None
    loop = _Loop(sim, route, command, pursuit, rng, keep_sensors, out, jpeg_cache)
    try:
        loop.run(limit_s, progress)
    except KeyboardInterrupt:
        if loop.n_control == 0:
            raise
        raise DriveInterrupted(loop.result(route, "interrupted")) from None
    return loop.result(route, "complete")
