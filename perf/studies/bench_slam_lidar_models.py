"""Which LiDAR for the paper's SLAM spec: KISS-ICP with ``os1-64`` and ``os1-128`` on short
routes of the three paper scenes (issue 36).

Run: ``python perf/run.py slam_lidar_models [--length-m L] [--out DIR] [--models A,B]
[--scenes A,B]`` (full: 150 m, a temporary folder, ``os1-64,os1-128``, every scene of the spec).
For each model the shipped ``docs/examples/benchmark_slam_paper.toml`` runs with its routes
shortened to ``--length-m``
(same shapes: the loop around the habitat, the crater loop, the canyon out-and-back), the LiDAR
cell only (tau 0.5, no camera), methods wheel odometry and KISS-ICP, 2 workers; a resumed
benchmark (``--resume``) reuses finished cells, so an interrupted run continues. Prints per
scene and model: ATE (m, % of path), KISS-ICP's run time, the bag's size per km and the drive
time.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import time
from pathlib import Path

from perf.suite import Param, names, optional

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[2]
PARAMS = (Param("length_m", float, "route length of each scene (m)", quick=20.0, full=150.0),
          Param("out", optional(Path), "benchmark folder (none: the temporary folder's)",
                quick=None, full=None),
          Param("models", names, "LiDAR models, comma-separated", quick=("os1-64",),
                full=("os1-64", "os1-128")),
          Param("scenes", names, "paper-spec scenes, comma-separated (none: every one)",
                quick=("main-crater",), full=()))


def _spec(model: str, length_m: float, scenes: tuple[str, ...] | None = None):  # type: ignore[no-untyped-def]
    from marsscene.benchmark.slam.spec import SlamSpec

    spec = SlamSpec.from_toml(ROOT / "docs" / "examples" / "benchmark_slam_paper.toml")
    spec = spec.shortened(length_m=length_m, scenes=scenes)
    sensors = {"lidar": {"model": model}, "bag": False}
    methods = tuple(dataclasses.replace(m, seeds=None) for m in spec.methods
                    if m.kind in ("wheel-odometry", "kiss-icp"))  # one scene seed: the LiDAR's
    return dataclasses.replace(spec, tau=(0.5,), lidar_tau=0.5, sensors=sensors,
                               methods=methods, name=f"lidar-{model}")


def _size_mb(folder: Path) -> float:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file()) / 1e6


def main(length_m: float, out: Path | None, models: tuple[str, ...],
         scenes: tuple[str, ...]) -> list[dict[str, object]]:
    from marsscene.benchmark.slam.run import run_slam_benchmark

    out = out or Path(tempfile.gettempdir()) / "bench_lidar_models"
    figures: list[dict[str, object]] = []
    for model in models:
        t0 = time.perf_counter()
        res = run_slam_benchmark(_spec(model, length_m, scenes or None), out / model,
                                 workers=2, resume=True, report=False)
        wall = time.perf_counter() - t0
        for cell in res.cells:
            scene = cell["params"]["scene"]
            drive = cell.get("drive") or {}
            rows = {r["method"]: r for r in res.rows if r["scene"] == scene}
            k, w = rows.get("kiss-icp", {}), rows.get("wheel-odom", {})
            bag = out / model / "cells" / cell["cell_id"] / "drive" / "bag"
            km = (drive.get("path_length_m") or 1.0) / 1000.0
            print(f"lidar {model:8s} {scene:13s} path {drive.get('path_length_m', 0):6.1f} m: "
                  f"KISS-ICP {k.get('status')} ATE {k.get('ate_rmse_m', float('nan')):.3f} m "
                  f"({k.get('ate_pct_of_path', float('nan')):.3f} %) in "
                  f"{k.get('t_method_s', float('nan')):.0f} s; wheel ATE "
                  f"{w.get('ate_rmse_m', float('nan')):.3f} m; bag "
                  f"{_size_mb(bag) / km:.0f} MB/km; drive {drive.get('t_drive_s', 0):.0f} s",
                  flush=True)
            figures.append({"model": model, "scene": scene,
                            "path_m": drive.get("path_length_m"),
                            "kiss_status": k.get("status"), "kiss_ate_m": k.get("ate_rmse_m"),
                            "kiss_ate_pct": k.get("ate_pct_of_path"),
                            "kiss_s": k.get("t_method_s"), "wheel_ate_m": w.get("ate_rmse_m"),
                            "bag_mb_per_km": _size_mb(bag) / km,
                            "drive_s": drive.get("t_drive_s")})
        print(f"lidar {model}: {wall:.0f} s wall in all (finished cells reused)", flush=True)
    return figures

