"""DTM read averaged strip by strip (marsscene.dem.decimate) and the level-of-detail terrain
built on it (marsscene.pipeline.dem_lod): box means against a brute-force reference, missing
posts, geo-reference, and the scene's outer level and focus window."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.dem.decimate import read_dem_averaged
from marsscene.dem.io import read_dem
from tests.dem.lod_checks import assert_outer_matches

CRS = "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=150 +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs"


def _write(path: Path, z: np.ndarray, nodata: float | None = -32767.0) -> Path:
    import rasterio
    from affine import Affine

    with rasterio.open(path, "w", driver="GTiff", height=z.shape[0], width=z.shape[1], count=1,
                       dtype="float32", crs=CRS, transform=Affine(1.0, 0, 1000.0, 0, -1.0, 500.0),
                       nodata=nodata) as ds:
        ds.write(z.astype(np.float32), 1)
    return path


def _brute(z: np.ndarray, f: int) -> np.ndarray:
    h = (f | 1) // 2
    rows, cols = (z.shape[0] - 1) // f + 1, (z.shape[1] - 1) // f + 1
    out = np.full((rows, cols), np.nan)
    for i in range(rows):  # the reference: a plain loop over the output posts
        for j in range(cols):
            box = z[max(i * f - h, 0):i * f + h + 1, max(j * f - h, 0):j * f + h + 1]
            if np.isfinite(box).any():
                out[i, j] = np.nanmean(box)
    return out


@pytest.mark.parametrize(("factor", "strip_posts"), [(4, 700), (3, 10**8), (2, 1)])
def test_box_means_equal_the_reference_for_any_strip_size(tmp_path: Path, factor: int,
                                                          strip_posts: int) -> None:
    rng = np.random.default_rng(3)
    z = rng.normal(size=(61, 83)).astype(np.float32)
    z[10:17, 20:40] = -32767.0  # a nodata patch wider than a box
    path = _write(tmp_path / "r.tif", z)
    full = read_dem(path)
    avg = read_dem_averaged(path, factor=factor, strip_posts=strip_posts)
    ref = _brute(full.elevation_m.astype(np.float64), factor)
    assert avg.elevation_m.shape == ref.shape
    np.testing.assert_array_equal(np.isnan(avg.elevation_m), np.isnan(ref))
    assert np.isnan(ref).any()  # the patch leaves boxes with no valid post
    np.testing.assert_allclose(avg.elevation_m, ref, atol=1e-5, equal_nan=True)
    # output post j is input post j * factor: same centre coordinates
    assert avg.post_m == factor * full.post_m
    xf, yf = full.transform[2] + 0.5, full.transform[5] - 0.5
    assert (avg.transform[2] + 0.5 * avg.post_m, avg.transform[5] - 0.5 * avg.post_m) == (xf, yf)


def test_lod_scene_on_a_dtm_read_averaged(tmp_path: Path) -> None:
    """post_m = 4 on a 1 m DTM: the outer level is the 4 m box average (away from the stitched
    band), the focus window comes from the DTM's own posts, and no full-resolution array of the
    whole DTM is made (the note says how it was read)."""
    from marsscene.pipeline.terrain import lod_inputs

    rows, cols = 241, 321
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    z = -2000.0 + 0.03 * xx + 0.4 * np.sin(2 * np.pi * xx / 3.0) * np.cos(2 * np.pi * yy / 7.0)
    path = _write(tmp_path / "dtm.tif", z, nodata=None)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(path), "lod": True, "post_m": 4.0,
                    "focus_size_m": 80.0, "focus_xy_m": [40.0, 0.0], "lod_blend_m": 8.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}})
    scene = ms.build_scene(cfg, seed=1)
    assert any("read averaged to 4 m posts strip by strip" in n for n in scene.provenance.notes)
    outer = scene.outer
    assert outer is not None and outer.heightfield.cell_size_m == 4.0
    assert outer.heightfield.shape == (61, 81)
    datum = scene.provenance.frame.datum_m
    ref = (_brute(z, 4) - datum)[::-1]  # south-up rows
    assert_outer_matches(outer, ref, 4.0, 2000)
    fx0, fy0, fx1, fy1 = outer.focus_bounds_xy_m
    world, _ = lod_inputs(cfg, 1)
    assert world.base.cell_size_m == 1.0
    bx0, by0, bx1, by1 = world.base.bounds_xy_m
    assert bx0 <= fx0 - 4 and bx1 >= fx1 + 4 and by0 <= fy0 - 4 and by1 >= fy1 + 4
    assert world.base.z_m.size < z.size / 2  # the window, not the whole DTM
    # the focus holds the 3 m ripple of the DTM's posts (the 4 m outer level cannot)
    fine = scene.heightfield
    at_posts = fine.z_m[::4, ::4][36:-36, 36:-36]  # past the 32 m taper
    base_at = world.base.sample(*np.meshgrid(fine.grid_xy()[0][::4], fine.grid_xy()[1][::4]))
    np.testing.assert_allclose(at_posts, base_at[36:-36, 36:-36], atol=5e-3)
    assert float((at_posts - at_posts.mean(axis=1, keepdims=True)).std()) > 0.15
