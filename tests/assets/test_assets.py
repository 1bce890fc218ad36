"""Assets: site search, levelling (base within 2 cm, pad slope under the limit), rocks cleared,
USD round trip through pxr (mesh and referenced USD assets), collision in MuJoCo."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

import marsscene as ms
from marsscene.assets import AssetConfig, find_site, habitat_model, place_assets
from marsscene.errors import ConfigError
from marsscene.terrain.heightfield import Heightfield
from tests.mjcf_drop import drop_box


def _rough_with_flat_patch(rng: np.random.Generator) -> Heightfield:
    """Rough noise (rms 0.5 m) except a smooth, tilted (3 deg) 30 m patch around (20, -20)."""
    z = rng.normal(0.0, 0.5, (201, 201)).astype(np.float32)
    hf = Heightfield.centered(z, 0.5)
    xv, yv = hf.grid_xy()
    d = np.maximum(np.abs(xv[None, :] - 20.0), np.abs(yv[:, None] + 20.0))
    patch = d < 15.0
    z[patch] = (np.tan(np.radians(3.0)) * np.broadcast_to(xv[None, :], z.shape))[patch]
    return hf.with_z(z)


def test_find_site_picks_the_flat_patch(rng: np.random.Generator) -> None:
    hf = _rough_with_flat_patch(rng)
    x, y = find_site(hf, 8.0, max_slope_deg=8.0, clearance_m=2.0)
    assert abs(x - 20.0) <= 7.0 and abs(y + 20.0) <= 7.0
    # the pad's tilt is measured: a 5 deg plane passes a 6 deg limit and fails a 4 deg one
    plane = hf.with_z(np.tan(np.radians(5.0)) * np.broadcast_to(
        hf.grid_xy()[0][None, :], hf.shape).astype(np.float32))
    find_site(plane, 8.0, max_slope_deg=6.0, clearance_m=2.0)
    with pytest.raises(ConfigError, match=r"below assets\.max_slope_deg = 4 deg"):
        find_site(plane, 8.0, max_slope_deg=4.0, clearance_m=2.0)
    # so does an avoided disc (another asset, the rover start)
    x3, y3 = find_site(hf, 8.0, max_slope_deg=8.0, clearance_m=2.0,
                       avoid=[(20.0, -20.0, 5.0)])
    assert np.hypot(x3 - 20.0, y3 + 20.0) > 13.0
    with pytest.raises(ConfigError, match="no site"):
        find_site(hf, 60.0, max_slope_deg=8.0, clearance_m=2.0)


def _base_points(model, xy):  # type: ignore[no-untyped-def]
    v = np.concatenate([p.vertices for p in model.parts])
    base = v[v[:, 2] < 1e-6]
    return base[:, 0] + xy[0], base[:, 1] + xy[1]


def test_levelled_pad_holds_the_base_within_2cm(rng: np.random.Generator) -> None:
    z = (rng.normal(0.0, 1.0, (241, 241))).astype(np.float32)
    hf = Heightfield.centered(z, 0.25)
    hf = hf.with_z(hf.z_m + 0.2 * np.arange(241, dtype=np.float32)[None, :] * 0.25)  # 11 deg
    model = habitat_model()
    cfg = AssetConfig(habitat=True, xy_m=((2.0, 1.0),), keep_clear_m=0.0)
    out, placed = place_assets(hf, [model], cfg)
    a = placed[0]
    np.testing.assert_array_equal(hf.z_m, z + 0.2 * np.arange(241, dtype=np.float32)[None, :]
                                  * 0.25)  # input untouched
    xs, ys = _base_points(model, a.xy_m)
    assert np.abs(out.sample(xs, ys) - a.base_z_m).max() < 0.02
    # the pad is level: slope under the limit everywhere on it
    xv, yv = out.grid_xy()
    on_pad = np.hypot(xv[None, :] - 2.0, yv[:, None] - 1.0) < a.pad_radius_m - out.cell_size_m
    assert float(out.slope_deg()[on_pad].max()) < cfg.max_slope_deg
    # the blend joins the terrain: outside pad + blend nothing changed
    far = np.hypot(xv[None, :] - 2.0, yv[:, None] - 1.0) > a.pad_radius_m + cfg.blend_m + 0.5
    np.testing.assert_array_equal(out.z_m[far], hf.z_m[far])


@pytest.fixture(scope="module")
def base_scene(tmp_path_factory: pytest.TempPathFactory) -> tuple[ms.Scene, Path]:
    cfg = ms.SceneConfig.from_dict({"preset": "mars-base", "terrain": {
        "size_m": [100.0, 100.0], "post_m": 0.5}, "rocks": {"d_min_m": 0.3}})
    scene = ms.build_scene(cfg, seed=11)
    out = tmp_path_factory.mktemp("base") / "scene"
    ms.write_scene(scene, out)
    return scene, out


def test_habitat_sits_on_ground_and_rocks_are_cleared(base_scene) -> None:  # type: ignore[no-untyped-def]
    scene, _ = base_scene
    (a,) = scene.assets
    xs, ys = _base_points(a.model, a.xy_m)
    assert np.abs(scene.heightfield.sample(xs, ys) - a.base_z_m).max() < 0.02
    assert np.hypot(*a.xy_m) > 15.0  # clear of the rover start
    rocks = scene.rocks.position_xyz_m
    assert len(rocks) > 100
    assert np.hypot(rocks[:, 0] - a.xy_m[0], rocks[:, 1] - a.xy_m[1]).min() > a.pad_radius_m


def test_usd_has_the_asset_prims_on_the_pad(base_scene) -> None:  # type: ignore[no-untyped-def]
    from pxr import Usd, UsdGeom, UsdPhysics

    scene, out = base_scene
    (a,) = scene.assets
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    prim = stage.GetPrimAtPath("/World/Assets/habitat")
    assert prim.IsValid()
    parts = [p for p in prim.GetChildren() if p.IsA(UsdGeom.Mesh)]
    assert len(parts) == len(a.model.parts)
    assert all(p.HasAPI(UsdPhysics.CollisionAPI) for p in parts)
    box = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default"]).ComputeWorldBound(prim)
    rng_ = box.ComputeAlignedRange()
    assert rng_.GetMin()[2] == pytest.approx(a.base_z_m, abs=1e-4)
    assert rng_.GetMax()[2] == pytest.approx(a.base_z_m + a.model.height_m, abs=1e-3)
    from marsscene.export.usd import validate_stage

    assert validate_stage(stage) == []


def test_box_dropped_on_the_habitat_rests_on_its_roof(base_scene) -> None:  # type: ignore[no-untyped-def]
    scene, out = base_scene
    (a,) = scene.assets
    x, y = a.xy_m[0] - 1.5, a.xy_m[1] - 1.0  # above the main module's dome top
    roof = a.base_z_m + a.model.parts[0].vertices[:, 2].max()
    z = drop_box(out / "mjcf" / "scene.xml", (x, y, roof + 1.0))
    ground = float(scene.heightfield.sample(x, y))
    assert z > ground + 4.0  # held up by the habitat, not the terrain
    assert z == pytest.approx(roof + 0.2, abs=0.25)  # on the (domed) roof


def test_obj_and_glb_assets_from_files(tmp_path: Path) -> None:
    obj = tmp_path / "lander.obj"
    trimesh.creation.box(extents=(3.0, 2.0, 1.5)).export(obj)
    glb = tmp_path / "tower.glb"  # glTF is Y-up: tall along y in the file
    trimesh.creation.box(extents=(1.0, 4.0, 1.0)).export(glb)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [80.0, 80.0], "post_m": 0.5},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "assets": {"files": [str(obj), str(glb)], "xy_m": [[10.0, -12.0], [-20.0, 15.0]]}})
    scene = ms.build_scene(cfg, seed=2)
    lander, tower = scene.assets
    assert lander.xy_m == (10.0, -12.0) and tower.xy_m == (-20.0, 15.0)
    assert lander.model.height_m == pytest.approx(1.5)
    assert tower.model.height_m == pytest.approx(4.0)  # Y-up turned Z-up
    for a in scene.assets:
        xs, ys = _base_points(a.model, a.xy_m)
        assert np.abs(scene.heightfield.sample(xs, ys) - a.base_z_m).max() < 0.02
    out = tmp_path / "out"
    ms.write_scene(scene, out)
    from marsscene.export.mjcf import validate_mjcf

    model, _ = validate_mjcf(out / "mjcf" / "scene.xml", seconds=0.1)
    assert model.geom("asset_lander_0").type == mujoco.mjtGeom.mjGEOM_MESH


USDA = """#usda 1.0
(
    defaultPrim = "Hab"
    metersPerUnit = 0.01
    upAxis = "Y"
)
def Xform "Hab"
{
    def Cube "Shell"
    {
        double size = 200
        double3 xformOp:translate = (500, 100, 0)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }
}
"""


def test_usd_asset_is_referenced_levelled_and_scaled(tmp_path: Path) -> None:
    from pxr import Usd, UsdGeom

    src = tmp_path / "hab.usda"
    src.write_text(USDA)
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [60.0, 60.0], "post_m": 0.5},
        "craters": {"enabled": False}, "rocks": {"enabled": False},
        "assets": {"files": [str(src)], "xy_m": [[5.0, 5.0]]}})
    scene = ms.build_scene(cfg, seed=3)
    (a,) = scene.assets
    assert a.model.height_m == pytest.approx(2.0)  # 200 cm cube
    out = tmp_path / "out"
    ms.write_scene(scene, out)
    assert (out / "assets" / "hab.usda").is_file()
    stage = Usd.Stage.Open(str(out / "scene.usda"))
    shell = stage.GetPrimAtPath("/World/Assets/hab/Model/Shell")
    assert shell.IsValid()
    box = UsdGeom.BBoxCache(Usd.TimeCode.Default(), ["default"]).ComputeWorldBound(shell)
    lo, hi = box.ComputeAlignedRange().GetMin(), box.ComputeAlignedRange().GetMax()
    np.testing.assert_allclose([lo[0], lo[1], lo[2]], [4.0, 4.0, a.base_z_m], atol=1e-4)
    np.testing.assert_allclose([hi[0], hi[1], hi[2]], [6.0, 6.0, a.base_z_m + 2.0], atol=1e-4)


def test_asset_errors_are_one_line(tmp_path: Path, runner) -> None:  # type: ignore[no-untyped-def]
    from marsscene.cli import main

    with pytest.raises(ConfigError, match="not a supported asset"):
        AssetConfig(files=("hab.fbx",))
    with pytest.raises(ConfigError, match="one \\[x, y\\] per asset"):
        AssetConfig(habitat=True, xy_m=((1.0, 2.0), (3.0, 4.0)))
    res = runner.invoke(main, ["build", "--preset", "mars-base", "--size-m", "60", "60",
                               "--post-m", "1", "--asset-xy", "500", "0", "--out",
                               str(tmp_path / "o")])
    assert res.exit_code == 1
    assert "outside the terrain footprint" in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "o").exists()


def test_rover_route_goes_around_the_habitat(tmp_path: Path, runner) -> None:  # type: ignore[no-untyped-def]
    """The habitat's geoms are world obstacles: the authored route bends around them and the
    rover reaches the goal behind the habitat."""
    from marsscene.cli import main

    scene_dir, run_dir = tmp_path / "scene", tmp_path / "run"
    res = runner.invoke(main, ["build", "--preset", "mars-base", "--size-m", "100", "100",
                               "--post-m", "0.5", "--seed", "1", "--asset-xy", "0", "-20",
                               "--format", "mjcf", "--out", str(scene_dir)])
    assert res.exit_code == 0, res.output
    (tmp_path / "wp.txt").write_text("0 0\n0 -42\n")
    res = runner.invoke(main, ["drive", str(scene_dir), "--waypoints", str(tmp_path / "wp.txt"),
                               "--seconds", "200", "--out", str(run_dir)])
    assert res.exit_code == 0, res.output
    gt = np.loadtxt(run_dir / "gt.tum")
    assert np.hypot(gt[-1, 1], gt[-1, 2] + 42.0) < 1.0  # reached the goal behind the habitat
    hab = habitat_model()
    lo, hi = hab.parts[0].bounds  # the domed main module, in the asset frame
    cx, cy = (lo[0] + hi[0]) / 2.0, -20.0 + (lo[1] + hi[1]) / 2.0
    clearance = np.hypot(gt[:, 1] - cx, gt[:, 2] - cy).min() - (hi[0] - lo[0]) / 2.0
    assert clearance > 1.0  # the rover body (half-width ~1.4 m from its centre) never hit it
    assert np.abs(gt[:, 1]).max() > 5.0  # the straight line x = 0 crosses the module: it bent
