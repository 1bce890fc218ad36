"""``drive_sim``: drive a prepared simulator with a controller and log every sensor.

The loop itself is :class:`~marsscene.sim.session.DriveSession`; the controller is pure pursuit
along a route (the MarsLab protocol), an open-loop command, or any callable of an
:class:`~marsscene.sim.control.Observation` (:mod:`marsscene.sim.control`). Most users call
:func:`marsscene.drive`, which loads the scene, authors the route and exports the run.

With a run folder, every log streams to disk as it is sampled (:mod:`marsscene.sim.run_writer`):
memory stays flat however long the drive, and an interrupted drive (Ctrl-C, or SIGTERM turned
into one by the command line) ends in :class:`DriveInterrupted` after writing a complete run
folder up to that moment (``summary.status = "interrupted"``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._validate import plain
from marsscene.errors import RuntimeSimError
from marsscene.runs.runlog import read_numeric_csv
from marsscene.runs.tum import Trajectory, read_tum, write_tum
from marsscene.sensors.imu import ImuNoise, bias_record
from marsscene.sim.control import Controller, OpenLoop
from marsscene.sim.cross_track import cross_track_m
from marsscene.sim.goal import goal_reached
from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Route
from marsscene.sim.run_writer import GT_HEADER, ODOM_HEADER
from marsscene.sim.session import DriveSession, SessionOptions

__all__ = ["DriveInterrupted", "DriveProgress", "DriveResult", "drive_sim"]


@dataclass(frozen=True)
class DriveProgress:
    """Where a drive stands, passed to ``progress`` once per simulated second.

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
        self.team: dict[str, DriveResult] = {}  # a team drive's: every robot's, by name


class _Rows:
    """Keeps the control rows in memory when the drive writes no run folder."""

    def __init__(self) -> None:
        self.gt: list[np.ndarray] = []
        self.odom: list[np.ndarray] = []
        self.cmd: list[tuple[float, float, float]] = []

    def control(self, t: float, v: float, w: float, rates: Any, steer: Any,
                gt: tuple[Any, Any], odom: tuple[Any, Any]) -> None:
        self.gt.append(np.concatenate([[t], *gt]))
        self.odom.append(np.concatenate([[t], *odom]))
        self.cmd.append((t, v, w))

    def trajectories(self) -> tuple[Trajectory, Trajectory, np.ndarray]:
        gt_a, od_a = np.array(self.gt), np.array(self.odom)
        gt = Trajectory.from_wxyz(gt_a[:, 0], gt_a[:, 1:4], gt_a[:, 4:8])
        odom = Trajectory.from_wxyz(od_a[:, 0], od_a[:, 1:4], od_a[:, 4:8])
        return gt, odom, np.array(self.cmd).reshape(-1, 3)


def _read_back(out: Path) -> tuple[Trajectory, Trajectory, np.ndarray]:
    """Ground truth, odometry and commands read back from a run folder (cut to their common
    length: an interruption may fall between two rows)."""
    gt, odom = read_tum(out / "gt.tum"), read_tum(out / "odom.tum")
    n = min(len(gt), len(odom))
    for name, traj, head in (("gt", gt, GT_HEADER), ("odom", odom, ODOM_HEADER)):
        if len(traj) > n:
            write_tum(out / f"{name}.tum", traj.head(n), header=head)  # cut mid-period
    return gt.head(n), odom.head(n), read_numeric_csv(out / "cmd.csv", 3)


def _goal_reached(gt: Trajectory, controller: Any, route: Route | None) -> bool | None:
    """The summary's ``goal_reached``: the drive ended within the goal tolerance of its route's
    end (:func:`marsscene.sim.goal.goal_reached`, the environments' and the bridge's test); a
    drive without a route reports its controller's ``done``, if it has one."""
    if route is not None:
        return bool(goal_reached(gt.xyz_m[-1, :2], route.xy_m[-1]))
    done = getattr(controller, "done", None)
    return bool(done) if done is not None else None


def _result(session: DriveSession, rows: _Rows | None, controller: Any, route: Route | None,
            status: str) -> DriveResult:
    """Close the session; the trajectories and the summary (written into ``run.json``)."""
    summary_camera = {}
    if session.renderer is not None:
        summary_camera = {"exposure_gain_last": session.renderer.exposure.gain}
    session.close()
    out = session.writer.out
    if rows is not None or out is None:
        assert rows is not None
        gt, odom, cmd = rows.trajectories()
    else:
        gt, odom, cmd = _read_back(out)
    summary: dict[str, Any] = {
        "status": status,
        "sim_time_s": round(float(gt.timestamps_s[-1]), 6),
        "poses": len(gt),
        "path_length_m": round(gt.path_length_m(), 6),
        "lidar_scans": session.n_lidar,
        "camera_frames": session.n_cam,
        "goal_reached": _goal_reached(gt, controller, route),
        **summary_camera,
        "imu_bias": _imu_bias(session.imu_noise),
    }
    if route is not None:
        ct = cross_track_m(route, gt.xyz_m[:, :2])
        summary["cross_track_rms_m"] = round(float(np.sqrt(np.mean(ct**2))), 6)
        summary["cross_track_max_m"] = round(float(ct.max()), 6)
    session.writer.finish(summary)
    res = DriveResult(gt, odom, cmd, summary, session.scans, session.images)
    res.stereo_images = session.stereo_images
    if session.keep and session.imu_rows:
        res.imu = np.array(session.imu_rows)
    return res


def _controller(route: Route | None, controller: Any, command: Any,
                pursuit: PursuitConfig | None) -> tuple[Any, dict[str, Any]]:
    """The controller of a drive and what ``run.json`` records of it."""
    if sum(x is not None for x in (controller, command)) > 1:
        raise RuntimeSimError("give a controller or a command, not both")
    if controller is not None:
        if not callable(controller):
            raise RuntimeSimError(f"controller {controller!r} is not callable")
        name = getattr(controller, "__qualname__", type(controller).__qualname__)
        module = getattr(controller, "__module__", type(controller).__module__)
        return controller, {"controller": f"{module}:{name}"}
    if command is not None:
        return OpenLoop(command), {}
    if route is None:
        raise RuntimeSimError("drive needs a route, a command or a controller")
    follower = PurePursuit(route, pursuit)
    return follower, {"pursuit": asdict(follower.config)}


def _checked(cmd: Any) -> tuple[float, float]:
    """A controller's ``(v, omega)``, or a one-line error naming what it returned."""
    try:
        v, w = cmd
        ok = math.isfinite(v) and math.isfinite(w)
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise RuntimeSimError(f"controller returned {plain(cmd)!r}; expected (v_m_s, "
                              "omega_rad_s), two finite numbers")
    return v, w


def _time_limit_s(route: Route | None, seconds: float | None) -> float:
    limit = (seconds if seconds is not None
             else (2.0 * route.length_m / 0.1 + 60.0 if route is not None else None))
    if limit is None or limit <= 0:
        raise RuntimeSimError(
            f"seconds = {plain(seconds)!r} must be > 0 when driving without a route")
    return float(limit)


def _imu_bias(imu: ImuNoise) -> dict[str, list[float]]:
    """The run's IMU biases: turn-on (constant part) and at the end (after the random walk)."""
    return bias_record(imu.gyro_turn_on_rad_s, imu.gyro_bias_rad_s, imu.accel_turn_on_m_s2,
                       imu.accel_bias_m_s2)


def drive_sim(
    sim: Any,
    *,
    route: Route | None = None,
    controller: Controller | Callable[[Any], tuple[float, float]] | None = None,
    command: tuple[float, float] | Callable[[float], tuple[float, float]] | None = None,
    seconds: float | None = None,
    out_dir: str | Path | None = None,
    rng: np.random.Generator,
    pursuit: PursuitConfig | None = None,
    session: SessionOptions | None = None,
    progress: Callable[[DriveProgress], None] | None = None,
) -> DriveResult:
    """Drive a prepared simulator and log every sensor.

    Parameters
    ----------
    sim : RoverSim
        Reset at the start pose (:func:`~marsscene.sim.mission.prepare_drive`).
    route : Route, optional
        Followed with pure pursuit until the goal (or ``seconds``) unless a controller or a
        command is given; with one, it still sets the time limit and the cross-track summary.
    controller : callable, optional
        ``controller(Observation) -> (v, omega)`` once per control period
        (:mod:`marsscene.sim.control`); its optional ``done`` attribute ends the drive.
    command : (v, omega) or callable t -> (v, omega), optional
        Open-loop command.
    seconds : float, optional
        Sim-time limit (required without a route).
    out_dir : path, optional
        Run folder (layout in :mod:`marsscene.runs.logs`); nothing is written if omitted.
    rng : numpy.random.Generator
        Sensor noise stream (e.g. ``stage_rng(seed, "sensors")``).
    pursuit : PursuitConfig, optional
        Of the route follower.
    session : SessionOptions, optional
        Samples kept in memory, LiDAR files, listeners, the bag's JPEG cache.
    progress : callable, optional
        ``progress(DriveProgress)`` called once per simulated second.

    Raises
    ------
    DriveInterrupted
        On Ctrl-C (a :class:`KeyboardInterrupt`), after finishing the run folder up to the
        interruption; its ``result`` holds the prefix.
    """
    ctrl, meta = _controller(route, controller, command, pursuit)
    limit_s = _time_limit_s(route, seconds)
    rows = _Rows() if out_dir is None else None
    opts = session if session is not None else SessionOptions()
    if rows is not None:
        opts = replace(opts, listeners=(*opts.listeners, rows))
    loop = DriveSession(sim, rng=rng, out_dir=out_dir, options=opts, meta=meta)
    follower = ctrl if isinstance(ctrl, PurePursuit) else None

    def report(t: float) -> None:
        if progress is not None:
            progress(DriveProgress(t, limit_s, loop.distance_m,
                                   float(follower.s[follower.index]) if follower else None,
                                   float(follower.s[-1]) if follower else None))

    try:
        _run(loop, ctrl, round(limit_s / sim.dt_physics_s), report)
    except KeyboardInterrupt:
        if loop.n_control == 0:
            loop.close()
            raise
        raise DriveInterrupted(_result(loop, rows, ctrl, route, "interrupted")) from None
    except BaseException:  # a controller's error, a diverged simulation: free the threads
        loop.close()
        raise
    return _result(loop, rows, ctrl, route, "complete")


def _run(loop: DriveSession, ctrl: Any, steps_limit: int,
         report: Callable[[float], None]) -> None:
    """Observe, command, advance, until the controller is done or the time limit."""
    obs = loop.observe()
    while True:
        v, w = _checked(ctrl(obs))
        loop.act(v, w)
        if getattr(ctrl, "done", False) or not loop.advance(steps_limit, report):
            return
        obs = loop.observe()
