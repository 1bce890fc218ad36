"""The traversability-estimation baseline: the rover's own LiDAR elevation map, scored against
the ground truth.

A drive's LiDAR points (each posed at its firing time from the run's ground truth and the
LiDAR's mount, so a perfect localiser: the score is the map's, not the odometry's) are gridded
into an elevation map of ``cell_m`` cells (the mean height of the points in a cell; a cell with
fewer than ``min_points`` is unobserved), the unobserved cells filled from their nearest
observed one, and the result run through the same traversability model as the ground truth
(:func:`marsscene.traversability.compute`: slope, roughness, step, belly over the rover's
footprint; it knows no rocks but the relief they make in the map, and no soil). The estimate is
then scored on the observed cells (:mod:`marsscene.traversability.score`): hazard IoU and cost
AUROC against the ground truth sampled at the estimate's cell centres.

What the baseline cannot know: the terrain behind rocks and crests (unobserved, left out of the
score), the soil (the ground truth's slip term), and rocks narrower than a cell.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from scipy.spatial.transform import Rotation, Slerp

from marsscene.errors import RuntimeSimError
from marsscene.orbital import local_elevation_map
from marsscene.rover.config import RoverConfig
from marsscene.runs.tum import read_tum
from marsscene.terrain.heightfield import Heightfield
from marsscene.traversability import HAZARD_BITS, Traversability, TraversabilityConfig, compute
from marsscene.traversability.score import cost_auroc, hazard_iou

__all__ = ["EstimateScore", "lidar_map_points", "lidar_traversability", "score_estimate"]


def lidar_map_points(run_dir: str | os.PathLike[str]) -> NDArray[np.float64]:
    """Every LiDAR point of a run folder in the map frame (N, 3): each posed at its firing time
    (the scan's stamp plus the point's ``t``) by the ground truth and the LiDAR's mount."""
    from marsscene.benchmark.slam.kiss_icp import lidar_mount
    from marsscene.runs.runlog import RunLog, read_ply, run_rover

    run = RunLog(Path(run_dir))
    lidar = run.lidar
    if lidar is None:
        raise RuntimeSimError(f"{run_dir} has no LiDAR scans: drive with a LiDAR (--lidar)")
    gt = read_tum(Path(run_dir) / "gt.tum")
    rover = run_rover(json.loads((Path(run_dir) / "run.json").read_text(encoding="utf-8")))
    mount = lidar_mount(rover)
    slerp = Slerp(gt.timestamps_s, Rotation.from_quat(gt.quat_wxyz[:, [1, 2, 3, 0]]))
    parts = []
    for t0, f in zip(*lidar, strict=True):
        scan = read_ply(f)
        p = np.column_stack([scan["x"], scan["y"], scan["z"]]).astype(np.float64)
        t = t0 + (scan["t"].astype(np.float64) * 1e-9 if "t" in (scan.dtype.names or ())
                  else np.zeros(len(p)))
        t = np.clip(t, gt.timestamps_s[0], gt.timestamps_s[-1])
        p_base = p @ mount[:3, :3].T + mount[:3, 3]
        pos = np.column_stack([np.interp(t, gt.timestamps_s, gt.xyz_m[:, k]) for k in range(3)])
        parts.append(slerp(t).apply(p_base) + pos)
    return np.concatenate(parts) if parts else np.zeros((0, 3))


def lidar_traversability(points_xyz_m: ArrayLike, *, cell_m: float = 0.25, min_points: int = 3,
                         rover: RoverConfig | None = None
                         ) -> tuple[Traversability, NDArray[np.bool_]]:
    """The traversability of the elevation map of ``points_xyz_m`` (map frame) and the mask of
    its observed cells whose footprint lies inside the map (the module's docstring)."""
    local = local_elevation_map(points_xyz_m, cell_m=cell_m, min_points=min_points)
    seen = local.mask
    if not seen.any():
        raise RuntimeSimError(f"no cell of {cell_m} m holds {min_points} LiDAR points")
    nearest = ndimage.distance_transform_edt(~seen, return_distances=False, return_indices=True)
    z = local.z_m[tuple(nearest)].astype(np.float32)
    hf = Heightfield(z, float(cell_m), local.origin_xy_m)
    est = compute(hf, rover=rover, config=TraversabilityConfig(cell_m=cell_m))
    # a footprint that leaves the map is an "edge" hazard of the map, not of the terrain
    return est, seen & ((est.hazard_bits & HAZARD_BITS["edge"]) == 0)


@dataclass(frozen=True)
class EstimateScore:
    """An estimate's scores over its observed cells inside the ground truth's grid."""

    hazard_iou: float
    cost_auroc: float
    cells: int
    true_hazard_share: float
    predicted_hazard_share: float

    def as_dict(self) -> dict[str, Any]:
        return {"hazard_iou": self.hazard_iou, "cost_auroc": self.cost_auroc,
                "cells": self.cells, "true_hazard_share": self.true_hazard_share,
                "predicted_hazard_share": self.predicted_hazard_share}


def score_estimate(estimate: Traversability, valid: ArrayLike, truth: Traversability
                   ) -> EstimateScore:
    """Hazard IoU and cost AUROC of ``estimate`` (on its ``valid`` cells) against ``truth``,
    sampled at the estimate's cell centres (nearest cell)."""
    rows, cols = estimate.shape
    x = estimate.origin_xy_m[0] + estimate.cell_m * np.arange(cols)
    y = estimate.origin_xy_m[1] + estimate.cell_m * np.arange(rows)
    c = np.rint((x - truth.origin_xy_m[0]) / truth.cell_m).astype(np.int64)
    r = np.rint((y - truth.origin_xy_m[1]) / truth.cell_m).astype(np.int64)
    inside = ((r >= 0) & (r < truth.shape[0]))[:, None] & ((c >= 0) & (c < truth.shape[1]))
    ok = np.asarray(valid, dtype=bool) & inside
    rr, cc = np.meshgrid(np.clip(r, 0, truth.shape[0] - 1), np.clip(c, 0, truth.shape[1] - 1),
                         indexing="ij")
    true_hazard = truth.hazard[rr, cc]
    n = int(ok.sum())
    if n == 0:
        raise RuntimeSimError("the estimate has no observed cell inside the ground truth")
    return EstimateScore(hazard_iou(estimate.hazard, true_hazard, ok),
                         cost_auroc(estimate.cost, true_hazard, ok), n,
                         float(true_hazard[ok].mean()), float(estimate.hazard[ok].mean()))
