"""GeoTIFFs of scene grids (dem.io_write): rows flipped to north-up, each post at its pixel's
centre, the scene frame's projected origin and CRS, band names; read back by rasterio and by the
package's own DEM reader onto the same posts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from marsscene.dem.io import read_dem
from marsscene.dem.io_write import write_geotiff
from marsscene.errors import ConfigError
from marsscene.terrain.from_dem import heightfield_from_dem

CRS = "+proj=eqc +lat_ts=18.4 +lat_0=0 +lon_0=77.5 +x_0=0 +y_0=0 +R=3394839.8 +units=m +no_defs"


def _grid() -> np.ndarray:
    rows, cols = 5, 7
    return (np.arange(rows)[:, None] * 100 + np.arange(cols)[None, :]).astype(np.float32)


def test_layers_are_north_up_bands_at_the_posts_projected_and_named(tmp_path: Path) -> None:
    import rasterio

    z = _grid()  # row 0 south: value = 100 * row + col
    path = write_geotiff(tmp_path / "t.tif", {"cost": z, "hazard": z * 0 + 1},
                         origin_xy_m=(-3.0, -2.0), cell_m=1.0, crs_wkt=CRS,
                         origin_projected_xy_m=(1000.0, 2000.0))
    with rasterio.open(path) as ds:
        assert ds.count == 2 and ds.descriptions == ("cost", "hazard")
        top = ds.read(1)
        assert top[0, 0] == 400.0 and top[-1, 0] == 0.0  # the northern row first
        # post (row 0, col 0) at scene (-3, -2), projected (997, 1998): the centre of the
        # south-west pixel
        x, y = ds.xy(ds.height - 1, 0)
        assert (x, y) == (997.0, 1998.0)
        assert ds.crs is not None and "eqc" in ds.crs.to_proj4()


def test_the_dem_reader_puts_the_written_grid_back_on_its_posts(tmp_path: Path) -> None:
    z = _grid()
    path = write_geotiff(tmp_path / "z.tif", {"z": z}, origin_xy_m=(-3.0, -2.0), cell_m=1.0,
                         crs_wkt=CRS, origin_projected_xy_m=(1000.0, 2000.0))
    hf, frame = heightfield_from_dem(read_dem(path))
    np.testing.assert_allclose(hf.z_m + frame.datum_m, z)  # south-up again
    assert frame.origin_projected_xy_m == pytest.approx((1000.0, 2000.0))  # the centre post


def test_same_layers_same_bytes(tmp_path: Path) -> None:
    a = write_geotiff(tmp_path / "a.tif", {"z": _grid()}, origin_xy_m=(0, 0), cell_m=0.5)
    b = write_geotiff(tmp_path / "b.tif", {"z": _grid()}, origin_xy_m=(0, 0), cell_m=0.5)
    assert a.read_bytes() == b.read_bytes()


def test_layers_of_different_shapes_are_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="one 2-D shape and dtype"):
        write_geotiff(tmp_path / "x.tif", {"a": _grid(), "b": _grid()[:2]}, origin_xy_m=(0, 0),
                      cell_m=1.0)
