"""The LiDAR's one-scene Embree cast: the disc window is exact wherever the sensor is inside
its margin, small rocks stay in reach, and the lean path matches the full-size one."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.sensors.raycast import TerrainCaster, embree_available
from marsscene.sensors.rock_mesh import SMALL_ROCK_REACH_M
from marsscene.terrain.heightfield import Heightfield

needs_embree = pytest.mark.skipif(not embree_available(), reason="embreex not installed")

RANGE_M = (0.5, 60.0)


def _hills() -> Heightfield:
    """240 m x 240 m at 0.5 m: rolling hills of a few metres and one 12 m mound."""
    x = np.arange(481) * 0.5
    xx, yy = np.meshgrid(x, x)
    z = 2.0 * np.sin(xx / 17.0) * np.cos(yy / 23.0) + 12.0 * np.exp(
        -((xx - 170.0) ** 2 + (yy - 120.0) ** 2) / 300.0)
    return Heightfield(z.astype(np.float32), 0.5)


def _rocks(hf: Heightfield, n: int, d_m: tuple[float, float], seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(5.0, 235.0, (n, 2))
    d = rng.uniform(*d_m, n)
    z = hf.sample(xy[:, 0], xy[:, 1]) - 0.1 * d
    return np.column_stack([np.arange(n), xy, z, d, 0.6 * d])


def _wall() -> tuple[np.ndarray, np.ndarray]:
    """One large static triangle, 8 m tall (an asset)."""
    v = np.array([[140.0, 95.0, -5.0], [140.0, 135.0, -5.0], [140.0, 115.0, 8.0]], np.float32)
    return v, np.array([[0, 1, 2]], np.int32)


def _rays(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    az = rng.uniform(-np.pi, np.pi, n)
    el = np.radians(rng.uniform(-25.0, 25.0, n))
    return np.column_stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


def _caster(hf: Heightfield, rocks: np.ndarray) -> TerrainCaster:
    return TerrainCaster(hf, RANGE_M[1], rocks=rocks, static=_wall(), margin_m=30.0,
                         use_embree=True)


@needs_embree
def test_the_window_is_exact_anywhere_inside_its_margin():
    hf = _hills()
    rocks = _rocks(hf, 3000, (0.3, 2.0), 4)  # large rocks only: the window holds them all
    dirs = _rays(30000, 5)
    moved = _caster(hf, rocks)
    moved.cast_hits(np.array([120.0, 120.0, 3.0]), dirs[:10], RANGE_M)
    start = moved._centre.copy()
    origin = np.array([141.0, 99.0, 3.0])  # 29.7 m from the window's centre: no rebuild
    a = moved.cast_hits(origin, dirs, RANGE_M)
    np.testing.assert_array_equal(moved._centre, start)
    b = _caster(hf, rocks).cast_hits(origin, dirs, RANGE_M)  # a window centred on it
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_allclose(a[1], b[1], atol=1e-4)
    # past the margin the window follows the sensor
    moved.cast_hits(np.array([160.0, 120.0, 3.0]), dirs[:10], RANGE_M)
    np.testing.assert_array_equal(moved._centre, [160.0, 120.0])


@needs_embree
def test_small_rocks_within_reach_of_the_sensor_are_cast():
    hf = Heightfield(np.zeros((481, 481), np.float32), 0.5)
    caster = TerrainCaster(hf, RANGE_M[1], margin_m=30.0, use_embree=True,
                           rocks=np.array([[7.0, 120.0 + 29.0 + SMALL_ROCK_REACH_M - 1.0, 120.0,
                                            -0.05, 0.25, 0.2]]))
    caster.cast_hits(np.array([120.0, 120.0, 1.0]), _rays(10, 6), RANGE_M)  # the window
    origin = np.array([149.0, 120.0, 0.1])  # 29 m from the centre, rock 39 m ahead
    t, n = caster.cast(origin, np.array([[1.0, 0.0, 0.0]]), RANGE_M)
    assert 38.7 < t[0] < 39.0 and n[0, 0] < -0.5


@needs_embree
def test_cast_hits_is_cast_without_the_misses():
    hf = _hills()
    rocks = np.concatenate([_rocks(hf, 2000, (0.3, 2.0), 8), _rocks(hf, 2000, (0.1, 0.3), 9)])
    rocks[:, 0] = np.arange(len(rocks))
    caster = _caster(hf, rocks)
    dirs = _rays(20000, 10)
    rng = np.random.default_rng(11)
    origins = np.array([120.0, 120.0, 4.0]) + rng.normal(0.0, 0.02, (len(dirs), 3))
    dist, normal = caster.cast(origins, dirs, RANGE_M)
    idx, t, n = caster.cast_hits(origins.astype(np.float32), dirs.astype(np.float32), RANGE_M)
    np.testing.assert_array_equal(idx, np.flatnonzero(np.isfinite(dist)))
    np.testing.assert_array_equal(t, dist[idx])
    np.testing.assert_array_equal(n, normal[idx])
    assert len(idx) > 5000 and np.all((t >= RANGE_M[0]) & (t <= RANGE_M[1]))
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-9)
    assert np.all(normal[np.isinf(dist)] == 0.0)
