"""Orthoimages: HiRISE JP2 + .LBL (DN scaling, CORE_NULL), real ISIS3 crops, co-registration."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from marsscene.dem.io_ortho import read_ortho
from marsscene.dem.model import Ortho
from marsscene.dem.resample import resample_separable
from marsscene.dem.texture import texture_rgb
from marsscene.errors import ConfigError, CRSError
from marsscene.testing.pds3 import write_hirise_ortho
from tests.dem.conftest import real

SCALE_IF = 1.07543902665525e-04  # the real ESP_013951_1955_RED label's SCALING_FACTOR
OFFSET_IF = 0.081203337858079


@pytest.fixture
def jp2_ortho(tmp_path: Path) -> tuple[Path, np.ndarray]:
    dn = (np.arange(40 * 30).reshape(40, 30) % 900 + 3).astype(np.uint16)
    dn[0, :] = 0  # CORE_NULL
    lbl = write_hirise_ortho(tmp_path, dn, template=real("labels", "GDAL_ESP_013951_1955_RED.LBL"),
                             x0_m=-6139000.25, y0_m=936010.75, scale_m=0.5)
    return lbl, dn


def test_jp2_label_scaling_null_and_transform(jp2_ortho: tuple[Path, np.ndarray]) -> None:
    lbl, dn = jp2_ortho
    ortho = read_ortho(lbl)
    assert ortho.transform == (0.5, 0.0, -6139000.25, 0.0, -0.5, 936010.75)
    img = ortho.image[:, :, 0]
    assert np.isnan(img[0]).all() and np.isfinite(img[1:]).all()
    want = dn[1:].astype(np.float32) * np.float32(SCALE_IF) + np.float32(OFFSET_IF)
    np.testing.assert_allclose(img[1:], want, rtol=1e-6)  # I/F = DN * SCALING_FACTOR + OFFSET
    assert "+lat_ts=15.0" in ortho.crs_wkt and ortho.metadata["PRODUCT_ID"] == (
        "ESP_013951_1955_RED")


def test_window_read_and_decimation(jp2_ortho: tuple[Path, np.ndarray]) -> None:
    lbl, _ = jp2_ortho
    full = read_ortho(lbl)
    x0, _, _, y1 = full.bounds_xy_m
    part = read_ortho(lbl, bounds_xy_m=(x0 + 5.0, y1 - 12.0, x0 + 10.0, y1 - 6.0), pixel_m=1.0)
    assert part.metadata["decimation"] == 2
    assert part.pixel_m == pytest.approx(1.0)
    # the decimated window's pixel (0, 0) averages full-res pixels it covers
    r, c = full.rowcol_of(*part.xy_of(0, 0))
    assert float(r) % 1 == 0.5 and float(c) % 1 == 0.5  # centred between 2 x 2 source pixels
    rr, cc = int(np.floor(r)), int(np.floor(c))
    np.testing.assert_allclose(part.image[0, 0, 0], full.image[rr:rr + 2, cc:cc + 2, 0].mean(),
                               rtol=1e-3)


def test_real_isis_orthos_coregister_at_zero_shift() -> None:
    """The real 0.25 m crop averaged onto the real 1 m crop's grid correlates best at zero
    offset: both transforms put the same ground on the same pixel."""
    o1 = read_ortho(real("isis_hidtmgen", "PSP_002118_1510_1m_o_forPDS_cropped.cub"))
    o4 = read_ortho(real("isis_hidtmgen", "PSP_002118_1510_25cm_o_forPDS_cropped.cub"))
    scores = {}
    for shift in (-2, -1, 0, 1, 2):
        rows, cols = np.mgrid[3:12, 1:12]
        x, y = o1.xy_of(rows, cols + shift)
        ur, _ = o4.rowcol_of(np.zeros(9), y[:, 0])
        _, uc = o4.rowcol_of(x[0], np.zeros(11))
        scale = o1.pixel_m / o4.pixel_m
        avg = resample_separable(o4.image[:, :, 0], ur, uc, method="area", scale_rows=scale,
                                 scale_cols=scale)
        ref = o1.image[3:12, 1:12, 0]
        ok = np.isfinite(avg) & np.isfinite(ref)
        scores[shift] = float(np.corrcoef(avg[ok], ref[ok])[0, 1])
    assert max(scores, key=scores.__getitem__) == 0
    assert scores[0] > 0.6


def test_texture_pixel_edges_on_footprint() -> None:
    # a 1 m ortho with a single bright pixel centred on projected (10.5, 20.5)
    img = np.zeros((40, 40), np.float32)
    img[19, 10] = 100.0  # centre x = 0 + 10.5, y = 40 - 19.5
    ortho = Ortho(image=img, transform=(1.0, 0, 0.0, 0, -1.0, 40.0))
    tex = texture_rgb(ortho, (5.0, 10.0, 25.0, 30.0), percentiles=(0, 100))
    assert tex.shape == (20, 20, 3)  # 1 m texture pixels, edges on the footprint bounds
    row, col = np.unravel_index(int(np.argmax(tex[:, :, 0])), tex.shape[:2])
    assert (row, col) == (9, 5)  # x 5 + 5.5 = 10.5, y 30 - 9.5 = 20.5


def test_texture_errors() -> None:
    ortho = Ortho(image=np.ones((10, 10), np.float32), transform=(1.0, 0, 0.0, 0, -1.0, 10.0),
                  crs_wkt="+proj=eqc +lat_ts=15 +lon_0=180 +R=3394839.8 +units=m")
    with pytest.raises(ConfigError, match="does not cover"):
        texture_rgb(ortho, (5.0, 5.0, 20.0, 9.0))
    with pytest.raises(CRSError, match="differs"):
        texture_rgb(ortho, (1.0, 1.0, 9.0, 9.0),
                    crs_wkt="+proj=eqc +lat_ts=18 +lon_0=77 +R=3394839.8 +units=m")
