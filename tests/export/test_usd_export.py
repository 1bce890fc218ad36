"""USD round trip: re-open the written stage with pxr and check what Isaac Sim relies on."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import marsscene as ms

pxr = pytest.importorskip("pxr")
from pxr import Usd, UsdGeom, UsdPhysics  # noqa: E402

from marsscene.export.usd import validate_stage  # noqa: E402


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    cfg = ms.SceneConfig.from_dict(
        {
            "terrain": {"source": "procedural", "size_m": [30.0, 20.0], "post_m": 0.25},
            "export": {"max_tile_posts": 33},
            "rocks": {"enabled": False},
            "craters": {"enabled": False},
        }
    )
    scene = ms.build_scene(cfg, seed=3)
    out = tmp_path_factory.mktemp("usd") / "scene"
    ms.write_scene(scene, out, formats=("usd",))
    return scene, out


def test_stage_metrics_default_prim_and_provenance(written: tuple[ms.Scene, Path]) -> None:
    scene, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert UsdPhysics.GetStageKilogramsPerUnit(stage) == 1.0
    assert stage.GetDefaultPrim().GetPath() == "/World"
    data = stage.GetRootLayer().customLayerData
    assert data["marsscene:seed"] == 3
    assert data["marsscene:configHash"] == scene.config.config_hash()
    assert data["creator"].startswith("marsscene ")


def test_physics_scene_has_mars_gravity(written: tuple[ms.Scene, Path]) -> None:
    _, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    phys = UsdPhysics.Scene(stage.GetPrimAtPath("/World/PhysicsScene"))
    assert phys.GetGravityMagnitudeAttr().Get() == pytest.approx(3.72)
    assert tuple(phys.GetGravityDirectionAttr().Get()) == (0.0, 0.0, -1.0)


def test_terrain_tiles_match_the_heightfield(written: tuple[ms.Scene, Path]) -> None:
    scene, out = written
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    hf = scene.heightfield
    meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    rows, cols = hf.shape
    assert len(meshes) == int(np.ceil((rows - 1) / 32)) * int(np.ceil((cols - 1) / 32))
    n_faces = 0
    for mesh in meshes:
        pts = np.asarray(mesh.GetPointsAttr().Get())
        assert len(pts) <= 33 * 33
        assert len(np.asarray(mesh.GetNormalsAttr().Get())) == len(pts)
        st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st").Get()
        assert len(st) == len(pts)
        assert mesh.GetPrim().HasAPI(UsdPhysics.CollisionAPI)
        np.testing.assert_allclose(pts[:, 2], hf.sample(pts[:, 0], pts[:, 1]), atol=1e-5)
        n_faces += len(mesh.GetFaceVertexCountsAttr().Get())
    assert n_faces == 2 * (rows - 1) * (cols - 1)


def test_usd_validation_reports_no_errors(written: tuple[ms.Scene, Path]) -> None:
    _, out = written
    assert validate_stage(Usd.Stage.Open(str(out / "scene.usda"))) == []


@pytest.mark.parametrize("usd_format", ["usdc", "usdz"])
def test_binary_and_packaged_formats_open(tmp_path: Path, usd_format: str) -> None:
    cfg = ms.SceneConfig.from_dict(
        {"terrain": {"source": "procedural", "size_m": [8.0, 8.0], "post_m": 0.5},
         "export": {"usd_format": usd_format, "formats": ["usd"]},
         "rocks": {"enabled": False}, "craters": {"enabled": False}}
    )
    ms.write_scene(ms.build_scene(cfg, seed=1), tmp_path / "s")
    if usd_format == "usdz":  # everything is packaged: no loose assets or empty folders
        assert sorted(p.name for p in (tmp_path / "s").iterdir()) == ["manifest.json",
                                                                       "scene.usdz"]
    stage = Usd.Stage.Open(str(tmp_path / "s" / f"scene.{usd_format}"))
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    assert len(meshes) == 1
    assert validate_stage(stage) == []


def test_background_threads_do_not_change_the_written_files(
    written: tuple[ms.Scene, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every file but the manifest (which holds timings) is the same bytes whether the tiles
    and textures are made on background threads (big terrains) or on one thread (small ones,
    as the fixture's)."""
    import threading

    import marsscene._threads as threads

    scene, out = written
    assert not threads.worth_a_thread(scene.heightfield.z_m.size)
    monkeypatch.setattr(threads, "THREADED_MIN_POSTS", 1)
    seen: set[str] = set()
    start = threading.Thread.start

    def spy(self: threading.Thread) -> None:
        seen.add(self.name.rsplit("_", 1)[0])
        start(self)

    monkeypatch.setattr(threading.Thread, "start", spy)
    ms.write_scene(scene, tmp_path / "threaded", formats=("usd",))
    assert {"marsscene-tiles", "marsscene-textures"} <= seen  # the threaded path ran
    files = [p.relative_to(out) for p in sorted(out.rglob("*")) if p.is_file()
             and p.name != "manifest.json"]
    assert Path("assets/terrain.usdc") in files
    assert Path("textures/regolith_detail_normal.png") in files
    for rel in files:
        assert (tmp_path / "threaded" / rel).read_bytes() == (out / rel).read_bytes(), rel
