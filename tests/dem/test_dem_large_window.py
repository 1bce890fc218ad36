"""A DTM far larger than the build reads only the crop's window: a 40000 x 40000 float32
GeoTIFF (6.4 GB of samples, tiled and sparse on disk, so the test file is small) is cropped
and built in a child process whose peak memory stays far below the raster's size."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

N = 40_000  # posts per side; 1 m posts -> a 40 km x 40 km DTM
BLOCK = 3000  # written data: the central 3 km, the rest of the file is sparse (nodata)

# Peak memory of the child alone: VmHWM of its own address space. (ru_maxrss is no good here:
# Linux carries a forked parent's resident size into the child's ru_maxrss at exec.)
CHILD = r"""
import json, sys, warnings
import numpy as np
import marsscene as ms
path, size = sys.argv[1], float(sys.argv[2])
terrain = {"source": "dem", "dem_path": path, "post_m": 1.0, "detail": False}
if size > 0:
    terrain["size_m"] = [size, size]
cfg = ms.SceneConfig.from_dict({"terrain": terrain, "craters": {"enabled": False},
                                "rocks": {"enabled": False}, "lighting": {"enabled": False}})
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    scene = ms.build_scene(cfg, seed=0)
z = scene.heightfield.z_m
print(json.dumps({"shape": list(z.shape), "mean": float(z.mean()), "ptp": float(np.ptp(z)),
                  "peak_mb": int(next(line.split()[1] for line in open("/proc/self/status")
                                      if line.startswith("VmHWM:"))) / 1024,
                  "warnings": [type(w.message).__name__ for w in caught],
                  "window": scene.provenance.extra.get("dem_window_rows_cols")}))
"""


@pytest.fixture(scope="module")
def huge_dtm(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import rasterio
    from affine import Affine
    from rasterio.windows import Window

    path = tmp_path_factory.mktemp("huge") / "huge.tif"
    crs = "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=150 +x_0=0 +y_0=0 +R=3396190 +units=m +no_defs"
    off = N // 2 - BLOCK // 2
    yy, xx = np.mgrid[0:BLOCK, 0:BLOCK].astype(np.float32)
    block = -2500.0 + 0.01 * xx + 0.005 * yy  # a gentle plane: 30 m and 15 m across
    with rasterio.open(path, "w", driver="GTiff", width=N, height=N, count=1, dtype="float32",
                       crs=crs, transform=Affine(1.0, 0, -N / 2, 0, -1.0, N / 2), nodata=-32767.0,
                       tiled=True, blockxsize=256, blockysize=256, SPARSE_OK=True) as ds:
        ds.write(block, 1, window=Window(off, off, BLOCK, BLOCK))
    assert path.stat().st_size < 100e6  # sparse: only the written tiles take space
    return path


def _child(path: Path, size_m: float) -> dict:  # type: ignore[type-arg]
    res = subprocess.run([sys.executable, "-c", CHILD, str(path), str(size_m)],
                         capture_output=True, text=True, timeout=300, check=True)
    out: dict = json.loads(res.stdout.strip().splitlines()[-1])  # type: ignore[type-arg]
    return out


def test_crop_reads_only_its_window(huge_dtm: Path) -> None:
    out = _child(huge_dtm, 500.0)
    assert out["shape"] == [501, 501]
    assert out["window"] == [N // 2 - 250, N // 2 - 250, 501, 501]
    # the centre of the plane, relative to the datum: exact values, not nodata fill
    assert out["ptp"] == pytest.approx(0.01 * 500 + 0.005 * 500, abs=0.01)
    # a full read would hold 6.4 GB of float32 samples; the crop build stays far below
    assert out["peak_mb"] < 1000.0


def test_whole_dtm_without_crop_is_auto_cropped_by_window(huge_dtm: Path) -> None:
    out = _child(huge_dtm, 0.0)
    assert out["shape"] == [1001, 1001]  # AUTO_CROP_M = 1 km, read by window
    assert "AutoCropWarning" in out["warnings"]
    assert out["peak_mb"] < 1000.0
