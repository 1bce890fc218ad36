"""Drive one built cell scene and evaluate wheel odometry against ground truth (ATE/RPE).

Calls the runtime exactly as ``marsscene drive`` does (route authoring, contact corridor,
settling, pure pursuit) and then :func:`~marsscene.runtime.ate` / :func:`~marsscene.runtime.rpe`.
``mujoco`` is imported only when a cell is driven.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.sweep.spec import DriveSpec

__all__ = ["drive_cell"]


def drive_cell(scene_dir: Path, spec: DriveSpec, out_dir: Path) -> dict[str, Any]:
    """Drive the rover on ``scene_dir`` as ``spec`` says; logs go to ``out_dir``.

    Returns
    -------
    dict
        ``distance_m``, ``sim_time_s``, ``goal_reached``, ``cross_track_rms_m``,
        ``ate_rmse_m`` (SE(3)-aligned), ``rpe_trans_rmse_m`` / ``rpe_rot_rmse_deg`` (1 frame at
        the 50 Hz control rate), ``sim_wall_ratio`` (simulated / wall-clock seconds).
    """
    from marsscene.runtime import (
        CameraConfig,
        LidarConfig,
        PursuitConfig,
        Route,
        RunConfig,
        ate,
        author_route,
        read_tum,
        rpe,
    )
    from marsscene.runtime.driver import drive
    from marsscene.runtime.sim import RoverSim, scene_obstacles
    from marsscene.seeding import stage_rng

    run = RunConfig(
        lidar=LidarConfig() if spec.lidar else None,
        camera=CameraConfig() if spec.camera else None,
    )
    sim = RoverSim(scene_dir, run=run, settle_s=0.0)
    if spec.route is not None:
        route = Route.from_trajectory(read_tum(spec.route))
    else:
        route = author_route(
            np.asarray(spec.waypoints, dtype=np.float64),
            sim.heightfield,
            max_slope_deg=spec.max_slope_deg,
            obstacles=scene_obstacles(sim),
        )
    if sim.rocks_kept[1]:  # simulate only the rocks the rover can meet or sense
        corridor = spec.corridor_m
        if run.lidar is not None:
            corridor = max(corridor, run.lidar.range_m[1])
        if run.camera is not None:
            corridor = max(corridor, run.camera.terrain_window_m / 2.0)
        sim = RoverSim(scene_dir, run=run, settle_s=0.0, contact_corridor_xy_m=route.xy_m,
                       contact_corridor_m=corridor)
    a, b = route.xy_m[0], route.xy_m[min(5, len(route.xy_m) - 1)]
    sim.settle_s = 3.0
    sim.reset(xy_m=(float(a[0]), float(a[1])), yaw_rad=math.atan2(b[1] - a[1], b[0] - a[0]))
    t0 = time.perf_counter()
    res = drive(
        sim,
        route=route,
        seconds=spec.seconds,
        out_dir=out_dir,
        rng=stage_rng(spec.noise_seed, "sensors"),
        pursuit=PursuitConfig(lookahead_m=spec.lookahead_m),
    )
    wall_s = time.perf_counter() - t0
    s = res.summary
    a_err = ate(res.odom, res.gt, align="se3")
    r_err = rpe(res.odom, res.gt, delta_frames=1)
    return {
        "distance_m": s["path_length_m"],
        "sim_time_s": s["sim_time_s"],
        "goal_reached": s["goal_reached"],
        "cross_track_rms_m": s.get("cross_track_rms_m", float("nan")),
        "ate_rmse_m": round(a_err.stats.rmse, 9),
        "rpe_trans_rmse_m": round(r_err.translation.rmse, 9),
        "rpe_rot_rmse_deg": round(r_err.rotation_deg.rmse, 9),
        "sim_wall_ratio": round(s["sim_time_s"] / max(wall_s, 1e-9), 3),
    }
