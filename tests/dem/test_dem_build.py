"""End to end: PDS3 DTM + HiRISE JP2 ortho -> scene -> USD / MJCF, co-registration, CLI."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.testing.pds3 import write_hirise_ortho, write_pds3_dtm
from tests.dem.conftest import real

# DEM upper-left corner and the ground point of a feature drawn into both rasters (projected m,
# on the real ESP_013951_1955 label's sphere: lat_ts 15 N, lon_0 180, R 3394839.8133163 m)
X0, Y0 = -6_139_000.0, 936_000.0
XB, YB = X0 + 71.3, Y0 - 48.6
LABEL_SPHERE = {"center_lat": 15.0, "center_lon": 180.0, "radius_km": 3394.8398133163}


@pytest.fixture
def dem_and_ortho(tmp_path: Path, gale_z: np.ndarray) -> tuple[Path, Path]:
    rows, cols = gale_z.shape
    y, x = np.mgrid[0:rows, 0:cols]
    r2 = (X0 + x + 0.5 - XB) ** 2 + (Y0 - y - 0.5 - YB) ** 2
    z = gale_z + 60.0 * np.exp(-r2 / (2 * 2.5**2))
    z[0, :3] = np.nan
    dem = write_pds3_dtm(tmp_path / "DTEEC_COREG.IMG", z.astype(np.float32),
                         spo=-X0 - 0.5, lpo=Y0 - 0.5, **LABEL_SPHERE)
    # 0.5 m ortho whose grid is offset from the DEM's by a non-integer number of pixels
    ox0, oy0 = X0 - 10.25, Y0 + 8.75
    orows, ocols = 280, 360
    oy, ox = np.mgrid[0:orows, 0:ocols]
    xo, yo = ox0 + (ox + 0.5) * 0.5, oy0 - (oy + 0.5) * 0.5
    dn = 300 + (xo - X0) + 0.5 * (Y0 - yo)
    dn[np.hypot(xo - XB, yo - YB) < 5.0] = 1000.0  # > 0.5 % of the texture: above the stretch
    dn[:4] = 0  # CORE_NULL stripe outside the footprint
    lbl = write_hirise_ortho(tmp_path, dn, template=real("labels", "GDAL_ESP_013951_1955_RED.LBL"),
                             x0_m=ox0, y0_m=oy0, scale_m=0.5)
    return dem, lbl


def _config(dem: Path, ortho: Path) -> ms.SceneConfig:
    return ms.SceneConfig.from_dict({"terrain": {
        "source": "dem", "dem_path": str(dem), "ortho_path": str(ortho), "detail": False,
        "crop_px": [10, 20, 100, 120]}})


def test_feature_lands_on_same_world_point(dem_and_ortho: tuple[Path, Path]) -> None:
    scene = ms.build_scene(_config(*dem_and_ortho), seed=3)
    hf, frame = scene.heightfield, scene.provenance.frame
    assert frame.origin_projected_xy_m is not None
    want = (XB - frame.origin_projected_xy_m[0], YB - frame.origin_projected_xy_m[1])
    # terrain: centroid of the bump
    z = hf.z_m.astype(np.float64)
    r0, c0 = np.unravel_index(int(np.argmax(z)), z.shape)
    win = z[r0 - 6:r0 + 7, c0 - 6:c0 + 7]
    w = np.clip(win - (win.max() - 30.0), 0, None)
    rr, cc = np.mgrid[r0 - 6:r0 + 7, c0 - 6:c0 + 7]
    hx, hy = hf.xy_of((w * rr).sum() / w.sum(), (w * cc).sum() / w.sum())
    assert np.hypot(hx - want[0], hy - want[1]) < 0.3
    # texture: centroid of the bright disc, mapped through st (s east, t north, pixel edges)
    tex = scene.texture_rgb
    assert tex is not None and tex.dtype == np.uint8 and tex.shape == (198, 238, 3)
    bright = (tex[:, :, 0] > 200).astype(np.float64)
    tr, tc = np.mgrid[0:tex.shape[0], 0:tex.shape[1]]
    s = ((bright * tc).sum() / bright.sum() + 0.5) / tex.shape[1]
    t = 1.0 - ((bright * tr).sum() / bright.sum() + 0.5) / tex.shape[0]
    x0, y0, x1, y1 = hf.bounds_xy_m
    tx, ty = x0 + s * (x1 - x0), y0 + t * (y1 - y0)
    assert np.hypot(tx - want[0], ty - want[1]) < 0.3
    assert scene.provenance.extra["dem_filled_posts"] == 0  # the NaN corner is cropped away
    assert scene.provenance.inputs["ortho"].endswith(".LBL")


def test_usd_and_mjcf_carry_the_ortho(tmp_path: Path, dem_and_ortho: tuple[Path, Path]) -> None:
    pytest.importorskip("pxr")
    pytest.importorskip("mujoco")
    from pxr import Usd, UsdGeom

    from marsscene.export.mjcf import validate_mjcf
    from marsscene.export.usd import validate_stage

    scene = ms.build_scene(_config(*dem_and_ortho), seed=3)
    out = tmp_path / "scene"
    ms.write_scene(scene, out, formats=("usd", "mjcf"))
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    assert validate_stage(stage) == []
    tex = stage.GetPrimAtPath("/World/Terrain/Looks/Regolith/Albedo")
    assert tex.IsValid() and (out / "textures/terrain_albedo.png").is_file()
    from PIL import Image

    with Image.open(out / "textures/terrain_albedo.png") as png:  # lossless, the same pixels
        assert np.array_equal(np.asarray(png.convert("RGB")), scene.texture_rgb)
    # the vertex nearest the feature has st inside a bright texture pixel
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Terrain/tile_0_0"))
    pts = np.asarray(mesh.GetPointsAttr().Get())
    st = np.asarray(UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st").Get())
    ox, oy = scene.provenance.frame.origin_projected_xy_m or (0.0, 0.0)
    i = int(np.argmin(np.hypot(pts[:, 0] - (XB - ox), pts[:, 1] - (YB - oy))))
    image = scene.texture_rgb
    assert image is not None
    row = int((1.0 - st[i, 1]) * image.shape[0])
    col = int(st[i, 0] * image.shape[1])
    assert image[row, col, 0] > 200
    xml = (out / "mjcf/scene.xml").read_text()
    assert 'file="assets/terrain_albedo.png"' in xml and (out / "mjcf/assets/terrain_albedo.png"
                                                          ).is_file()
    validate_mjcf(out / "mjcf/scene.xml", seconds=0.1)


def test_build_is_deterministic(dem_and_ortho: tuple[Path, Path]) -> None:
    a = ms.build_scene(_config(*dem_and_ortho), seed=3)
    b = ms.build_scene(_config(*dem_and_ortho), seed=3)
    assert a.texture_rgb is not None and b.texture_rgb is not None
    assert a.texture_rgb.tobytes() == b.texture_rgb.tobytes()
    assert a.heightfield.z_m.tobytes() == b.heightfield.z_m.tobytes()


def test_cli_build_with_dem_ortho_and_crop(tmp_path: Path, runner,  # type: ignore[no-untyped-def]
                                           dem_and_ortho: tuple[Path, Path]) -> None:
    from marsscene.cli import main

    dem, lbl = dem_and_ortho
    out = tmp_path / "cli"
    res = runner.invoke(main, ["-q", "build", "--dem", str(dem), "--ortho", str(lbl),
                               "--crop-px", "10", "20", "60", "80", "--post-m", "2",
                               "--z-scale", "1.5", "--format", "mjcf", "--out", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "manifest.json").read_text())
    assert doc["terrain"]["post_m"] == 2.0 and doc["terrain"]["shape_rows_cols"] == [30, 40]
    assert doc["frame"]["z_scale"] == 1.5
    assert doc["config"]["terrain"]["crop_px"] == [10, 20, 60, 80]
    assert set(doc["inputs"]) == {"dem", "ortho", "ortho_data"}
    assert doc["inputs"]["ortho_data"]["name"].endswith(".JP2")
    assert len(doc["inputs"]["ortho_data"]["sha256"]) == 64
    assert doc["summary"]["dem_product_id"] == "DTEEC_045994_1985_046060_1985_U01"


def test_cli_lonlat_crop_of_default_dem(tmp_path: Path, runner) -> None:  # type: ignore[no-untyped-def]
    from marsscene.cli import main

    out = tmp_path / "gale"
    res = runner.invoke(main, ["-q", "build", "--crop-lonlat", "137.3702", "-4.6671", "--size-m",
                               "40", "30", "--post-m", "1", "--format", "mjcf", "--out", str(out)])
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "manifest.json").read_text())
    assert doc["terrain"]["size_m"] == [40.0, 30.0]
    lon, lat = doc["frame"]["origin_lonlat_deg"]
    assert abs(lon - 137.3702) < 2e-5 and abs(lat + 4.6671) < 2e-5


def test_cli_errors(tmp_path: Path, runner) -> None:  # type: ignore[no-untyped-def]
    from marsscene.cli import main

    cub = real("isis_hidtmgen", "DTM_2Bands_cropped.cub")
    res = runner.invoke(main, ["build", "--dem", str(cub), "--out", str(tmp_path / "x")])
    assert res.exit_code == 1 and "2 bands" in res.output and "--band" in res.output
    res = runner.invoke(main, ["build", "--crop-lonlat", "137.37", "-4.667",
                               "--out", str(tmp_path / "y")])
    assert res.exit_code == 2 and "--size-m" in res.output
    res = runner.invoke(main, ["build", "--crop-lonlat", "10", "10", "--size-m", "5", "5",
                               "--out", str(tmp_path / "z")])
    assert res.exit_code == 1 and "outside the DEM" in res.output
    res = runner.invoke(main, ["build", "--post-m", "0.01", "--out", str(tmp_path / "m")])
    assert res.exit_code == 1 and "GB" in res.output and "budget" in res.output
    assert not (tmp_path / "m").exists()


def test_whole_dem_over_budget_is_auto_cropped(tmp_path: Path) -> None:
    from marsscene.dem.ops import AutoCropWarning

    rng = np.random.default_rng(5)
    z = (-2500 + np.cumsum(rng.standard_normal((1500, 1200)), axis=1) * 0.05).astype(np.float32)
    path = write_pds3_dtm(tmp_path / "DTEEC_BIG.IMG", z)
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": str(path),
                                                "max_memory_gb": 0.25}})
    with pytest.warns(AutoCropWarning, match=r"about 0\.3 GB"):
        scene = ms.build_scene(cfg, seed=0)
    assert scene.heightfield.shape == (1001, 1001)
    assert scene.provenance.extra["dem_window_rows_cols"] == [250, 100, 1001, 1001]


def test_toml_keys_and_relative_paths(tmp_path: Path, dem_and_ortho: tuple[Path, Path]) -> None:
    dem, lbl = dem_and_ortho
    toml = tmp_path / "site.toml"
    toml.write_text(
        "[terrain]\n"
        'source = "dem"\n'
        f'dem_path = "{dem.name}"\n'
        f'ortho_path = "{lbl.name}"\n'
        "crop_bounds_m = [-6138980.0, 935900.0, -6138900.0, 935960.0]\n"
        "post_m = 2.0\n"
        'resampling = "area"\n'
        "texture_max_px = 64\n"
    )
    cfg = ms.SceneConfig.from_toml(toml)
    assert cfg.terrain.dem_path == str(dem.resolve())
    assert cfg.terrain.ortho_path == str(lbl.resolve())
    scene = ms.build_scene(cfg, seed=1)
    # bounds keep posts with centres inside: x -6138979.5 .. -6138900.5 (80 posts, 79 m)
    assert scene.heightfield.size_m == (78.0, 58.0) and scene.heightfield.cell_size_m == 2.0
    assert scene.texture_rgb is not None and max(scene.texture_rgb.shape[:2]) == 64
    with pytest.raises(ms.MarsSceneError, match="crop_px, crop_bounds_m"):
        ms.SceneConfig.from_dict({"terrain": {"source": "dem", "dem_path": "x.img",
                                              "crop_px": [0, 0, 4, 4],
                                              "crop_bounds_m": [0, 0, 1, 1]}})
    with pytest.raises(ms.MarsSceneError, match="needs a DEM"):
        ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "ortho_path": "o.tif"}})
