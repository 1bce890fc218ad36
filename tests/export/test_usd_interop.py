"""USD for other clients: NVIDIA's Omniverse Asset Validator (default rules) on every USD
encoding, physics materials equal to the MJCF contact, the ``kind`` model hierarchy, extents."""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pxr = pytest.importorskip("pxr")
from pxr import Kind, Usd, UsdGeom, UsdPhysics, UsdShade  # noqa: E402

CFG = {
    "terrain": {"source": "procedural", "size_m": [100.0, 100.0], "post_m": 1.0},
    "rocks": {"k": 0.05, "d_min_m": 0.3},  # 123 collider prims (D >= 0.5 m), 4 merged meshes
    "craters": {"d_min_m": 1.0},
    "export": {"max_tile_posts": 33, "rover": True},
}


@pytest.fixture(scope="module")
def scene() -> ms.Scene:
    return ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=11)


@pytest.fixture(scope="module")
def written(scene: ms.Scene, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("interop") / "scene"
    ms.write_scene(scene, out)
    return out


@pytest.mark.parametrize("usd_format", ["usda", "usdc", "usdz"])
def test_asset_validator_reports_no_issues(scene: ms.Scene, tmp_path: Path,
                                           usd_format: str) -> None:
    validator = pytest.importorskip("omni.asset_validator")
    assert scene.rocks is not None and len(scene.rocks) > 100
    assert scene.craters is not None and len(scene.craters) > 64  # > the ASCII array limit
    export = dataclasses.replace(scene.config.export, usd_format=usd_format)
    variant = dataclasses.replace(scene, config=scene.config.replace(export=export))
    ms.write_scene(variant, tmp_path / "s", formats=("usd",))
    results = validator.ValidationEngine().validate(str(tmp_path / "s" / f"scene.{usd_format}"))
    assert [str(issue) for issue in results.issues()] == []


def _mjcf_friction(out: Path, material: str) -> float:
    root = ET.parse(out / "mjcf" / "scene.xml").getroot()
    frictions = {float(g.attrib["friction"].split()[0]) for g in root.iter("geom")
                 if g.attrib.get("material") == material}
    assert len(frictions) == 1
    return frictions.pop()


def _physics_material(prim: Usd.Prim) -> UsdPhysics.MaterialAPI:
    mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial("physics")
    assert mat, f"no physics material bound to {prim.GetPath()}"
    assert mat.GetPrim().HasAPI(UsdPhysics.MaterialAPI)
    return UsdPhysics.MaterialAPI(mat.GetPrim())


def test_physics_materials_match_the_mjcf_contact(written: Path) -> None:
    stage = Usd.Stage.Open(str(written / "scene.usda"))
    tiles = [p for p in stage.GetPrimAtPath("/World/Terrain").GetChildren() if p.IsA(UsdGeom.Mesh)]
    colliders = [p for p in Usd.PrimRange(stage.GetPrimAtPath("/World/RockColliders"),
                                          Usd.TraverseInstanceProxies())
                 if p.HasAPI(UsdPhysics.CollisionAPI)]
    assert not [p for p in Usd.PrimRange(stage.GetPrimAtPath("/World/Rocks"))
                if p.HasAPI(UsdPhysics.CollisionAPI)]  # the render instancer carries none
    assert tiles and colliders
    for prims, material in ((tiles, "regolith"), (colliders, "rock")):
        mu = _mjcf_friction(written, material)
        for prim in prims:
            api = _physics_material(prim)
            assert api.GetStaticFrictionAttr().Get() == pytest.approx(mu)
            assert api.GetDynamicFrictionAttr().Get() == pytest.approx(mu)
            assert api.GetRestitutionAttr().Get() == 0.0
    for tile in tiles:  # the render binding is still the surface material
        render, _ = UsdShade.MaterialBindingAPI(tile).ComputeBoundMaterial()
        assert render.GetPath().name == "Regolith"
    def approx(prims: list[Usd.Prim]) -> set[str]:
        return {UsdPhysics.MeshCollisionAPI(p).GetApproximationAttr().Get() for p in prims}

    merged = [p for p in colliders if "/Merged/" in str(p.GetPath())]
    assert merged and approx(tiles) == approx(merged) == {"none"}  # static triangle meshes
    assert approx([p for p in colliders if p not in merged]) == {"convexHull"}  # obstacles


def test_kind_hierarchy_and_extents(written: Path) -> None:
    stage = Usd.Stage.Open(str(written / "scene.usda"))
    kinds = {p: Usd.ModelAPI(stage.GetPrimAtPath(p)).GetKind() for p in
             ("/World", "/World/Terrain", "/World/Rocks", "/World/RockColliders",
              "/World/Lights", "/World/Cameras", "/World/Rover")}
    assert kinds == {"/World": Kind.Tokens.assembly, "/World/Terrain": Kind.Tokens.component,
                     "/World/Rocks": Kind.Tokens.component,
                     "/World/RockColliders": Kind.Tokens.component,
                     "/World/Lights": Kind.Tokens.group, "/World/Cameras": Kind.Tokens.group,
                     "/World/Rover": Kind.Tokens.component}
    components = [p.GetPath() for p in stage.Traverse() if Usd.ModelAPI(p).IsKind("component")]
    assert sorted(map(str, components)) == ["/World/RockColliders", "/World/Rocks",
                                            "/World/Rover", "/World/Terrain"]
    for prim in stage.Traverse():  # every boundable prim carries its authored extent
        if prim.IsA(UsdGeom.Boundable):
            ext = np.asarray(UsdGeom.Boundable(prim).GetExtentAttr().Get())
            assert ext.shape == (2, 3) and np.all(ext[1] >= ext[0]), prim.GetPath()
    craters = UsdGeom.Points(stage.GetPrimAtPath("/World/Craters"))
    pts = np.asarray(craters.GetPointsAttr().Get())
    ext = np.asarray(craters.GetExtentAttr().Get())
    assert np.all(pts >= ext[0]) and np.all(pts <= ext[1])


def test_every_usd_file_is_byte_reproducible(scene: ms.Scene, tmp_path: Path) -> None:
    export = dataclasses.replace(scene.config.export, usd_format="usdc")
    variant = dataclasses.replace(scene, config=scene.config.replace(export=export))
    for sub in ("a", "b"):
        ms.write_scene(variant, tmp_path / sub, formats=("usd",))
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*")
                   if p.is_file() and p.name != "manifest.json")
    assert {f.as_posix() for f in files} >= {"scene.usdc", "assets/terrain.usdc",
                                             "assets/rocks.usdc", "assets/craters.usdc",
                                             "assets/rock_colliders.usdc", "assets/rover.usda"}
    for f in files:
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
