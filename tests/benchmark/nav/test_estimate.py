"""The LiDAR elevation map's traversability, the estimation baseline: it finds a block the
ground truth calls a hazard, its score is the scorer's, and a run's points are posed right."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.benchmark.nav.estimate import (
    lidar_map_points,
    lidar_traversability,
    score_estimate,
)
from marsscene.terrain.heightfield import Heightfield
from marsscene.traversability import TraversabilityConfig, compute


def _terrain() -> Heightfield:
    z = np.zeros((121, 121), np.float32)  # 30 m at 0.25 m posts, origin (-15, -15)
    z[50:60, 70:80] = 0.8  # a 2.5 m block, taller than any step or belly the rover clears
    return Heightfield(z, 0.25, (-15.0, -15.0))


def _points(hf: Heightfield, spacing_m: float, rng: np.random.Generator) -> np.ndarray:
    """Points on the terrain at random places, ``spacing_m`` apart on average, 1 cm noise,
    none beyond 12 m of the centre (an unobserved ring left out of the score)."""
    n = int((24.0 / spacing_m) ** 2)
    xy = rng.uniform(-12.0, 12.0, (n, 2))
    col = np.rint((xy[:, 0] - hf.origin_xy_m[0]) / hf.cell_size_m).astype(int)
    row = np.rint((xy[:, 1] - hf.origin_xy_m[1]) / hf.cell_size_m).astype(int)
    return np.column_stack([xy, hf.z_m[row, col] + rng.normal(0.0, 0.01, n)])


def test_the_lidar_map_finds_the_block_the_ground_truth_calls_a_hazard():
    hf = _terrain()
    truth = compute(hf, config=TraversabilityConfig(cell_m=0.25))
    est, seen = lidar_traversability(_points(hf, 0.08, np.random.default_rng(0)))
    score = score_estimate(est, seen, truth)
    # the 24 m square observed, less the band where the footprint leaves the map
    assert 0.6 * 96**2 < score.cells < 0.9 * 96**2
    assert score.hazard_iou > 0.8 and score.cost_auroc > 0.95
    assert score.true_hazard_share == pytest.approx(score.predicted_hazard_share, rel=0.25)
    _, seen_sparse = lidar_traversability(_points(hf, 0.6, np.random.default_rng(0)))
    assert seen_sparse.sum() < 0.6 * seen.sum()  # a sparse scan observes fewer cells


def test_flat_ground_has_no_hazard_and_a_scorer_that_says_nan_iou():
    hf = Heightfield(np.zeros((121, 121), np.float32), 0.25, (-15.0, -15.0))
    truth = compute(hf, config=TraversabilityConfig(cell_m=0.25))
    est, seen = lidar_traversability(_points(hf, 0.1, np.random.default_rng(1)))
    score = score_estimate(est, seen, truth)
    assert not est.hazard[seen].any() and np.isnan(score.hazard_iou)  # nothing to overlap


def test_a_runs_points_lie_on_the_ground_it_drove(flat_scene: Path, tmp_path: Path):
    run = ms.RunConfig(lidar=ms.LidarConfig(model="vlp16"))
    ms.drive(flat_scene, command=(0.4, 0.2), seconds=1.0, config=run, out_dir=tmp_path / "r")
    p = lidar_map_points(tmp_path / "r")
    ground = p[np.hypot(p[:, 0], p[:, 1]) < 12.0]  # the plane z = 0, away from its edges
    assert len(ground) > 5000
    assert np.median(np.abs(ground[:, 2])) < 0.02 and np.percentile(np.abs(ground[:, 2]),
                                                                     95) < 0.06
