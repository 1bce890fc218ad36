"""KISS-ICP at a standing start on a paper-spec route: how far it is off after the first seconds,
per LiDAR model and KISS-ICP setting (issue 36).

Run: ``python perf/bench_kiss_start.py [SCENE_DIR] [SECONDS] [ROUTE_M] [MODELS] [MODES] [OUT]``
(defaults: the spec's main-crater scene, seed 1, built into a temporary folder; 60 s;
main-crater's route at its spec length, also for an empty ``ROUTE_M``; ``os1-64,os1-128``;
``default``). ``SCENE_DIR`` is a built main-crater scene (a cell's ``scene/`` of the paper
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
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[1]


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


def _report(run_dir: Path, model: str, mode: str) -> None:
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
    anchored = []
    for i in range(0, len(stamps), 50):
        true_m = (first @ _pose(gt, stamps[i]))[:3, 3]
        anchored.append(f"{stamps[i]:.0f} s {np.linalg.norm(true_m - poses[i, :3, 3]):.2f} m")
    print(f"{model:8s} {mode:10s} ATE {score.ate_rmse_m:.3f} m ({score.ate_percent:.2f} % of "
          f"{score.path_m:.1f} m), KISS-ICP path {score.estimated_path_m:.1f} m, "
          f"{seconds / len(stamps):.3f} s/scan", flush=True)
    print("   anchored error: " + ", ".join(anchored), flush=True)


def _scene(argv: list[str]) -> Path:
    if argv and argv[0]:
        return Path(argv[0])
    from _measure import paper_scene

    return paper_scene("main-crater")[0]


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    scene_dir = _scene(argv)
    seconds = float(argv[1]) if len(argv) > 1 else 60.0
    route_m = float(argv[2]) if len(argv) > 2 and argv[2] else None
    models = argv[3].split(",") if len(argv) > 3 else ["os1-64", "os1-128"]
    modes = argv[4].split(",") if len(argv) > 4 else ["default"]
    out = Path(argv[5]) if len(argv) > 5 else Path(tempfile.gettempdir()) / "bench_kiss_start"
    for model in models:
        run_dir = _drive(scene_dir, model, seconds, route_m, out / model)
        for mode in modes:
            _report(run_dir, model, mode)


if __name__ == "__main__":
    main(sys.argv[1:])
