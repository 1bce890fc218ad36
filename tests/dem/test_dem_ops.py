"""Pure DEM operations: crops in pixels / metres / lon-lat, resampling, nodata fill, detrend."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from marsscene.dem import ops
from marsscene.dem.crs import iau_2015_code, lonlat_to_xy, xy_to_lonlat
from marsscene.dem.io import read_dem
from marsscene.dem.model import DEM
from marsscene.errors import ConfigError, CRSError, NodataFilledWarning
from tests.dem.conftest import GALE_TIF

EQC = ("+proj=eqc +lat_ts=18.0 +lat_0=0 +lon_0=77.0 +x_0=0 +y_0=0 +R=3394839.8133163 "
       "+units=m +no_defs")


def plane_dem(rows: int = 60, cols: int = 80, post: float = 1.0, sx: float = 0.05,
              sy: float = -0.02) -> DEM:
    """z = -2500 + sx * x + sy * y on a 1 m grid with its upper-left corner at (1000, 1066000)."""
    dem = DEM(np.zeros((rows, cols), np.float32), (post, 0, 1000.0, 0, -post, 1_066_000.0), EQC)
    x, y = dem.xy_of(*np.mgrid[0:rows, 0:cols])
    return dem.replace(elevation_m=(-2500 + sx * (x - 1000) + sy * (y - 1_066_000)))


@pytest.fixture(scope="module")
def gale() -> DEM:
    return read_dem(GALE_TIF)


def test_crop_bounds_in_metres(gale: DEM) -> None:
    x0, _, _, y1 = gale.bounds_xy_m
    box = (x0 + 10.2, y1 - 60.0, x0 + 50.0, y1 - 20.4)
    out = ops.crop(gale, ops.Crop(bounds_xy_m=box))
    px0, py0, px1, py1 = out.post_bounds_xy_m
    # posts whose centres fall inside the box: centres at x0 + 10.5 .. x0 + 49.5
    assert (px0, px1) == (x0 + 10.5, x0 + 49.5)
    assert (py0, py1) == (y1 - 59.5, y1 - 20.5)
    assert out.shape == (40, 40)
    np.testing.assert_array_equal(out.elevation_m, gale.elevation_m[20:60, 10:50])


def test_crop_lonlat_centre_and_size(gale: DEM) -> None:
    lon, lat = 137.3702, -4.6671
    out = ops.crop(gale, ops.Crop(center_lonlat_deg=(lon, lat), size_m=(100.0, 60.0)))
    x0, y0, x1, y1 = out.post_bounds_xy_m
    assert (x1 - x0, y1 - y0) == (100.0, 60.0)  # footprint between outer posts, in metres
    cx, cy = lonlat_to_xy(gale.crs_wkt, lon, lat)
    assert abs((x0 + x1) / 2 - cx) <= 0.5 and abs((y0 + y1) / 2 - cy) <= 0.5
    clon, clat = out.center_lonlat_deg or (0.0, 0.0)
    # 1 m on a 3396.19 km sphere is 1.687e-5 deg: centre within a post of the request
    assert abs(clon - lon) < 2e-5 and abs(clat - lat) < 2e-5


def test_crop_outside_dem_is_refused(gale: DEM) -> None:
    with pytest.raises(ConfigError, match="outside the DEM"):
        ops.crop(gale, ops.Crop(center_lonlat_deg=(140.0, -4.667), size_m=(50.0, 50.0)))
    with pytest.raises(ConfigError, match="outside the DEM"):
        ops.crop(gale, ops.Crop(pixels=(400, 0, 10, 10)))


def test_crop_partly_outside_is_clipped_with_warning(gale: DEM) -> None:
    with pytest.warns(ops.CropClippedWarning, match="clipped"):
        out = ops.crop(gale, ops.Crop(pixels=(330, 340, 20, 20)))
    assert out.shape == (7, 8)


def test_lonlat_crop_needs_metric_crs() -> None:
    geo = DEM(np.zeros((4, 4), np.float32), (1e-4, 0, 137.0, 0, -1e-4, -4.0),
              "+proj=longlat +R=3396190 +no_defs")
    with pytest.raises(CRSError, match="geographic"):
        ops.crop(geo, ops.Crop(center_lonlat_deg=(137.0001, -4.0001), size_m=(1.0, 1.0)))


def test_lonlat_round_trip_and_iau_code(gale: DEM) -> None:
    x, y = lonlat_to_xy(gale.crs_wkt, np.array([137.37, 359.5]), np.array([-4.667, 10.0]))
    lon, lat = xy_to_lonlat(gale.crs_wkt, x, y)
    np.testing.assert_allclose(lon, [137.37, 359.5], atol=1e-9)
    np.testing.assert_allclose(lat, [-4.667, 10.0], atol=1e-9)
    # equidistant cylindrical on the 3396190 m sphere, lon_0 = 0: IAU_2015:49910
    assert iau_2015_code(gale.crs_wkt) == "IAU_2015:49910"
    assert iau_2015_code(EQC) is None  # local-radius label sphere: no IAU code
    # x = R * cos(lat_ts) * dlon (rad) on the label sphere
    xs, _ = lonlat_to_xy(EQC, 77.01, 0.0)
    assert float(xs) == pytest.approx(3394839.8133163 * np.cos(np.radians(18)) * np.radians(0.01))


@pytest.mark.parametrize("method", ["bilinear", "cubic"])
def test_upsampling_preserves_plane_slope(method: str) -> None:
    dem = plane_dem()
    out = ops.resample(dem, 0.25, method=method)
    assert out.post_m == 0.25 and out.post_bounds_xy_m == dem.post_bounds_xy_m
    rows, cols = out.shape
    r, c = np.mgrid[8:rows - 8, 8:cols - 8]  # interior (edges replicate)
    x, y = out.xy_of(r, c)
    design = np.stack([x.ravel() - 1000, y.ravel() - 1_066_000, np.ones(r.size)], axis=1)
    coef, res, *_ = np.linalg.lstsq(design, out.elevation_m[8:-8, 8:-8].ravel(), rcond=None)
    np.testing.assert_allclose(coef[:2], [0.05, -0.02], atol=1e-6)  # slopes kept
    assert np.sqrt(res[0] / r.size) < 1e-3  # still a plane (float32 rounding only)


def test_area_downsampling_preserves_mean(gale: DEM) -> None:
    sub = ops.crop(gale, ops.Crop(pixels=(0, 0, 241, 241)))
    out = ops.resample(sub, 4.0)
    assert out.metadata["resampling"] == "area" and out.shape == (61, 61)
    src = sub.elevation_m.astype(np.float64)
    # target post k sits on source index 4k; its 4-post box [4k-2, 4k+2] takes half of the two
    # end posts: weights (.5, 1, 1, 1, .5) / 4 per axis
    w = np.array([0.5, 1, 1, 1, 0.5]) / 4
    assert out.elevation_m[1, 1] == pytest.approx(float(w @ src[2:7, 2:7] @ w), abs=1e-3)
    # so the interior posts' mean is the source mean under those weights (mean preserved)
    w1 = np.ones(241)
    w1[:2] = w1[-2:] = 0
    w1[2] = w1[-3] = 0.5
    want = float(w1 @ src @ w1 / w1.sum() ** 2)
    assert float(out.elevation_m[1:-1, 1:-1].astype(np.float64).mean()) == pytest.approx(
        want, abs=1e-3)


def test_resample_scale_factors() -> None:
    dem = plane_dem()
    plain = ops.resample(dem, 2.0)
    out = ops.resample(dem, 2.0, xy_scale=0.5, z_scale=2.0)
    cx, cy = dem.center_xy()
    assert out.post_m == 1.0
    x0, _, _, y1 = plain.post_bounds_xy_m
    assert out.post_bounds_xy_m[0] == pytest.approx(cx + 0.5 * (x0 - cx))
    assert out.post_bounds_xy_m[3] == pytest.approx(cy + 0.5 * (y1 - cy))
    assert out.metadata["xy_scale"] == 0.5
    np.testing.assert_allclose(out.elevation_m, 2 * plain.elevation_m, rtol=1e-6)


def test_fill_nodata_smooth_and_bounded(gale: DEM) -> None:
    z = np.array(gale.elevation_m)
    z[100:130, 150:170] = np.nan
    ring = np.zeros(z.shape, bool)
    ring[99:131, 149:171] = True
    ring[100:130, 150:170] = False
    with pytest.warns(NodataFilledWarning, match="filled 600 missing posts"):
        filled, n = ops.fill_nodata(gale.replace(elevation_m=z))
    assert n == 600
    hole = filled.elevation_m[100:130, 150:170]
    assert hole.min() >= z[ring].min() - 1e-3 and hole.max() <= z[ring].max() + 1e-3
    np.testing.assert_array_equal(filled.elevation_m[~np.isnan(z)], z[~np.isnan(z)])


def test_fill_nodata_reproduces_a_plane() -> None:
    dem = plane_dem()
    z = np.array(dem.elevation_m)
    z[20:35, 30:50] = np.nan  # a harmonic fill of a linear surface is the surface itself
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NodataFilledWarning)
        filled, _ = ops.fill_nodata(dem.replace(elevation_m=z))
    np.testing.assert_allclose(filled.elevation_m, dem.elevation_m, atol=2e-3)


def test_fill_warning_points_at_the_callers_line() -> None:
    # filled deep inside a build, the warning names the user's line, not marsscene's own file
    from marsscene.terrain.config import TerrainConfig
    from marsscene.terrain.from_dem import prepare_dem

    dem = plane_dem()
    z = np.array(dem.elevation_m)
    z[20:35, 30:50] = np.nan
    with pytest.warns(NodataFilledWarning) as record:
        prepare_dem(dem.replace(elevation_m=z), TerrainConfig(), default_post_m=None)
    assert [w.filename for w in record] == [__file__]


def test_mostly_missing_crop_is_refused() -> None:
    z = np.full((20, 20), np.nan, np.float32)
    z[:5] = 1.0
    with pytest.raises(ConfigError, match=r"75\.0 % of the 400 posts are missing"):
        ops.fill_nodata(plane_dem(20, 20).replace(elevation_m=z))


def test_detrend_removes_plane_keeps_mean() -> None:
    dem = plane_dem()
    out = ops.detrend(dem)
    assert float(np.ptp(out.elevation_m)) < 1e-3
    assert float(out.elevation_m.mean()) == pytest.approx(float(dem.elevation_m.mean()),
                                                          abs=1e-3)
    assert dem.elevation_m.flags.writeable is False  # input untouched (frozen array)
