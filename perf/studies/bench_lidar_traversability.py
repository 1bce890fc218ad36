"""The traversability-estimation baseline measured: the rover's LiDAR elevation map against the
ground truth (issue 66, :mod:`marsscene.benchmark.nav.estimate`).

Run: ``python perf/run.py lidar_traversability --size quick|full [--lidar os1-64]``.

Builds the embedded default scene (``marsscene build --seed 7``: rocks k from the default
config), drives the rover along a straight route through its centre with the LiDAR, grids every
point (posed by the ground truth) at 0.25 m and scores its traversability on the observed cells
against the scene's ground truth at 0.25 m: hazard IoU, cost AUROC, cells observed, the hazard
shares; and the wall time of each step.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param

PARAMS = (Param("seconds", float, "drive length (sim s)", quick=10.0, full=40.0),
          Param("lidar", str, "LiDAR model", quick="vlp16", full="os1-64"),
          Param("cell_m", float, "map cell (m)", quick=0.25, full=0.25))


def main(seconds: float, lidar: str, cell_m: float) -> dict[str, Any]:
    import marsscene as ms
    from marsscene.benchmark.nav.estimate import (
        lidar_map_points,
        lidar_traversability,
        score_estimate,
    )
    from marsscene.traversability import TraversabilityConfig
    from marsscene.traversability.scene import inputs_of_scene, scene_traversability

    out: dict[str, Any] = {"lidar": lidar, "seconds": seconds, "cell_m": cell_m}
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        scene = ms.build_scene(ms.SceneConfig(), seed=7)
        ms.write_scene(scene, Path(tmp) / "scene", formats=("mjcf",))
        out["build_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        truth = scene_traversability(inputs_of_scene(scene),
                                     config=TraversabilityConfig(cell_m=cell_m))
        out["truth_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        run = ms.RunConfig(lidar=ms.LidarConfig(model=lidar))
        ms.drive(Path(tmp) / "scene", waypoints=[[-20.0, 0.0], [20.0, 0.0]], seconds=seconds,
                 config=run, out_dir=Path(tmp) / "run")
        out["drive_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        points = lidar_map_points(Path(tmp) / "run")
        est, valid = lidar_traversability(points, cell_m=cell_m)
        score = score_estimate(est, valid, truth)
        out["estimate_s"] = time.perf_counter() - t0
    out.update({"points": len(points), **score.as_dict()})
    for key, value in out.items():
        print(f"{key:24s} {value:.4g}" if isinstance(value, float) else f"{key:24s} {value}")
    return out
