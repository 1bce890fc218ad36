"""Drive one built cell scene and evaluate wheel odometry against ground truth (ATE/RPE).

Calls the runtime exactly as ``marsscene drive`` does (route authoring, contact corridor,
settling, pure pursuit) and then :func:`~marsscene.runtime.ate` / :func:`~marsscene.runtime.rpe`.
``mujoco`` is imported only when a cell is driven.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from marsscene.sweep.spec import DriveSpec

__all__ = ["drive_cell"]


def drive_cell(scene_dir: Path, spec: DriveSpec, out_dir: Path) -> dict[str, Any]:
    """Drive the rover on ``scene_dir`` as ``spec`` says; logs go to ``out_dir``.

    Returns
    -------
    dict
        ``distance_m``, ``sim_time_s``, ``goal_reached``, ``cross_track_rms_m``,
        ``ate_rmse_m`` (SE(3)-aligned), ``rpe_trans_rmse_m`` / ``rpe_rot_rmse_deg`` (1 frame at
        the 50 Hz control rate), ``sim_wall_ratio`` (simulated / wall-clock seconds),
        ``bag_s`` (seconds to write ``out_dir/bag`` with ``bag = true``, else NaN).
    """
    from marsscene.runtime import (
        CameraConfig,
        LidarConfig,
        PursuitConfig,
        Route,
        RunConfig,
        ate,
        read_tum,
        rpe,
    )
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive
    from marsscene.sim.mission import prepare_drive

    run = RunConfig(
        lidar=LidarConfig() if spec.lidar else None,
        camera=CameraConfig() if spec.camera else None,
    )
    sim, route = prepare_drive(
        scene_dir, run,
        route=Route.from_trajectory(read_tum(spec.route)) if spec.route is not None else None,
        waypoints_xy_m=spec.waypoints if spec.route is None else None,
        max_slope_deg=spec.max_slope_deg, corridor_m=spec.corridor_m,
    )
    from marsscene.runs.export.bag_images import JpegCache  # no rosbags import

    cache = JpegCache.fresh(out_dir) if spec.bag and spec.camera else None
    try:
        t0 = time.perf_counter()
        res = drive(
            sim,
            route=route,
            seconds=spec.seconds,
            out_dir=out_dir,
            rng=stage_rng(spec.noise_seed, "sensors"),
            pursuit=PursuitConfig(lookahead_m=spec.lookahead_m),
            jpeg_cache=cache,
        )
        wall_s = time.perf_counter() - t0
        bag_s = float("nan")
        if spec.bag:
            from marsscene.runs.export.bag import write_bag

            t1 = time.perf_counter()
            write_bag(out_dir, jpeg_cache=cache)
            bag_s = time.perf_counter() - t1
    finally:
        if cache is not None:
            cache.remove()
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
        "bag_s": round(bag_s, 3),
    }
