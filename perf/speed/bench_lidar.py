"""LiDAR: ray-cast speed per sensor model, and KISS-ICP (default configuration) on drives.

Run: ``python perf/run.py lidar`` (cast timings + the default-scene route of issue 21
per model), ``python perf/run.py lidar --mode cast`` (cast timings only: the terrain alone,
Embree vs the numpy march, then whole scans as a drive makes them: catalogue rocks, static
geoms, motion distortion, noise; and the time to build the Embree window), or
``python perf/run.py lidar --mode drive --scene SCENE --length-m L --models M`` with SCENE one of
``default``, ``mars-base``, ``main-crater``, ``grand-canyon`` (a square loop of LENGTH_M around
the scene centre, authored by the route planner) or ``mars-base-habitat`` (the loop around the
mars-base habitat, as the paper's Mars Base route; the plain loop of ``mars-base`` never sees
it: the habitat stands 420 m from the centre). Each drive is what a user types:
``marsscene build`` -> ``marsscene drive --lidar-model M --bag`` ->
``kiss_icp_pipeline --topic /rover/lidar/points RUN/bag``; the score is KISS-ICP's ATE
(SE(3)-aligned, lidar frame) against the ground truth. It also prints the drive's real-time
factor and how well the scans constrain horizontal motion (the smallest singular value of the
point-to-plane Jacobian against the true terrain, relative to the largest: a flat plain has
~0; walls and rocks raise it).
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param, names

os.environ.setdefault("MUJOCO_GL", "egl")

CACHE = Path(tempfile.gettempdir()) / "marsscene_bench_lidar"
MODELS = ("simple", "vlp16", "os1-64", "os1-128")
_ISSUE_ROUTE = "-10 -10\n10 -10\n10 10\n"
PARAMS = (Param("mode", str, "all: cast timings and drives; cast: timings only; drive: drives only",
                quick="cast", full="all", choices=("all", "cast", "drive")),
          Param("models", names, "LiDAR models, comma-separated", quick=("simple",), full=MODELS),
          Param("scene", str, "drive: default, a preset or mars-base-habitat", quick="default",
                full="default"),
          Param("length_m", float, "drive: the loop's length (m; the default scene drives the "
                "issue's 39.5 m route)", quick=40.0, full=40.0),
          Param("repeats", int, "whole scans timed per model", quick=2, full=10))


def _scene(name: str) -> Path:
    out = CACHE / f"scene-{name}"
    if not (out / "mjcf" / "scene.xml").is_file():
        cmd = ["marsscene", "build", "--seed", "7", "--out", str(out), "--format", "mjcf"]
        if name != "default":
            cmd += ["--preset", name]
        subprocess.run(cmd, check=True, capture_output=True)
    return out


def cast_timings(models: tuple[str, ...] = MODELS) -> list[dict[str, Any]]:
    """ms per scan of each model on the default scene (Embree and the numpy fallback)."""
    import numpy as np

    from marsscene.rover.config import RunConfig
    from marsscene.rover.lidar import LidarConfig
    from marsscene.sensors.lidar import Lidar
    from marsscene.sensors.raycast import TerrainCaster
    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(_scene("default"), run=RunConfig())
    rot = sim.data.site_xmat[sim.lidar_site].reshape(3, 3)
    origin = sim.data.site_xpos[sim.lidar_site].copy()
    print(f"{'model':8s} {'rays':>6s} {'embree ms':>10s} {'numpy ms':>9s} "
          f"{'|embree-numpy| p95 mm':>22s}")
    rows = []
    for model in models:
        lidar = Lidar(LidarConfig(model=model, range_noise_sigma_m=0.0))
        dirs = lidar.dirs_sensor @ rot.T
        rng_m = lidar.spec.range_m
        fast = TerrainCaster(sim.heightfield, rng_m[1], use_embree=True)
        slow = TerrainCaster(sim.heightfield, rng_m[1], use_embree=False)
        fast.cast(origin, dirs, rng_m)  # builds the window
        t0 = time.perf_counter()
        for _ in range(5):
            a, _ = fast.cast(origin, dirs, rng_m)
        t_fast = (time.perf_counter() - t0) / 5
        t0 = time.perf_counter()
        b, _ = slow.cast(origin, dirs, rng_m)
        t_slow = time.perf_counter() - t0
        ok = np.isfinite(a) & np.isfinite(b)
        p95 = float(np.percentile(np.abs(a[ok] - b[ok]), 95)) * 1e3 if ok.any() else float("nan")
        print(f"{model:8s} {len(dirs):6d} {t_fast * 1e3:10.1f} {t_slow * 1e3:9.0f} {p95:22.1f}")
        rows.append({"case": "terrain cast", "model": model, "rays": len(dirs),
                     "embree_ms": t_fast * 1e3, "numpy_ms": t_slow * 1e3, "p95_gap_mm": p95})
    return rows


def scan_timings(repeats: int = 10, models: tuple[str, ...] = MODELS) -> list[dict[str, Any]]:
    """ms per whole scan of each model as the drive casts it (default scene, rover moving)."""
    import numpy as np

    from marsscene.rover.config import RunConfig
    from marsscene.rover.lidar import LidarConfig
    from marsscene.sensors.camera_world import read_rock_catalog
    from marsscene.sensors.lidar import Lidar
    from marsscene.sim.rover_sim import RoverSim

    scene = _scene("default")
    sim = RoverSim(scene, run=RunConfig())
    rocks = read_rock_catalog(scene)
    sim.apply(0.5, 0.1)
    sim.advance(700)
    twist = sim.site_twist(sim.lidar_site)
    print(f"{'model':8s} {'rays':>6s} {'returns':>8s} {'build s':>8s} "
          f"{'scan ms (median, min)':>22s}")
    rows = []
    for model in models:
        lidar = Lidar(LidarConfig(model=model), rng=np.random.default_rng(0), rocks=rocks)
        t0 = time.perf_counter()
        scan = lidar.prepare(sim.model, sim.data, sim.lidar_site, sim.heightfield,
                             twist=twist)()  # builds the window
        build = time.perf_counter() - t0
        times = []
        for _ in range(repeats):
            cast = lidar.prepare(sim.model, sim.data, sim.lidar_site, sim.heightfield,
                                 twist=twist)
            t0 = time.perf_counter()
            cast()
            times.append(time.perf_counter() - t0)
        print(f"{model:8s} {len(lidar.t_s):6d} {len(scan['range_m']):8d} {build:8.2f} "
              f"{np.median(times) * 1e3:12.1f}, {min(times) * 1e3:5.1f}")
        rows.append({"case": "whole scan", "model": model, "rays": len(lidar.t_s),
                     "returns": len(scan["range_m"]), "build_s": build,
                     "scan_ms_median": float(np.median(times)) * 1e3,
                     "scan_ms_min": min(times) * 1e3})
    return rows


def _loop_waypoints(side_m: float, centre: tuple[float, float] = (0.0, 0.0)) -> str:
    h, (cx, cy) = side_m / 2.0, centre
    return "\n".join(f"{cx + x:.1f} {cy + y:.1f}" for x, y in
                     [(-h, -h), (h, -h), (h, h), (-h, h), (-h, -h + 1.0)]) + "\n"


def drive(scene: str, length_m: float, model: str = "os1-64", camera: bool = False) -> dict:
    """One drive + KISS-ICP; returns the figures (also printed as one JSON line)."""
    from marsscene.benchmark.routes import asset_xy_m
    from marsscene.benchmark.slam.kiss_icp import run_kiss_icp, score_lidar_odometry
    from marsscene.runs.runlog import RunLog

    around = scene.endswith("-habitat")  # mars-base-habitat: the loop circles the habitat
    scene_dir = _scene(scene.removesuffix("-habitat"))
    run_dir = CACHE / f"run-{scene}-{int(length_m)}-{model}{'-cam' if camera else ''}"
    wp = CACHE / f"wp-{scene}-{int(length_m)}.txt"
    centre = asset_xy_m(scene_dir, "habitat") if around else (0.0, 0.0)
    # the default scene: the issue's route (-10,-10) -> (10,-10) -> (10,10), 39.5 m
    wp.write_text(_ISSUE_ROUTE if scene == "default" else _loop_waypoints(length_m / 4.0,
                                                                          centre))
    cmd = ["marsscene", "drive", str(scene_dir), "--waypoints", str(wp), "--lidar-model",
           model, "--bag", "--overwrite", "--out", str(run_dir)]
    if camera:
        cmd += ["--camera"]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    run = RunLog(run_dir)
    sim_s = float(run.meta["summary"]["sim_time_s"])
    t0 = time.perf_counter()
    est = run_kiss_icp(run_dir / "bag")
    kiss_s = time.perf_counter() - t0
    score = score_lidar_odometry(est, run)
    row = {"scene": scene, "model": model, "path_m": round(score.path_m, 1),
           "ate_m": round(score.ate_rmse_m, 3), "ate_pct": round(score.ate_percent, 2),
           "est_path_m": round(score.estimated_path_m, 1), "status": score.status,
           "drive_rtf": round(sim_s / wall, 2), "kiss_s": round(kiss_s, 1)}
    print(json.dumps(row), flush=True)
    return row


def main(mode: str, models: tuple[str, ...], scene: str, length_m: float,
         repeats: int) -> list[dict[str, Any]]:
    rows = []
    if mode in ("all", "cast"):
        rows += cast_timings(models) + scan_timings(repeats, models)
    if mode in ("all", "drive"):
        rows += [{"case": "drive", **drive(scene, length_m, model)} for model in models]
    return rows

