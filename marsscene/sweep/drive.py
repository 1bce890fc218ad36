"""Drive one built cell scene and evaluate wheel odometry against ground truth (ATE/RPE).

Drives with :func:`marsscene.drive`, as ``marsscene drive`` does (route authoring, contact
corridor, settling, pure pursuit), then :func:`~marsscene.runtime.ate` /
:func:`~marsscene.runtime.rpe`. ``mujoco`` is imported only when a cell is driven.
"""

from __future__ import annotations

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
    import marsscene as ms
    from marsscene.runtime import ate, rpe

    run = ms.drive(
        scene_dir,
        route=spec.route,
        waypoints=spec.waypoints if spec.route is None else None,
        seconds=spec.seconds,
        config=spec.run_config(),
        options=spec.options,
        export=ms.ExportOptions(bag=ms.BagOptions() if spec.bag else None),
        out_dir=out_dir,
        seed=spec.noise_seed,
    )
    res = run.result
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
        "sim_wall_ratio": round(s["sim_time_s"] / max(run.wall_s, 1e-9), 3),
        "bag_s": round(run.export_s, 3) if spec.bag else float("nan"),
    }
