"""read_dem on PDS3 (attached/detached, assembled from real elevations), ISIS3 and GeoTIFF."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from marsscene.dem.io import open_source, read_dem
from marsscene.dem.ops import Crop
from marsscene.errors import CRSError, DEMReadError, MemoryBudgetError
from marsscene.testing.pds3 import write_pds3_dtm
from tests.dem.conftest import GALE_TIF, LPO, SCALE, SPO, real


@pytest.mark.parametrize("which", ["pds3_attached", "pds3_detached"])
def test_pds3_round_trip_and_missing(which: str, request: pytest.FixtureRequest,
                                     gale_holes: np.ndarray) -> None:
    dem = read_dem(request.getfixturevalue(which))
    z = dem.elevation_m
    assert z.shape == gale_holes.shape and z.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(z), np.isnan(gale_holes))
    np.testing.assert_array_equal(z[np.isfinite(z)], gale_holes[np.isfinite(gale_holes)])
    assert dem.metadata["PRODUCT_ID"] == "DTEEC_045994_1985_046060_1985_U01"
    assert dem.metadata["MISSING_CONSTANT"] == "16#FF7FFFFB#"
    assert dem.metadata["CENTER_LATITUDE"] == 18.0 and dem.metadata["A_AXIS_RADIUS"] > 3394
    assert ("data_file" in dem.metadata) == (which == "pds3_detached")


def test_pds3_known_post_coordinates(pds3_attached: Path) -> None:
    dem = read_dem(pds3_attached)
    # 1-based (sample 11, line 21) -> x = (11 - 1 - SPO) * scale, y = (LPO - (21 - 1)) * scale
    x, y = dem.xy_of(20, 10)
    assert float(x) == (11 - 1 - SPO) * SCALE == 1210.5
    assert float(y) == (LPO - 20) * SCALE == 1066680.5
    assert dem.rowcol_of(1210.5, 1066680.5) == (20.0, 10.0)


def test_pds3_transform_and_crs_agree_with_gdal(pds3_attached: Path) -> None:
    import rasterio
    from pyproj import CRS

    dem = read_dem(pds3_attached)
    with rasterio.open(pds3_attached) as ds:
        assert tuple(ds.transform)[:6] == dem.transform
        assert CRS.from_user_input(ds.crs.to_wkt()).equals(CRS.from_user_input(dem.crs_wkt))
        assert ds.nodata == -3.4028226550889045e38


def test_isis_special_pixels_by_bits_only(tmp_path: Path, gale_z: np.ndarray) -> None:
    z = gale_z[:8, :8].copy()
    raw = z.view(np.uint32)
    raw[0, 0] = 0xFF7FFFFD  # ISIS LIS special pixel -> missing
    raw[0, 1] = 0xFF7FFFF0  # a (huge) ordinary float near NULL4: kept, bits differ
    dem = read_dem(write_pds3_dtm(tmp_path / "SPECIAL.IMG", z))
    assert np.isnan(dem.elevation_m[0, 0])
    assert dem.elevation_m[0, 1] == z[0, 1] and np.isfinite(dem.elevation_m[1:]).all()


def test_windowed_read_equals_crop_of_full(pds3_attached: Path) -> None:
    full = read_dem(pds3_attached)
    part = read_dem(pds3_attached, window=(10, 20, 30, 40))
    np.testing.assert_array_equal(part.elevation_m, full.elevation_m[10:40, 20:60])
    assert part.xy_of(0, 0) == full.xy_of(10, 20)
    assert part.metadata["window_rows_cols"] == [10, 20, 30, 40]


def test_memory_refusal_has_estimate(pds3_attached: Path) -> None:
    with pytest.raises(MemoryBudgetError, match=r"about [0-9.]+ GB.*budget"):
        read_dem(pds3_attached, max_bytes=1e6, target_post_m=0.1)


def test_truncated_img(tmp_path: Path, pds3_attached: Path) -> None:
    blob = pds3_attached.read_bytes()
    bad = tmp_path / "TRUNC.IMG"
    bad.write_bytes(blob[:-1000])
    with pytest.raises(DEMReadError, match="truncated"):
        read_dem(bad)


def test_wrong_image_pointer_inside_label(tmp_path: Path, gale_z: np.ndarray) -> None:
    path = write_pds3_dtm(tmp_path / "PTR.IMG", gale_z, pointer_record=1)
    with pytest.raises(DEMReadError, match=r"\^IMAGE pointer is wrong"):
        read_dem(path)


def test_wrong_image_pointer_past_end(tmp_path: Path, gale_z: np.ndarray) -> None:
    path = write_pds3_dtm(tmp_path / "PTR2.IMG", gale_z, pointer_record=10_000)
    with pytest.raises(DEMReadError, match=r"\^IMAGE"):
        read_dem(path)


def test_detached_pointer_to_missing_file(pds3_detached: Path) -> None:
    pds3_detached.with_suffix(".IMG").unlink()
    with pytest.raises(DEMReadError, match="not beside the label"):
        read_dem(pds3_detached)


def test_not_a_raster(tmp_path: Path) -> None:
    bad = tmp_path / "notes.tif"
    bad.write_text("this is not a raster\n")
    with pytest.raises(DEMReadError, match="not a raster"):
        read_dem(bad)


def test_geographic_crs_refused(tmp_path: Path) -> None:
    import rasterio

    path = tmp_path / "geo.tif"
    with rasterio.open(path, "w", driver="GTiff", width=4, height=4, count=1, dtype="float32",
                       crs="+proj=longlat +R=3396190 +no_defs",
                       transform=rasterio.Affine(1e-4, 0, 137.0, 0, -1e-4, -4.0)) as ds:
        ds.write(np.zeros((4, 4), np.float32), 1)
    with pytest.raises(CRSError, match="geographic"):
        read_dem(path)


def test_isis3_two_band_dtm_needs_band() -> None:
    path = real("isis_hidtmgen", "DTM_2Bands_cropped.cub")
    with pytest.raises(DEMReadError, match="2 bands"):
        read_dem(path)
    dem = read_dem(path, band=1)
    assert dem.shape == (45, 16) and dem.post_m == 500.0
    # shared README: 870 of the 1440 samples (2 bands x 45 x 16) valid -> 435 in band 1
    assert int(np.isfinite(dem.elevation_m).sum()) == 435
    assert np.nanmin(dem.elevation_m) == pytest.approx(-1892.6, abs=0.05)
    assert np.nanmax(dem.elevation_m) == pytest.approx(-1308.1, abs=0.05)
    assert dem.metadata["ISIS_ProjectionName"] == "Equirectangular"
    lon, lat = dem.center_lonlat_deg or (0.0, 0.0)
    assert 355.6 < lon < 355.9 and 12.4 < lat < 12.9  # Marth crater, per the label's extents


def test_bundled_gale_geotiff() -> None:
    dem = read_dem(GALE_TIF)
    assert dem.shape == (337, 348) and dem.post_m == 1.0 and dem.valid_fraction == 1.0
    lon, lat = dem.center_lonlat_deg or (0.0, 0.0)
    assert lon == pytest.approx(137.370, abs=0.01) and lat == pytest.approx(-4.667, abs=0.01)
    assert open_source(GALE_TIF).driver == "GTiff"


def test_geotiff_nodata_corner(synthetic_dem_path: Path) -> None:
    dem = read_dem(synthetic_dem_path)
    assert np.isnan(dem.elevation_m[:3, :3]).all()
    assert int(np.isnan(dem.elevation_m).sum()) == 9


def test_polar_stereographic_dtm(tmp_path: Path, gale_z: np.ndarray) -> None:
    # DTEPC-style label: polar stereographic about the north pole, planetocentric sphere
    path = write_pds3_dtm(tmp_path / "DTEPC_POLAR.IMG", gale_z, proj_type="POLAR STEREOGRAPHIC",
                          center_lat=90.0, center_lon=0.0, radius_km=3376.2,
                          spo=-200_000.5, lpo=-10_000.5)
    dem = read_dem(path)
    assert "+proj=stere" in dem.crs_wkt and "+R=3376200.0" in dem.crs_wkt
    lon, lat = dem.center_lonlat_deg or (0.0, 0.0)
    # centre x ~ 200080 m, y ~ 9940 m from the pole: r = 2R tan((90 - lat) / 2)
    x, y = dem.center_xy()
    r = float(np.hypot(x, y))
    assert lat == pytest.approx(90 - 2 * np.degrees(np.arctan(r / (2 * 3376200.0))), abs=1e-9)
    assert lon == pytest.approx(np.degrees(np.arctan2(x, -y)) % 360, abs=1e-9)
    part = read_dem(path, crop=Crop(center_lonlat_deg=(lon, lat), size_m=(40.0, 30.0)))
    assert part.shape == (31, 41)


def test_pds4_written_by_gdal(tmp_path: Path, gale_z: np.ndarray) -> None:
    import rasterio

    z = gale_z.copy()
    z[5, 7] = -3.4028226550889045e38
    crs = ("+proj=eqc +lat_ts=18 +lat_0=0 +lon_0=77 +x_0=0 +y_0=0 +R=3394839.8 +units=m "
           "+no_defs")
    path = tmp_path / "dtm.xml"
    with rasterio.open(path, "w", driver="PDS4", width=z.shape[1], height=z.shape[0], count=1,
                       dtype="float32", crs=crs, nodata=-3.4028226550889045e38,
                       transform=rasterio.Affine(1.0, 0, 1000.0, 0, -1.0, 1_066_000.0)) as ds:
        ds.write(z, 1)
    dem = read_dem(path)
    assert dem.metadata["driver"] == "PDS4" and dem.transform[2] == 1000.0
    assert np.isnan(dem.elevation_m[5, 7]) and int(np.isnan(dem.elevation_m).sum()) == 1
    assert dem.center_lonlat_deg is not None and 77.0 < dem.center_lonlat_deg[0] < 77.1
