"""Shared fixtures: tiny synthetic inputs built in code (cf. rasterio tests/conftest.py)."""

from __future__ import annotations

import os
from pathlib import Path

# Headless offscreen rendering: must be set before anything imports mujoco (any test module).
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms

SHARED_REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def runner() -> CliRunner:
    return CliRunner()


@pytest.fixture
def small_procedural_config() -> ms.SceneConfig:
    """A 20 m x 16 m procedural terrain at 0.25 m, all later stages at their defaults."""
    return ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [20.0, 16.0], "post_m": 0.25}}
    )


@pytest.fixture
def synthetic_dem_path(tmp_path: Path) -> Path:
    """A 64 x 48 projected GeoTIFF DEM (a bowl plus a slope, 1 m posts, nodata corner)."""
    import rasterio
    from affine import Affine

    rows, cols = 48, 64
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float64)
    z = -4400.0 + 0.05 * xx + 0.02 * ((xx - 32) ** 2 + (yy - 24) ** 2) ** 0.5
    z[:3, :3] = -32767.0
    crs = (
        "+proj=eqc +lat_ts=18.4 +lat_0=0 +lon_0=77.5 +x_0=0 +y_0=0 "
        "+R=3394839.8 +units=m +no_defs"
    )
    path = tmp_path / "bowl.tif"
    with rasterio.open(
        path, "w", driver="GTiff", height=rows, width=cols, count=1, dtype="float32",
        crs=crs, transform=Affine(1.0, 0.0, -32.0, 0.0, -1.0, 1_090_000.0), nodata=-32767.0,
    ) as ds:
        ds.write(z.astype(np.float32), 1)
    return path
