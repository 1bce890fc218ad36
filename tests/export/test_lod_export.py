"""Level-of-detail scenes through the real tools: pxr (payload tiles, footprint, validator),
MuJoCo (two hfields, a dropped box, a short drive), byte reproducibility."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pxr")
mujoco = pytest.importorskip("mujoco")

import marsscene as ms  # noqa: E402
from marsscene.export.mjcf.terrain_lod import HOLE_DEPTH_M  # noqa: E402
from marsscene.export.usd import validate_stage  # noqa: E402
from marsscene.export.usd.terrain_lod import LOD_ATTR  # noqa: E402
from tests.mjcf_drop import drop_box  # noqa: E402

#: A 3.6 km footprint (8 m outer posts) with a 200 m focus at 1 m: the reference scene's extent
#: at a test-sized post count.
_BIG = {"terrain": {"source": "procedural", "size_m": [3600.0, 3600.0], "post_m": 8.0,
                    "lod": True, "focus_size_m": 200.0, "focus_post_m": 1.0,
                    "landform": "crater", "landform_size_m": 1500.0, "rms_height_m": 2.0,
                    "tile_m": 100.0},
        "craters": {"d_min_m": 20.0, "d_max_m": 200.0},
        "rocks": {"d_min_m": 0.5, "outer_d_min_m": 2.0},
        "export": {"max_tile_posts": 129}}
#: A gentle 60 m world with a 24 m focus at 0.25 m for MuJoCo contact and driving.
_GENTLE = {"terrain": {"source": "procedural", "size_m": [60.0, 60.0], "post_m": 1.0,
                       "lod": True, "focus_size_m": 24.0, "focus_xy_m": [4.0, 0.0],
                       "rms_height_m": 0.05, "lod_blend_m": 10.0},
           "craters": {"enabled": False}, "rocks": {"enabled": False}}


@pytest.fixture(scope="module")
def big(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    scene = ms.build_scene(ms.SceneConfig.from_dict(_BIG), seed=11)
    out = tmp_path_factory.mktemp("lod") / "big"
    ms.write_scene(scene, out)
    return scene, out


def test_usd_holds_the_whole_footprint_as_lod_payloads(big: tuple[ms.Scene, Path]) -> None:
    from pxr import Usd, UsdGeom

    scene, out = big
    assert scene.outer is not None
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    assert stage.GetPrimAtPath("/World/Terrain").GetAttribute(LOD_ATTR).Get() == 0
    lod1 = stage.GetPrimAtPath("/World/TerrainLod1")
    tiles = list(lod1.GetChildren())
    assert len(tiles) == 4 * 4 - 0  # 451 posts in 128-post steps: 4 x 4 tiles, none all-hole
    fx0, fy0, fx1, fy1 = scene.outer.focus_bounds_xy_m
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    for tile in tiles:
        assert tile.HasAuthoredPayloads() and tile.GetAttribute(LOD_ATTR).Get() == 1
        mesh = UsdGeom.Mesh(tile.GetChild("Mesh"))
        pts = np.asarray(mesh.GetPointsAttr().Get())
        faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
        lo, hi = np.minimum(lo, pts[:, :2].min(0)), np.maximum(hi, pts[:, :2].max(0))
        c = pts[faces].mean(axis=1)
        inside = (c[:, 0] > fx0) & (c[:, 0] < fx1) & (c[:, 1] > fy0) & (c[:, 1] < fy1)
        assert not inside.any()  # the hole the focus fills
    np.testing.assert_allclose(lo, [-1800.0, -1800.0])
    np.testing.assert_allclose(hi, [1800.0, 1800.0])
    fine = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Terrain/tile_0_0"))
    fpts = np.asarray(fine.GetPointsAttr().Get())
    assert float(fpts[:, 0].min()) == pytest.approx(fx0)
    assert validate_stage(stage) == []
    man = json.loads((out / "manifest.json").read_text())
    assert man["summary"]["lod"]["footprint_bounds_xy_m"] == [-1800.0, -1800.0, 1800.0, 1800.0]
    assert man["summary"]["lod"]["outer_posts"] == 451 * 451


def test_usd_rocks_are_payloads_per_focus_tile_and_outer(big: tuple[ms.Scene, Path]) -> None:
    from pxr import Usd, UsdGeom

    scene, out = big
    assert scene.rocks is not None and scene.outer is not None
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    group = stage.GetPrimAtPath("/World/Rocks")
    assert Usd.ModelAPI(group).GetKind() == "group"
    assert group.GetAttribute("marsscene:rockCount").Get() == len(scene.rocks)
    lod = scene.provenance.extra["lod"]
    # 200 m focus, tile_m 100 snapped to whole 8 m cells: 96 m tiles, 3 x 3
    assert lod["focus_tiles"] == [3, 3] and lod["focus_tile_m"] == 96.0
    names = sorted(p.GetName() for p in group.GetChildren())
    assert names == ["outer"] + [f"tile_{r}_{c}" for r in range(3) for c in range(3)]
    tile_m = 96.0
    fx0, fy0 = scene.outer.focus_bounds_xy_m[:2]
    total = 0
    for prim in group.GetChildren():
        assert prim.HasAuthoredPayloads() and Usd.ModelAPI(prim).GetKind() == "component"
        inst = UsdGeom.PointInstancer(prim.GetChild("Instancer"))
        pos = np.asarray(inst.GetPositionsAttr().Get())
        assert len(pos) == prim.GetAttribute("marsscene:rockCount").Get() > 0
        total += len(pos)
        if prim.GetName() == "outer":
            assert prim.GetAttribute(LOD_ATTR).Get() == 1
            scale = np.asarray(inst.GetScalesAttr().Get())
            assert float(scale[:, 0].min()) >= 2.0 - 1e-6  # outer_d_min_m: large rocks only
            continue
        assert prim.GetAttribute(LOD_ATTR).Get() == 0
        row, col = map(int, prim.GetName().split("_")[1:])
        x0, y0 = fx0 + tile_m * col, fy0 + tile_m * row
        assert np.all((pos[:, 0] >= x0) & (pos[:, 0] <= x0 + tile_m))
        assert np.all((pos[:, 1] >= y0) & (pos[:, 1] <= y0 + tile_m))
    assert total == len(scene.rocks)


@pytest.mark.parametrize("usd_format", ["usda", "usdz"])
def test_lod_stage_passes_the_omniverse_asset_validator(big: tuple[ms.Scene, Path],
                                                        tmp_path: Path, usd_format: str) -> None:
    import dataclasses

    validator = pytest.importorskip("omni.asset_validator")
    from pxr import Kind, Usd

    scene = big[0]
    export = dataclasses.replace(scene.config.export, usd_format=usd_format)
    variant = dataclasses.replace(scene, config=scene.config.replace(export=export))
    ms.write_scene(variant, tmp_path / "s", formats=("usd",))
    target = tmp_path / "s" / f"scene.{usd_format}"
    results = validator.ValidationEngine().validate(str(target))
    assert [str(issue) for issue in results.issues()] == []
    stage = Usd.Stage.Open(str(target))
    lod1 = stage.GetPrimAtPath("/World/TerrainLod1")
    assert Usd.ModelAPI(lod1).GetKind() == Kind.Tokens.group
    assert all(Usd.ModelAPI(t).GetKind() == Kind.Tokens.component for t in lod1.GetChildren())


def test_mjcf_compiles_with_two_hfields(big: tuple[ms.Scene, Path]) -> None:
    from marsscene.export.mjcf import validate_mjcf

    model, _ = validate_mjcf(big[1] / "mjcf" / "scene.xml", seconds=0.1)
    assert model.nhfield == 2
    hid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_HFIELD, "terrain_outer")
    np.testing.assert_allclose(model.hfield_size[hid][:2], [1800.0, 1800.0])


@pytest.fixture(scope="module")
def gentle(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    scene = ms.build_scene(ms.SceneConfig.from_dict(_GENTLE), seed=4)
    out = tmp_path_factory.mktemp("lod") / "gentle"
    ms.write_scene(scene, out, formats=("mjcf",))
    return scene, out


@pytest.mark.parametrize("xy", [(4.0, 0.0), (15.5, -11.5), (-20.0, 20.0)])
def test_dropped_box_lands_on_the_right_surface(gentle: tuple[ms.Scene, Path],
                                                xy: tuple[float, float]) -> None:
    scene, out = gentle
    assert scene.outer is not None
    in_focus = bool(scene.heightfield.contains(*xy))
    ground = float((scene.heightfield if in_focus else scene.outer.heightfield).sample(*xy))
    z = drop_box(out / "mjcf" / "scene.xml", (xy[0], xy[1], ground + 1.0))
    assert z == pytest.approx(ground + 0.2, abs=0.02)  # resting on the surface, not 2 m lower
    assert HOLE_DEPTH_M > 1.0


def test_rover_drives_in_the_focus(runner, gentle: tuple[ms.Scene, Path],  # type: ignore[no-untyped-def]
                                   tmp_path: Path) -> None:
    from marsscene.cli import main
    from marsscene.runtime import read_tum

    scene, out = gentle
    wp = tmp_path / "wp.txt"
    wp.write_text("# x y\n0 0\n8 0\n")
    res = runner.invoke(main, ["drive", str(out), "--waypoints", str(wp), "--seconds", "6",
                               "--out", str(tmp_path / "run"), "--seed", "1"])
    assert res.exit_code == 0, res.output
    gt = read_tum(tmp_path / "run" / "gt.tum")
    xyz = np.asarray(gt.xyz_m)
    assert gt.path_length_m() > 1.0
    clearance = xyz[:, 2] - scene.heightfield.sample(xyz[:, 0], xyz[:, 1])
    assert float(np.ptp(clearance)) < 0.15  # rolling on the fine surface throughout
    assert np.all(scene.heightfield.contains(xyz[:, 0], xyz[:, 1]))


def test_camera_model_has_no_terrain_hfields(gentle: tuple[ms.Scene, Path]) -> None:
    from marsscene.runtime import CameraConfig, RunConfig
    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(gentle[1], run=RunConfig(camera=CameraConfig(width_px=80, height_px=60)),
                   start_xy_m=(4.0, 0.0), settle_s=0.2)
    outer = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_outer")
    assert sim.model.geom_group[outer] == 3  # off the LiDAR's MuJoCo rays, like "terrain"
    cam = sim.make_renderer()
    try:
        m = cam.model
        for name in ("terrain", "terrain_outer"):  # the window mesh stands in for both: the
            # hfields are not in the camera's model (its GL context would upload them)
            assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name) < 0
        assert m.nhfield == 0
        rgb, _ = sim.render(cam)
        assert rgb.shape == (60, 80, 3) and float(rgb.std()) > 1.0
    finally:
        cam.close()


def test_lod_outputs_are_byte_reproducible(tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """Two builds give the same bytes; the second one runs every helper thread (focus rocks
    per tile, crater batches, textures, tile meshing), which small scenes otherwise skip."""
    import threading

    import marsscene._threads as threads

    cfg = ms.SceneConfig.from_dict({**_GENTLE, "rocks": {"d_min_m": 0.3},
                                    "craters": {"d_min_m": 2.0, "d_max_m": 20.0},
                                    "terrain": {**_GENTLE["terrain"], "tile_m": 12.0}})
    outs = []
    names: set[str] = set()
    start = threading.Thread.start

    def spy(self: threading.Thread) -> None:
        names.add(self.name.rsplit("_", 1)[0])
        start(self)

    for name in ("a", "b"):
        if name == "b":
            monkeypatch.setattr(threads, "THREADED_MIN_POSTS", 1)
            monkeypatch.setattr(threading.Thread, "start", spy)
        ms.write_scene(ms.build_scene(cfg, seed=6), tmp_path / name)
        outs.append(tmp_path / name)
    assert {"marsscene-focus-rocks", "marsscene-textures", "marsscene-tiles",
            "marsscene-outer-tiles"} <= names
    files = sorted(p.relative_to(outs[0]) for p in outs[0].rglob("*") if p.is_file()
                   and p.name != "manifest.json")
    assert any("terrain_lod1" in str(f) for f in files)
    assert any("terrain_outer.bin" in str(f) for f in files)
    for rel in files:
        assert (outs[0] / rel).read_bytes() == (outs[1] / rel).read_bytes(), rel


def test_streamed_asset_layers_equal_the_in_memory_ones(tmp_path: Path) -> None:
    """write_usd exports each asset layer (terrain tiles, rock payloads) as soon as it is
    authored; the files equal those of the in-memory stage exported afterwards."""
    from marsscene.export.usd import to_stage
    from marsscene.export.usd.stage import root_layer

    cfg = ms.SceneConfig.from_dict({**_GENTLE, "rocks": {"d_min_m": 0.3},
                                    "terrain": {**_GENTLE["terrain"], "tile_m": 12.0}})
    scene = ms.build_scene(cfg, seed=3)
    _, kept = to_stage(scene)
    _, streamed = to_stage(scene, stream_to=tmp_path / "streamed")
    assert sorted(kept) == sorted(streamed) and any(r.startswith("assets/rocks/") for r in kept)
    assert any(r.startswith("assets/rock_colliders/") for r in kept)
    for rel, blob in kept.items():
        path = streamed[rel]
        assert path == tmp_path / "streamed" / rel and path.is_file()
        if isinstance(blob, bytes):
            assert path.read_bytes() == blob
        else:
            ref = tmp_path / "kept" / rel
            ref.parent.mkdir(parents=True, exist_ok=True)
            assert root_layer(blob).Export(str(ref))
            assert ref.read_bytes() == path.read_bytes()
