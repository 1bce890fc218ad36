"""Fixtures of the DEM tests: real sample files (skipped if absent) and assembled PDS3 DTMs."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from marsscene.testing.pds3 import write_pds3_dtm
from tests.conftest import SHARED_REAL

GALE_TIF = Path(__file__).resolve().parents[2] / "marsscene/terrain/data/gale_missionDEM.tif"

#: Projection offsets of the assembled DTM: upper-left pixel corner at x = 1200 m, y = 1066701 m
#: on an equirectangular sphere with lat_ts = 18 N, lon_0 = 77 E (Jezero-like).
SPO, LPO, SCALE = -1200.5, 1066700.5, 1.0


LOCAL_REAL = Path(__file__).resolve().parent / "data"


def real(*parts: str) -> Path:
    """A real sample file (``tests/dem/data`` copy, else the shared folder), or skip the test."""
    path = LOCAL_REAL.joinpath(*parts)
    if not path.is_file():
        path = SHARED_REAL.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"real sample data not present: {path}")
    return path


@pytest.fixture(scope="session")
def gale_z() -> np.ndarray:
    """Real HiRISE-derived Gale elevations (the bundled MMGIS GeoTIFF), 120 x 160 crop."""
    import rasterio

    with rasterio.open(GALE_TIF) as ds:
        return ds.read(1)[100:220, 80:240].astype(np.float32)


@pytest.fixture
def gale_holes(gale_z: np.ndarray) -> np.ndarray:
    """The Gale crop with a 6 x 5 hole of missing posts and one missing corner post."""
    z = gale_z.copy()
    z[50:56, 70:75] = np.nan
    z[0, 0] = np.nan
    return z


@pytest.fixture
def pds3_attached(tmp_path: Path, gale_holes: np.ndarray) -> Path:
    return write_pds3_dtm(tmp_path / "DTEEC_045994_1985_046060_1985_U01.IMG", gale_holes,
                          lpo=LPO, spo=SPO, map_scale_m=SCALE)


@pytest.fixture
def pds3_detached(tmp_path: Path, gale_holes: np.ndarray) -> Path:
    return write_pds3_dtm(tmp_path / "DTEEC_DETACHED.IMG", gale_holes, detached=True,
                          lpo=LPO, spo=SPO, map_scale_m=SCALE)
