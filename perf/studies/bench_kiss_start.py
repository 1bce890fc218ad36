"""KISS-ICP at a standing start on a paper-spec route: how far it is off after the first seconds,
per LiDAR model and KISS-ICP setting (issue 36).

Run: ``python perf/run.py kiss_start [--scene DIR] [--seconds S] [--route-m M] [--models A,B]
[--modes A,B] [--out DIR]`` (full: the spec's main-crater scene, seed 1, built into a temporary
folder; 60 s; main-crater's route at its spec length; ``os1-64,os1-128``; ``default``).
``--scene`` is a built main-crater scene (a cell's ``scene/`` of the paper
spec, or ``marsscene build --preset main-crater --seed 1``). For each
model the rover drives the first ``SECONDS`` of the spec's main-crater route (``ROUTE_M``
long, automatic loop), LiDAR only, ``ln200s`` noise, the scans kept as PLYs; KISS-ICP (its
Python API, ``kiss_icp_pipeline``'s defaults) then registers them once per mode:

* ``default``: KISS-ICP as the pipeline runs it;
* ``fixed=X``: ``adaptive_threshold.fixed_threshold = X`` m (its authors' advice for
  standstill lock);
* ``wheel``: before each scan the constant-velocity prediction (``last_delta``) is replaced by
  the wheel odometry's step, moved to the LiDAR frame.

Prints per model and mode: ATE after SE(3) alignment, KISS-ICP's path, and the anchored error
(KISS-ICP's position against the true ``lidar_link`` displacement, both in the first scan's
frame) every 5 s.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from perf.suite import Param, names, optional

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[2]
PARAMS = (Param("scene", optional(Path), "a built main-crater scene (none: the paper spec's, "
                "built once)", quick=None, full=None),
          Param("seconds", float, "simulated seconds from the standing start", quick=5.0,
                full=60.0),
          Param("route_m", optional(float), "route length (m; none: the spec's)", quick=None,
                full=None),
          Param("models", names, "LiDAR models, comma-separated", quick=("os1-64",),
                full=("os1-64", "os1-128")),
          Param("modes", names, "KISS-ICP settings: default, fixed=X, wheel", quick=("default",),
                full=("default",)),
          Param("out", optional(Path), "drive folders (none: the temporary folder's)", quick=None,
                full=None))


def _drive(scene_dir: Path, model: str, seconds: float, route_m: float | None, out: Path) -> Path:
    import marsscene as ms
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.benchmark.slam.spec import SlamSpec
    from marsscene.sim.world import load_world

    spec = SlamSpec.from_toml(ROOT / "docs" / "examples" / "benchmark_slam_paper.toml")
    spec = spec.shortened(length_m=route_m, scenes=("main-crater",))
    world = load_world(scene_dir)
    route = auto_route(centred_on_asset(spec.scenes[0].route, scene_dir), world.heightfield,
                       world.obstacles)
    run = spec.run_config(lidar=True, camera=False)
    run = dataclasses.replace(run, lidar=dataclasses.replace(run.lidar, model=model))
    shutil.rmtree(out, ignore_errors=True)
    ms.drive(scene_dir, route=route, config=run, out_dir=out, seed=spec.noise_seed,
             seconds=seconds, export=ms.ExportOptions(lidar_files=True))
    return out


def _pose(traj, t: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    i = int(np.argmin(np.abs(traj.timestamps_s - t)))
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_quat(traj.quat_xyzw[i]).as_matrix()
    pose[:3, 3] = traj.xyz_m[i]
    return pose


def _register(run_dir: Path, mode: str) -> tuple[np.ndarray, list[float], float]:
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP
    from scipy.spatial.transform import Rotation

    from marsscene.rover.geometry import sensor_mounts
    from marsscene.runs.runlog import RunLog, read_ply

    run = RunLog(run_dir)
    if run.lidar is None:
        raise SystemExit(f"{run_dir}: the drive stored no LiDAR scans")
    stamps, files = run.lidar
    config = load_config(None)
    if mode.startswith("fixed="):
        config.adaptive_threshold.fixed_threshold = float(mode.split("=", 1)[1])
    odometry = KissICP(config)
    (mx, my, mz), pitch = sensor_mounts(run.rover)["lidar"]
    mount = np.eye(4)
    mount[:3, :3] = Rotation.from_euler("y", pitch).as_matrix()
    mount[:3, 3] = (mx, my, mz)
    poses, previous, t0 = [], None, time.perf_counter()
    for t, path in zip(stamps, files, strict=True):
        rec = read_ply(path)
        wheel = _pose(run.odom, t) @ mount
        if mode == "wheel" and previous is not None:
            odometry.last_delta = np.linalg.inv(previous) @ wheel
        previous = wheel
        xyz = np.column_stack([rec["x"], rec["y"], rec["z"]]).astype(np.float64)
        odometry.register_frame(xyz, rec["t"].astype(np.float64))
        poses.append(odometry.last_pose.copy())
    return np.stack(poses), list(stamps), time.perf_counter() - t0


def _report(run_dir: Path, model: str, mode: str) -> dict[str, object]:
    from scipy.spatial.transform import Rotation

    from marsscene.benchmark.slam.kiss_icp import lidar_ground_truth, score_lidar_odometry
    from marsscene.runs.runlog import RunLog
    from marsscene.runs.tum import Trajectory

    poses, stamps, seconds = _register(run_dir, mode)
    run = RunLog(run_dir)
    est = Trajectory(np.asarray(stamps), poses[:, :3, 3],
                     Rotation.from_matrix(poses[:, :3, :3]).as_quat())
    score = score_lidar_odometry(est, run)
    gt = lidar_ground_truth(run.gt, run.rover)
    first = np.linalg.inv(_pose(gt, stamps[0]))
    anchored, anchored_m = [], {}
    for i in range(0, len(stamps), 50):
        true_m = (first @ _pose(gt, stamps[i]))[:3, 3]
        err_m = float(np.linalg.norm(true_m - poses[i, :3, 3]))
        anchored.append(f"{stamps[i]:.0f} s {err_m:.2f} m")
        anchored_m[f"{stamps[i]:.0f}"] = err_m
    print(f"{model:8s} {mode:10s} ATE {score.ate_rmse_m:.3f} m ({score.ate_percent:.2f} % of "
          f"{score.path_m:.1f} m), KISS-ICP path {score.estimated_path_m:.1f} m, "
          f"{seconds / len(stamps):.3f} s/scan", flush=True)
    print("   anchored error: " + ", ".join(anchored), flush=True)
    return {"model": model, "mode": mode, "ate_m": score.ate_rmse_m, "ate_pct": score.ate_percent,
            "path_m": score.path_m, "kiss_path_m": score.estimated_path_m,
            "s_per_scan": seconds / len(stamps), "anchored_error_m": anchored_m}


def _scene(scene: Path | None) -> Path:
    if scene is not None:
        return scene
    from perf._measure import paper_scene

    return paper_scene("main-crater")[0]


def main(scene: Path | None, seconds: float, route_m: float | None, models: tuple[str, ...],
         modes: tuple[str, ...], out: Path | None) -> list[dict[str, object]]:
    scene_dir = _scene(scene)
    out = out or Path(tempfile.gettempdir()) / "bench_kiss_start"
    rows = []
    for model in models:
        run_dir = _drive(scene_dir, model, seconds, route_m, out / model)
        rows += [_report(run_dir, model, mode) for mode in modes]
    return rows

