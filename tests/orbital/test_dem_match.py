"""``dem-correlation``: a local elevation map cut from a procedural terrain found again in the
orbital DTM made from it (PSF and noise applied) from a prior 20 m and 5 degrees off; low
confidence on a featureless map; the local map from LiDAR scans and their poses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import marsscene as ms
from marsscene.errors import ConfigError
from marsscene.orbital import (
    OrbitalMap,
    local_elevation_map,
    match_dem,
    points_in_frame,
    pose_matrix,
    procedural_orbital_map,
)
from marsscene.terrain.heightfield import Heightfield

RADIUS_M = 30.0  # the local map's reach: a few LiDAR scans around the rover


@pytest.fixture(scope="module")
def world() -> tuple[Heightfield, OrbitalMap]:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [200, 200]},
                                    "craters": {"enabled": False}, "rocks": {"enabled": False},
                                    "lighting": {"enabled": False}})
    hf = ms.build_scene(cfg, seed=3).heightfield
    return hf, procedural_orbital_map(hf, None, 3, image=False)


def _patch(hf: Heightfield, x: float, y: float, yaw: float, rng: np.random.Generator
           ) -> np.ndarray:
    """The terrain's posts within RADIUS_M of (x, y) in the frame at (x, y, yaw), with a 2 cm
    range-like noise, a third of them dropped, and an arbitrary vertical datum."""
    gx, gy = hf.grid_xy()
    xx, yy = np.meshgrid(gx, gy)
    sel = (np.hypot(xx - x, yy - y) < RADIUS_M) & (rng.random(xx.shape) > 1 / 3)
    dx, dy = xx[sel] - x, yy[sel] - y
    c, s = math.cos(yaw), math.sin(yaw)
    z = hf.z_m[sel].astype(np.float64) + 17.0 + rng.normal(0.0, 0.02, dx.size)
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, z])


def _yaw_err_deg(a: float, b: float) -> float:
    return abs(math.degrees((a - b + math.pi) % (2 * math.pi) - math.pi))


def test_recovers_offset_and_heading_from_a_20_m_5_deg_prior(world) -> None:
    hf, omap = world
    rng = np.random.default_rng(0)
    x, y, yaw = 12.3, -7.6, math.radians(131.0)
    local = local_elevation_map(_patch(hf, x, y, yaw, rng))
    prior = (x + 20.0 * math.cos(0.7), y + 20.0 * math.sin(0.7), yaw - math.radians(5.0))
    m = match_dem(local, omap, prior, search_radius_m=25.0)
    assert math.hypot(m.x_m - x, m.y_m - y) < 1.5  # the DTM's correlated noise: see below
    assert _yaw_err_deg(m.yaw_rad, yaw) < 1.0
    assert m.peak_ncc > 0.8 and m.confidence > 0.4
    assert m.observed_cells == local.observed > 2500


def test_a_featureless_map_gives_low_confidence() -> None:
    flat = Heightfield(np.zeros((401, 401), np.float32), 0.5, (-100.0, -100.0))
    omap = procedural_orbital_map(flat, None, 3, image=False)  # the orbital noise alone
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(-30, 30, 40000), rng.uniform(-30, 30, 40000),
                           rng.normal(0.0, 0.02, 40000)])
    m = match_dem(local_elevation_map(pts, radius_m=RADIUS_M), omap, (0.0, 0.0, 0.0))
    assert m.peak_ncc < 0.3 and m.confidence < 0.1


@settings(max_examples=15, deadline=None)
@example(dx=0.0, dy=0.0, yaw_deg=-98.625, dyaw_deg=1.5)  # the worst heading found: 2.53 deg
@given(dx=st.floats(-20.0, 20.0), dy=st.floats(-20.0, 20.0),
       yaw_deg=st.floats(-180.0, 180.0), dyaw_deg=st.floats(-5.0, 5.0))
def test_matches_anywhere_in_the_search_window(world, dx: float, dy: float, yaw_deg: float,
                                               dyaw_deg: float) -> None:
    hf, omap = world
    x, y, yaw = 5.0, -5.0, math.radians(yaw_deg)
    local = local_elevation_map(_patch(hf, x, y, yaw, np.random.default_rng(7)))
    m = match_dem(local, omap, (x + dx, y + dy, yaw + math.radians(dyaw_deg)),
                  search_radius_m=25.0)
    # every prior in the window gives about a success at the strict threshold, 1 m / 2 deg:
    # the error here is the orbital noise's, which is correlated over 3 m (as a stereo DTM's),
    # so a whole patch of posts errs together and the worst headings found reach 2.5 deg
    assert math.hypot(m.x_m - x, m.y_m - y) < 1.5
    assert _yaw_err_deg(m.yaw_rad, yaw) < 3.0


def test_local_map_from_scans_and_poses() -> None:
    # two scans of the plane z = 0.1 x (local frame), each seen from its own sensor pose
    lattice = -9.875 + 0.25 * np.arange(80)  # 4 x 4 points in each 1 m cell, symmetric about it
    gx, gy = np.meshgrid(lattice, lattice)
    local_pts = np.column_stack([gx.ravel(), gy.ravel(), 0.1 * gx.ravel()])
    poses = pose_matrix([[1.0, 2.0, 1.5], [-3.0, 0.5, 1.4]],
                        [[math.cos(0.3), 0, 0, math.sin(0.3)], [1.0, 0.0, 0.0, 0.0]])
    halves = np.array_split(local_pts, 2)
    scans = [(p - t[:3, 3]) @ t[:3, :3] for p, t in zip(halves, poses, strict=True)]
    back = points_in_frame(scans, poses)
    np.testing.assert_allclose(back, local_pts, atol=1e-9)
    lm = local_elevation_map(back, cell_m=1.0, min_points=3)
    x, y = lm.cell_xy()
    assert lm.cell_m == 1.0 and lm.origin_xy_m == (-10.0, -10.0)
    inner = (np.abs(x) < 9.5) & (np.abs(y) < 9.5)  # whole cells (the edges hold half cells)
    assert lm.mask[inner].all()
    np.testing.assert_allclose(lm.z_m[inner], 0.1 * x[inner], atol=1e-9)
    assert lm.observed == 21 * 21  # the edge cells hold 2 x 4 points, the corners 2 x 2
    with pytest.raises(ConfigError, match="2 scans but 1 poses"):
        points_in_frame(scans, poses[:1])
