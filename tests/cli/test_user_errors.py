"""User mistakes and edge inputs (issue 13 part 4): one-line errors, plain numbers in messages,
a warning for DEMs without geo-reference, and manifests that do not depend on where files live."""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene._validate import check_range
from marsscene.cli import main
from marsscene.errors import ConfigError, CRSError, NoGeoreferenceWarning, RuntimeSimError

pytest.importorskip("pxr")

_SMALL = ["--procedural", "--size-m", "20", "20", "--format", "mjcf"]


def _no_crs_dem(path: Path) -> Path:
    import rasterio
    from rasterio.transform import from_origin

    z = np.add.outer(np.arange(40.0), np.arange(50.0)).astype(np.float32) * 0.05
    with rasterio.open(path, "w", driver="GTiff", height=40, width=50, count=1,
                       dtype="float32", transform=from_origin(0.0, 40.0, 1.0, 1.0)) as ds:
        ds.write(z, 1)
    return path


def test_unwritable_output_folder_is_a_one_line_error(runner: CliRunner) -> None:
    result = runner.invoke(main, ["build", *_SMALL, "--out", "/proc/marsscene-x/out"])
    assert result.exit_code == 1
    assert result.output.startswith("Error: cannot write the output folder /proc/marsscene-x")
    assert result.output.count("\n") == 1 and "Traceback" not in result.output
    assert not isinstance(result.exception, OSError | AssertionError)


def test_messages_print_plain_numbers_not_numpy_reprs() -> None:
    with pytest.raises(ConfigError) as err:
        check_range("terrain.post_m", np.float64(-1.5), 0.0, np.float32(10.0))
    assert str(err.value) == "terrain.post_m = -1.5 is out of range; allowed [0.0, 10.0]"
    from marsscene.runs.tum import Trajectory

    pose = np.tile([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0], (3, 1))
    with pytest.raises(RuntimeSimError) as terr:
        Trajectory(np.array([0.0, 1.0, 1.0]), pose[:, :3], pose[:, 3:])
    assert "timestamp 1.0 s does not increase (previous 1.0 s)" in str(terr.value)
    assert "np." not in str(terr.value)


def test_lonlat_crop_on_a_dem_without_crs_says_it_has_no_georeference(
    runner: CliRunner, tmp_path: Path
) -> None:
    dem = _no_crs_dem(tmp_path / "nocrs.tif")
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": str(dem),
                                                "crop_lonlat": [77.0, 18.0],
                                                "size_m": [10.0, 10.0]}})
    with pytest.raises(CRSError, match="no geo-reference"):
        ms.build_scene(cfg, seed=0)
    result = runner.invoke(main, ["build", "--dem", str(dem), "--crop-lonlat", "77", "18",
                                  "--size-m", "10", "10", "--out", str(tmp_path / "o")])
    assert result.exit_code == 1 and "unusable CRS" not in result.output
    assert "Error: the DEM has no geo-reference (no CRS)" in result.output
    assert not (tmp_path / "o").exists()


def test_dem_without_crs_warns_once_and_names_the_sun_site(tmp_path: Path) -> None:
    dem = _no_crs_dem(tmp_path / "nocrs.tif")
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": str(dem)},
                                    "rocks": {"enabled": False}})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = ms.build_scene(cfg, seed=0)
    ours = [w for w in caught if issubclass(w.category, NoGeoreferenceWarning)]
    assert len(ours) == 1
    assert "nocrs.tif has no geo-reference" in str(ours[0].message)
    assert "default site" in str(ours[0].message)
    assert scene.lighting is not None
    from marsscene.lighting.config import DEFAULT_SITE_LAT_LON_EAST_DEG

    lat, _ = DEFAULT_SITE_LAT_LON_EAST_DEG
    assert scene.lighting.site_lat_deg == pytest.approx(lat)
    # with the site given, the warning says nothing about the sun
    cfg2 = cfg.replace(lighting=ms.lighting.LightingConfig(site_lat_deg=0.0,
                                                           site_lon_east_deg=10.0))
    with pytest.warns(NoGeoreferenceWarning) as rec:
        ms.build_scene(cfg2, seed=0)
    assert all("default site" not in str(w.message) for w in rec)


def test_georeferenced_dem_does_not_warn(synthetic_dem_path: Path) -> None:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "dem",
                                                "dem_path": str(synthetic_dem_path)}})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ms.build_scene(cfg, seed=0)
    assert not [w for w in caught if issubclass(w.category, NoGeoreferenceWarning)]


def test_manifest_is_the_same_in_two_checkouts(
    runner: CliRunner, tmp_path: Path, synthetic_dem_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    docs = []
    for name in ("checkout_a", "checkout_b"):
        root = tmp_path / name
        root.mkdir()
        shutil.copy(synthetic_dem_path, root / "dem.tif")
        monkeypatch.chdir(root)
        result = runner.invoke(main, ["build", "--dem", "dem.tif", "--format", "mjcf",
                                      "--seed", "3", "--out", "scene"])
        assert result.exit_code == 0, result.output
        doc = json.loads((root / "scene" / "manifest.json").read_text())
        doc.pop("timings_s")
        docs.append(doc)
    assert docs[0] == docs[1]
    assert docs[0]["inputs"]["dem"]["name"] == "dem.tif"
    assert str(tmp_path) not in json.dumps(docs[0])
