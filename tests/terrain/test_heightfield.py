"""Heightfield geometry: grid<->world conversion, bilinear sampling, normals, slopes, meshing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.errors import ConfigError
from marsscene.terrain import Heightfield
from marsscene.terrain.mesh import grid_faces, heightfield_tiles


def plane(rows: int = 30, cols: int = 40, cell: float = 0.5, a: float = 0.2, b: float = -0.1):
    hf0 = Heightfield.centered(np.zeros((rows, cols), np.float32), cell)
    xs, ys = hf0.grid_xy()
    z = a * xs[None, :] + b * ys[:, None] + 3.0
    return Heightfield(z.astype(np.float32), cell, hf0.origin_xy_m), a, b


def test_centered_footprint_and_inverse_conversion() -> None:
    hf, _, _ = plane()
    x0, y0, x1, y1 = hf.bounds_xy_m
    assert (x0 + x1, y0 + y1) == (0.0, 0.0)
    assert hf.size_m == (39 * 0.5, 29 * 0.5)
    x, y = hf.xy_of([0, 29, 3.5], [0, 39, 7.25])
    assert x[0] == x0 and y[0] == y0 and x[1] == x1 and y[1] == y1
    r, c = hf.rowcol_of(x, y)
    np.testing.assert_allclose(r, [0, 29, 3.5])
    np.testing.assert_allclose(c, [0, 39, 7.25])


def test_row_zero_is_south() -> None:
    z = np.zeros((5, 4), np.float32)
    z[0, :] = 1.0  # southern row
    hf = Heightfield.centered(z, 1.0)
    assert hf.sample(0.0, hf.bounds_xy_m[1]) == pytest.approx(1.0)
    assert hf.sample(0.0, hf.bounds_xy_m[3]) == pytest.approx(0.0)


def test_bilinear_sample_is_exact_on_a_plane_and_at_posts() -> None:
    hf, a, b = plane()
    rng = np.random.default_rng(0)
    x = rng.uniform(hf.bounds_xy_m[0], hf.bounds_xy_m[2], 200)
    y = rng.uniform(hf.bounds_xy_m[1], hf.bounds_xy_m[3], 200)
    np.testing.assert_allclose(hf.sample(x, y), a * x + b * y + 3.0, atol=1e-4)
    xs, ys = hf.grid_xy()
    np.testing.assert_allclose(hf.sample(xs[5], ys[7]), hf.z_m[7, 5], atol=1e-6)


def test_normal_and_slope_of_a_plane() -> None:
    hf, a, b = plane()
    n = hf.normal(np.array([0.3]), np.array([-1.1]))[0]
    expected = np.array([-a, -b, 1.0]) / np.linalg.norm([-a, -b, 1.0])
    np.testing.assert_allclose(n, expected, atol=1e-5)
    np.testing.assert_allclose(hf.slope_deg(), np.degrees(np.arctan(np.hypot(a, b))), atol=1e-3)


def test_heightfield_is_immutable_and_validated() -> None:
    hf, _, _ = plane()
    with pytest.raises(ValueError):
        hf.z_m[0, 0] = 1.0
    with pytest.raises(ConfigError, match="NaN"):
        Heightfield(np.full((3, 3), np.nan, np.float32), 1.0)
    with pytest.raises(ConfigError, match="cell_size_m"):
        Heightfield(np.zeros((3, 3), np.float32), -1.0)


@settings(max_examples=25, deadline=None)
@given(rows=st.integers(2, 40), cols=st.integers(2, 40), tile=st.integers(2, 17))
def test_tiles_cover_the_grid_without_cracks(rows: int, cols: int, tile: int) -> None:
    z = np.arange(rows * cols, dtype=np.float32).reshape(rows, cols)
    hf = Heightfield.centered(z, 0.25)
    tiles = heightfield_tiles(hf, max_tile_posts=tile)
    faces = sum(len(t.face_vertex_indices) for t in tiles)
    assert faces == 2 * (rows - 1) * (cols - 1)
    assert all(len(t.points_m) <= tile * tile for t in tiles)
    pts = np.concatenate([t.points_m for t in tiles])
    assert len(np.unique(pts, axis=0)) == rows * cols  # every post present, shared borders
    st_all = np.concatenate([t.st for t in tiles])
    assert st_all.min() == 0.0 and st_all.max() == 1.0


def test_grid_faces_are_counter_clockwise_from_above() -> None:
    faces = grid_faces(3, 4)
    assert faces.shape == (2 * 2 * 3, 3)
    xy = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0)), axis=-1).reshape(-1, 2)
    p = xy[faces]
    cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (
        p[:, 1, 1] - p[:, 0, 1]
    ) * (p[:, 2, 0] - p[:, 0, 0])
    assert (cross > 0).all()


def test_window_normals_equal_the_grid_normals_and_float64_reference() -> None:
    rng = np.random.default_rng(2)
    z = np.cumsum(rng.normal(0, 0.05, (37, 29)), axis=0).astype(np.float32)
    hf = Heightfield.centered(z, 0.25)
    full = hf.grid_normals()
    gx, gy = hf.grid_gradient()  # float64
    ref = np.stack([-gx, -gy, np.ones_like(gx)], axis=-1)
    ref /= np.linalg.norm(ref, axis=-1, keepdims=True)
    np.testing.assert_allclose(full, ref, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(full, axis=-1), 1.0, atol=1e-6)
    for rows, cols in (((0, 37), (0, 29)), ((0, 9), (0, 9)), ((8, 17), (20, 29)),
                       ((36, 37), (5, 6)), ((30, 37), (0, 2))):
        window = hf.window_normals(rows, cols)  # bit-identical: a mesh can be made per tile
        np.testing.assert_array_equal(window, full[slice(*rows), slice(*cols)])


def test_owning_constructor_takes_the_array_and_validates_it() -> None:
    z = np.arange(12, dtype=np.float32).reshape(3, 4)
    hf = Heightfield._owning(z, 0.5, (1.0, 2.0))
    assert np.shares_memory(hf.z_m, z) and not hf.z_m.flags.writeable
    assert hf.cell_size_m == 0.5 and hf.origin_xy_m == (1.0, 2.0)
    public = Heightfield(z.copy(), 0.5, (1.0, 2.0))
    xs, ys = np.random.default_rng(0).uniform(0.5, 3.0, (2, 50))
    assert np.array_equal(hf.sample(xs + 1, ys + 2), public.sample(xs + 1, ys + 2))
    bad = z.copy()
    bad[1, 1] = np.nan
    with pytest.raises(ConfigError, match="NaN"):
        Heightfield._owning(bad, 0.5)


def test_sample_and_gradient_equal_the_bilinear_formula_at_random_points() -> None:
    rng = np.random.default_rng(3)
    hf = Heightfield(rng.normal(size=(37, 53)).astype(np.float32), 0.25, (-3.0, 7.0))
    r, c = rng.uniform(0, 36, 500), rng.uniform(0, 52, 500)
    x, y = hf.xy_of(r, c)
    r0, c0 = np.floor(r).astype(int), np.floor(c).astype(int)
    fr, fc = r - r0, c - c0
    z = hf.z_m.astype(np.float64)
    ref = ((z[r0, c0] * (1 - fc) + z[r0, c0 + 1] * fc) * (1 - fr)
           + (z[r0 + 1, c0] * (1 - fc) + z[r0 + 1, c0 + 1] * fc) * fr)
    np.testing.assert_allclose(hf.sample(x, y), ref, rtol=0, atol=1e-12)
    gx, gy = hf.gradient(x, y)
    np.testing.assert_allclose(
        gx, ((z[r0, c0 + 1] - z[r0, c0]) * (1 - fr) + (z[r0 + 1, c0 + 1] - z[r0 + 1, c0]) * fr)
        / 0.25, atol=1e-10)
    np.testing.assert_allclose(
        gy, ((z[r0 + 1, c0] - z[r0, c0]) * (1 - fc) + (z[r0 + 1, c0 + 1] - z[r0, c0 + 1]) * fc)
        / 0.25, atol=1e-10)
