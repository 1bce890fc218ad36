"""``drive``: run the rover along a route (or a fixed command) and write the logs.

Every sensor is sampled on one simulation clock. The loop advances the physics in ticks of the
greatest common divisor of all sensor periods; the controller (pure pursuit on the ground-truth
pose, the MarsLab protocol) runs at ``run.control_hz``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._validate import plain
from marsscene.runtime.logs import CsvLog, ImageWriter, ply_bytes, write_json
from marsscene.runtime.pursuit import PurePursuit, PursuitConfig
from marsscene.runtime.route import Route, cross_track_m
from marsscene.runtime.rover import DRIVE_JOINTS, STEER_JOINTS
from marsscene.runtime.sensors import Lidar, WheelOdometry, imu_measure, measure_wheels
from marsscene.runtime.tum import Trajectory, write_tum

__all__ = ["DriveResult", "drive"]


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


def _period(sim: Any, rate_hz: float) -> int:
    return round(1.0 / (rate_hz * sim.dt_physics_s))


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
    progress: Callable[[float, float], None] | None = None,
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
        Run folder (layout in :mod:`marsscene.runtime.logs`); nothing is written if omitted.
    rng : numpy.random.Generator
        Sensor noise stream (e.g. ``stage_rng(seed, "sensors")``).
    keep_sensors : bool
        Keep LiDAR scans, images and IMU samples in memory in the result.
    progress : callable, optional
        ``progress(t_s, limit_s)`` called once per simulated second.
    """
    from marsscene.errors import RuntimeSimError

    if route is None and command is None:
        raise RuntimeSimError("drive needs a route or a command")
    limit = (
        seconds
        if seconds is not None
        else (2.0 * route.length_m / 0.1 + 60.0 if route is not None else None)
    )
    if limit is None or limit <= 0:
        raise RuntimeSimError(
            f"seconds = {plain(seconds)!r} must be > 0 when driving without a route"
        )
    run = sim.run
    follower = PurePursuit(route, pursuit) if route is not None else None
    lidar = Lidar(run.lidar) if run.lidar is not None else None
    periods = {"control": _period(sim, run.control_hz), "imu": _period(sim, run.imu_hz)}
    if run.lidar is not None:
        periods["lidar"] = _period(sim, run.lidar.rate_hz)
    renderer = None
    if run.camera is not None:
        periods["camera"] = _period(sim, run.camera.rate_hz)
        renderer = sim.make_renderer(rng=rng.spawn(1)[0])
    stereo = renderer is not None and renderer.stereo_ids is not None
    tick = math.gcd(*periods.values())
    images_out = ImageWriter()  # camera PNGs are encoded beside the simulation
    out = Path(out_dir) if out_dir is not None else None
    logs: dict[str, CsvLog] = {}
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        logs["cmd"] = CsvLog(out / "cmd.csv", ["t", "v", "omega"])
        logs["wheels"] = CsvLog(
            out / "wheels.csv",
            [
                "t",
                *[f"rate_{j[-2:]}" for j in DRIVE_JOINTS],
                *[f"steer_{j[-2:]}" for j in STEER_JOINTS],
            ],
        )
        logs["imu"] = CsvLog(out / "imu.csv", ["t", "ax", "ay", "az", "gx", "gy", "gz"])
        logs["imu_true"] = CsvLog(out / "imu_true.csv", ["t", "ax", "ay", "az", "gx", "gy", "gz"])
        if lidar is not None:
            logs["lidar"] = CsvLog(out / "lidar" / "stamps.csv", ["t", "file", "points"])
        if renderer is not None:
            logs["camera"] = CsvLog(out / "camera" / "stamps.csv", ["t", "rgb", "depth"])
            write_json(out / "camera" / "intrinsics.json", sim.camera_intrinsics())
            if stereo:
                for side in ("left", "right"):
                    logs[side] = CsvLog(out / "camera" / side / "stamps.csv", ["t", "rgb"])
                    (out / "camera" / side / "rgb").mkdir(parents=True, exist_ok=True)
                    write_json(out / "camera" / side / "intrinsics.json",
                               sim.camera_intrinsics(side))
    pos0, _ = sim.pose()
    odo = WheelOdometry(sim.rover, pos0[0], pos0[1], pos0[2], sim.yaw_rad())
    gt_rows: list[np.ndarray] = []
    od_rows: list[np.ndarray] = []
    cmd_rows: list[tuple[float, float, float]] = []
    imu_rows: list[np.ndarray] = []
    scans: list[dict[str, Any]] = []
    images: list[tuple[np.ndarray, np.ndarray | None]] = []
    stereo_images: list[tuple[np.ndarray, np.ndarray]] = []
    steps_limit = round(limit / sim.dt_physics_s)
    dt_ctrl = periods["control"] * sim.dt_physics_s
    k = 0
    n_lidar = n_cam = 0
    next_report = 1.0
    while k <= steps_limit:
        t = k * sim.dt_physics_s
        if k % periods["control"] == 0:
            pos, quat = sim.pose()
            gt_rows.append(np.concatenate([[t], pos, quat]))
            rates, steer = measure_wheels(sim.wheel_rates(), sim.steer_angles(), run.noise, rng=rng)
            if k > 0:
                odo.update(rates, steer, dt_ctrl)
            opos, oquat = odo.pose()
            od_rows.append(np.concatenate([[t], opos, oquat]))
            if follower is not None:
                v, w = follower.command(pos[0], pos[1], sim.yaw_rad())
            else:
                v, w = command(t) if callable(command) else command  # type: ignore[misc]
            sim.apply(v, w)
            cmd_rows.append((t, v, w))
            if logs:
                logs["cmd"].row(t, (v, w))
                logs["wheels"].row(t, (*rates, *steer))
            if follower is not None and follower.done:
                break
        if k % periods["imu"] == 0:
            acc_true, gyr_true = sim.imu_true()
            acc, gyr = imu_measure(acc_true, gyr_true, run.noise, rng=rng)
            if logs:
                logs["imu"].row(t, (*acc, *gyr))
                logs["imu_true"].row(t, (*acc_true, *gyr_true))
            if keep_sensors:
                imu_rows.append(np.concatenate([[t], acc, gyr]))
        if lidar is not None and k % periods["lidar"] == 0:
            scan = lidar.scan(sim.model, sim.data, sim.lidar_site, sim.heightfield)
            if out is not None:
                name = f"{n_lidar:06d}.ply"
                (out / "lidar" / name).write_bytes(
                    ply_bytes(scan["xyz_m"], scan["intensity"], scan["ring"])
                )
                logs["lidar"].row(t, (name, len(scan["range_m"])))
            if keep_sensors:
                scans.append({"t": t, **scan})
            n_lidar += 1
        if renderer is not None and k % periods["camera"] == 0:
            rgb, depth = sim.render(renderer)
            if out is not None:
                name = f"{n_cam:06d}.png"
                (out / "camera" / "rgb").mkdir(parents=True, exist_ok=True)
                images_out.submit(out / "camera" / "rgb" / name, rgb)
                dname = ""
                if depth is not None:
                    (out / "camera" / "depth").mkdir(parents=True, exist_ok=True)
                    mm = np.clip(np.round(depth * 1000.0), 0, 65535).astype(np.uint16)
                    images_out.submit(out / "camera" / "depth" / name, mm)
                    dname = "depth/" + name
                logs["camera"].row(t, ("rgb/" + name, dname))
            if stereo:
                pair = renderer.render_stereo(sim)
                for side, img in zip(("left", "right"), pair, strict=True):
                    if out is not None:
                        images_out.submit(out / "camera" / side / "rgb" / name, img)
                        logs[side].row(t, ("rgb/" + name,))
                if keep_sensors:
                    stereo_images.append(pair)
            if keep_sensors:
                images.append((rgb, depth))
            n_cam += 1
        if progress is not None and t >= next_report:
            progress(t, limit)
            next_report += 1.0
        sim.advance(tick)
        k += tick
    images_out.close()
    for log in logs.values():
        log.close()
    if renderer is not None:
        summary_camera = {"exposure_gain_last": renderer.exposure.gain}
        renderer.close()
    else:
        summary_camera = {}
    gt_a, od_a = np.array(gt_rows), np.array(od_rows)
    gt = Trajectory.from_wxyz(gt_a[:, 0], gt_a[:, 1:4], gt_a[:, 4:8])
    odom = Trajectory.from_wxyz(od_a[:, 0], od_a[:, 1:4], od_a[:, 4:8])
    summary: dict[str, Any] = {
        "sim_time_s": round(float(gt.timestamps_s[-1]), 6),
        "poses": len(gt),
        "path_length_m": round(gt.path_length_m(), 6),
        "lidar_scans": n_lidar,
        "camera_frames": n_cam,
        "goal_reached": bool(follower.done) if follower is not None else None,
        **summary_camera,
    }
    if route is not None:
        ct = cross_track_m(route, gt.xyz_m[:, :2])
        summary["cross_track_rms_m"] = round(float(np.sqrt(np.mean(ct**2))), 6)
        summary["cross_track_max_m"] = round(float(ct.max()), 6)
    if out is not None:
        write_tum(out / "gt.tum", gt, header="ground truth base_link in map (world) frame")
        write_tum(
            out / "odom.tum", odom, header="wheel odometry base_link in odom frame (= map at t=0)"
        )
        write_json(
            out / "run.json",
            {
                "summary": summary,
                "rover": asdict(sim.rover),
                "noise": asdict(run.noise),
                "rates_hz": {
                    "physics": 1.0 / sim.dt_physics_s,
                    "control": run.control_hz,
                    "imu": run.imu_hz,
                    "lidar": run.lidar.rate_hz if run.lidar else None,
                    "camera": run.camera.rate_hz if run.camera else None,
                },
                "lidar": asdict(run.lidar) if run.lidar else None,
                "camera": asdict(run.camera) if run.camera else None,
                "pursuit": asdict(follower.config) if follower is not None else None,
                "frames": {
                    "world": "map: x east, y north, z up (REP-103/105)",
                    "base_link": "x forward, y left, z up",
                    "imu": "= base_link",
                    "lidar": "x forward, y left, z up at the mast top",
                },
            },
        )
    res = DriveResult(gt, odom, np.array(cmd_rows), summary, scans, images)
    res.stereo_images = stereo_images
    if keep_sensors and imu_rows:
        res.imu = np.array(imu_rows)
    return res
