"""Craters through the pipeline and the exporters (USD points prim, CSV catalogue)."""

from __future__ import annotations

import csv
import io
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.errors import ExtrapolationWarning


def _cfg(**craters: object) -> ms.SceneConfig:
    c = {"d_min_m": 1.0, "d_max_m": 8.0, "system": "hartmann-daubar-2016"}
    c.update(craters)
    return ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [40.0, 30.0], "post_m": 0.25},
        "craters": c, "rocks": {"enabled": False}, "lighting": {"enabled": False},
    })


def test_pipeline_sets_craters_and_manifest_models() -> None:
    cfg = _cfg()
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExtrapolationWarning)  # HD2016 covers 1-8 m
        scene = ms.build_scene(cfg, seed=3)
    assert scene.craters is not None and len(scene.craters) > 5
    names = [m.name for m in scene.provenance.models if m.stage == "craters"]
    assert "production function hartmann-daubar-2016" in names
    assert any("equilibrium" in n for n in names)
    assert scene.provenance.extra["craters"]["count"] == len(scene.craters)
    flat = ms.build_scene(_cfg(enabled=False), seed=3)
    assert flat.craters is None
    assert not np.array_equal(flat.heightfield.z_m, scene.heightfield.z_m)
    # the crater stream is the stage's own: the terrain is identical before stamping
    assert flat.heightfield.shape == scene.heightfield.shape


def test_extrapolation_is_warned_and_noted() -> None:
    with pytest.warns(ExtrapolationWarning):
        scene = ms.build_scene(_cfg(system="neukum-ivanov-2001"), seed=1)
    assert any("outside its validity range" in n for n in scene.provenance.notes)


def test_same_seed_same_craters_and_bytes(tmp_path: Path) -> None:
    cfg = _cfg()
    a = ms.build_scene(cfg, seed=5)
    np.random.default_rng(0).random(5)
    b = ms.build_scene(cfg, seed=5)
    np.testing.assert_array_equal(a.craters.center_xy_m, b.craters.center_xy_m)
    np.testing.assert_array_equal(a.heightfield.z_m, b.heightfield.z_m)
    c = ms.build_scene(cfg, seed=6)
    assert not np.array_equal(a.craters.center_xy_m[:1], c.craters.center_xy_m[:1])
    ms.write_scene(a, tmp_path / "a", formats=("usd",))
    ms.write_scene(b, tmp_path / "b", formats=("usd",))
    for name in ("craters.csv", "scene.usda"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_usd_points_prim_round_trip(tmp_path: Path) -> None:
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    from marsscene.export.usd import validate_stage

    scene = ms.build_scene(_cfg(axis_ratio_min=0.8), seed=2)
    ms.write_scene(scene, tmp_path / "s", formats=("usd",))
    stage = Usd.Stage.Open(str(tmp_path / "s" / "scene.usda"))
    assert validate_stage(stage) == []
    prim = stage.GetPrimAtPath("/World/Craters")
    pts = UsdGeom.Points(prim)
    assert pts.GetPurposeAttr().Get() == UsdGeom.Tokens.guide
    t = scene.craters
    xyz = np.array(pts.GetPointsAttr().Get())
    np.testing.assert_allclose(xyz[:, :2], t.center_xy_m, atol=1e-4)
    np.testing.assert_allclose(xyz[:, 2], scene.heightfield.sample(*t.center_xy_m.T), atol=1e-4)
    np.testing.assert_allclose(np.array(pts.GetWidthsAttr().Get()), t.diameter_m, rtol=1e-6)
    api = UsdGeom.PrimvarsAPI(prim)
    for name, col in (("depth_m", t.depth_m), ("age_ga", t.age_ga), ("axisRatio", t.axis_ratio)):
        pv = api.GetPrimvar(f"marsscene:crater:{name}")
        assert pv.IsIndexed()
        got = np.array(pv.ComputeFlattened())
        np.testing.assert_allclose(got, col, rtol=1e-6, atol=1e-7)
    assert prim.GetAttribute("marsscene:crater:count").Get() == len(t)
    assert prim.GetAttribute("marsscene:crater:system").Get() == "hartmann-daubar-2016"


def test_csv_catalogue_xy_and_lonlat(tmp_path: Path) -> None:
    scene = ms.build_scene(_cfg(), seed=4)
    ms.write_scene(scene, tmp_path / "p", formats=("mjcf",))
    rows = list(csv.DictReader(io.StringIO((tmp_path / "p" / "craters.csv").read_text())))
    assert len(rows) == len(scene.craters) and "lon_deg" not in rows[0]  # procedural: no frame
    np.testing.assert_allclose([float(r["diameter_m"]) for r in rows], scene.craters.diameter_m,
                               atol=1e-4)
    inside = [int(r["in_scene"]) for r in rows]
    assert 0 < sum(inside) < len(rows)
    manifest = json.loads((tmp_path / "p" / "manifest.json").read_text())
    assert "craters.csv" in manifest["outputs"]


def test_csv_lonlat_inverts_with_frame() -> None:
    from dataclasses import replace

    from marsscene.craters.geo import lonlat_to_xy_m
    from marsscene.export.catalog_craters import crater_catalog_text
    from marsscene.terrain.from_dem import GeoFrame

    scene = ms.build_scene(_cfg(), seed=4)
    frame = GeoFrame(0.0, (0.0, 0.0), (137.37, -4.67), "", 1.0)
    geo = replace(scene, provenance=replace(scene.provenance, frame=frame))
    rows = list(csv.DictReader(io.StringIO(crater_catalog_text(geo))))
    lon = np.array([float(r["lon_deg"]) for r in rows])
    lat = np.array([float(r["lat_deg"]) for r in rows])
    x, y = lonlat_to_xy_m(lon, lat, origin_lonlat_deg=(137.37, -4.67))
    np.testing.assert_allclose(np.c_[x, y], scene.craters.center_xy_m, atol=2e-3)
    # 1 m north = 1 / (R * pi / 180) degrees of latitude on the Mars 2000 sphere
    assert (lat.max() - lat.min()) == pytest.approx(
        np.ptp(scene.craters.center_xy_m[:, 1]) * 180 / (np.pi * 3_396_190.0), rel=1e-4)
