"""The USD rover (``assets/rover.usda``) and the rock colliders, read back through pxr and
OpenUSD's own physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, which Newton's importer
uses), and checked against the MJCF rover compiled by MuJoCo."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.export.config import ExportConfig
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS

pytest.importorskip("pxr")
from pxr import Usd, UsdGeom, UsdPhysics

from tests.support.usd import physics_parse, rock_collider_tiers

CFG = {
    "terrain": {"source": "procedural", "size_m": [60.0, 60.0], "post_m": 0.5},
    "rocks": {"k": 0.05, "d_min_m": 0.3},
    "craters": {"d_min_m": 2.0},
    "export": {"rover": True, "rover_xy_m": [4.0, -3.0], "rover_yaw_deg": 30.0},
}


@pytest.fixture(scope="module")
def scene() -> ms.Scene:
    return ms.build_scene(ms.SceneConfig.from_dict(CFG), seed=5)


@pytest.fixture(scope="module")
def written(scene: ms.Scene, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("rover") / "scene"
    ms.write_scene(scene, out)
    return out


def test_physics_parser_sees_every_rock_and_the_rover_articulation(
        scene: ms.Scene, written: Path) -> None:
    """Every rock of the scene (all >= the 0.2 m collider minimum) is a collider the parser
    reports: the obstacle rocks (>= 0.5 m) as one instance each, named by its rock-table row,
    the others inside one merged mesh per tile, which lists their rows."""
    stage = Usd.Stage.Open(str(written / "scene.usda"))
    parsed = physics_parse(stage)
    meshes = parsed["MeshShape"][0]
    instances, tiles = rock_collider_tiers(stage, meshes)
    big = np.flatnonzero(scene.rocks.diameter_m >= ExportConfig().rock_instance_min_diameter_m)
    parts = sum(len(scene.rock_prototypes[k].collision) for k in scene.rocks.prototype[big])
    assert len(instances) == parts == len(set(instances)) and len(big) > 10
    assert {p.split("/")[3] for p in instances} == {f"rock_{i}" for i in big}
    merged = np.concatenate([t.rows for t in tiles])
    assert len(tiles) >= 2 and len(merged) > 100
    assert sorted(merged.tolist() + big.tolist()) == list(range(len(scene.rocks)))
    assert not any("/World/Rocks/" in p for p in meshes)  # the render instancer is not one
    (root,), (desc,) = parsed["Articulation"]
    assert root == "/World/Rover"
    assert [str(p) for p in desc.rootPrims] == ["/World/Rover/base_link"]
    assert len(parsed["RigidBody"][0]) == len(desc.articulatedBodies) == 18
    rev = dict(zip(*parsed["RevoluteJoint"], strict=True))
    names = {p.rsplit("/", 1)[1]: d for p, d in rev.items()}
    assert set(names) == {*DRIVE_JOINTS, *STEER_JOINTS, "rocker_left", "rocker_right",
                          "bogie_left", "bogie_right", "differential"}
    cfg = RoverConfig()
    for j in DRIVE_JOINTS:  # velocity drives: stiffness 0, damping in N m s / deg
        d = names[j].drive
        assert d.enabled and d.stiffness == 0.0
        assert d.damping == pytest.approx(cfg.drive_kv_nm_s * math.pi / 180, rel=1e-6)
        assert d.forceLimit == pytest.approx(cfg.drive_torque_limit_nm)
    for j in STEER_JOINTS:  # position drives within the steering limit
        d, lim = names[j].drive, names[j].limit
        assert d.enabled and d.stiffness == pytest.approx(cfg.steer_kp_nm * math.pi / 180,
                                                          rel=1e-6)
        assert lim.enabled and lim.upper == pytest.approx(math.degrees(cfg.steer_limit_rad))
    for j in ("rocker_left", "rocker_right", "bogie_left", "bogie_right", "differential"):
        assert not names[j].drive.enabled  # free
    sph = dict(zip(*parsed["SphericalJoint"], strict=True))
    excluded = sorted(p.rsplit("/", 1)[1] for p, d in sph.items() if d.excludeFromArticulation)
    assert excluded == ["diff_link_left", "diff_link_right"] and len(sph) == 4
    assert len(parsed["CylinderShape"][0]) == 6 and len(parsed["CubeShape"][0]) == 1
    (group,), _ = parsed["CollisionGroup"]
    rel = UsdPhysics.CollisionGroup(stage.GetPrimAtPath(group)).GetFilteredGroupsRel()
    assert [str(t) for t in rel.GetTargets()] == [group]  # rover parts never collide


def test_rover_asset_equals_the_mjcf_rover() -> None:
    """Masses, centres of mass, inertias, joint frames, limits and the navcam of the USD rover
    equal MuJoCo's compiled MJCF rover (the differential's bar and rods excepted: MuJoCo couples
    the rockers by an equality, and their 3 kg are taken from the USD chassis)."""
    mujoco = pytest.importorskip("mujoco")
    from marsscene.export.usd.rover import rover_stage
    from marsscene.rover.links import DIFF_BAR_KG, DIFF_ROD_KG
    from marsscene.sim.rover_model import rover_mjcf
    from marsscene.transforms import quat_to_matrix

    for cfg in (RoverConfig(), RoverConfig(wheel_collision="sphere", track_m=2.4,
                                           mass_kg=900.0, wheel_radius_m=0.3)):
        model = mujoco.MjModel.from_xml_string(rover_mjcf(cfg))
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        stage = rover_stage(cfg)
        cache = UsdGeom.XformCache()
        base_z = data.xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base_link")][2]
        total = 0.0
        for prim in stage.Traverse():
            if not prim.HasAPI(UsdPhysics.MassAPI):
                continue
            name = prim.GetName()
            api = UsdPhysics.MassAPI(prim)
            mass = api.GetMassAttr().Get()
            total += mass
            if name.startswith("diff_"):
                continue
            b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            diff = DIFF_BAR_KG + 2 * DIFF_ROD_KG if name == "base_link" else 0.0
            assert mass + diff == pytest.approx(model.body_mass[b], rel=1e-6), name
            origin = np.asarray(cache.GetLocalToWorldTransform(prim))[3, :3]
            np.testing.assert_allclose(origin, data.xpos[b], atol=1e-6, err_msg=name)
            if name == "base_link":
                continue  # its box inertia is for the lighter chassis
            com = np.asarray(api.GetCenterOfMassAttr().Get())
            np.testing.assert_allclose(com, model.body_ipos[b], atol=1e-6, err_msg=name)
            q = api.GetPrincipalAxesAttr().Get()  # to a matrix as PhysX / Newton do (products,
            r = quat_to_matrix([q.GetReal(), *q.GetImaginary()])  # not Gf.Rotation's acos)
            tensor = r @ np.diag(api.GetDiagonalInertiaAttr().Get()) @ r.T
            rm = np.zeros(9)
            mujoco.mju_quat2Mat(rm, model.body_iquat[b])
            rm = rm.reshape(3, 3)
            np.testing.assert_allclose(tensor, rm @ np.diag(model.body_inertia[b]) @ rm.T,
                                       atol=1e-5 * model.body_inertia[b].max(), err_msg=name)
        assert total == pytest.approx(cfg.mass_kg) and model.body_mass.sum() == pytest.approx(
            cfg.mass_kg)
        for j in model.jnt_type.nonzero()[0]:  # hinges: anchors, axes and ranges
            name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
            joint = UsdPhysics.RevoluteJoint(stage.GetPrimAtPath(f"/Rover/Joints/{name}"))
            body1 = stage.GetPrimAtPath(joint.GetBody1Rel().GetTargets()[0])
            anchor = np.asarray(cache.GetLocalToWorldTransform(body1))[3, :3]
            np.testing.assert_allclose(anchor, data.xanchor[j], atol=1e-6, err_msg=name)
            axis = "XYZ"[int(np.argmax(np.abs(data.xaxis[j])))]
            assert joint.GetAxisAttr().Get() == axis
            if model.jnt_limited[j]:
                lo, hi = joint.GetLowerLimitAttr().Get(), joint.GetUpperLimitAttr().Get()
                np.testing.assert_allclose(np.radians([lo, hi]), model.jnt_range[j], rtol=1e-6)
        wheel = UsdGeom.Cylinder(stage.GetPrimAtPath("/Rover/wheel_fl/visual_1")
                                 if cfg.wheel_collision == "sphere"
                                 else stage.GetPrimAtPath("/Rover/wheel_fl/collision"))
        assert wheel.GetRadiusAttr().Get() == pytest.approx(cfg.wheel_radius_m)
        assert wheel.GetHeightAttr().Get() == pytest.approx(cfg.wheel_width_m)
        cam = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "navcam")
        nav = np.asarray(cache.GetLocalToWorldTransform(
            stage.GetPrimAtPath("/Rover/base_link/navcam")))
        np.testing.assert_allclose(nav[3, :3], data.cam_xpos[cam], atol=1e-5)
        np.testing.assert_allclose(nav[:3, :3].T, data.cam_xmat[cam].reshape(3, 3), atol=1e-5)
        assert base_z == pytest.approx(cfg.ride_height_m)


def test_rover_is_placed_at_the_runtime_spawn_pose(scene: ms.Scene, written: Path) -> None:
    pytest.importorskip("mujoco")
    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(written, start_xy_m=(4.0, -3.0), start_yaw_rad=math.radians(30.0))
    spawn = sim._spawn_pose((4.0, -3.0), math.radians(30.0))
    stage = Usd.Stage.Open(str(written / "scene.usda"))
    base = np.asarray(UsdGeom.XformCache().GetLocalToWorldTransform(
        stage.GetPrimAtPath("/World/Rover/base_link")))
    np.testing.assert_allclose(base[3, :3], spawn[:3], atol=1e-4)
    from marsscene.transforms import quat_to_matrix

    np.testing.assert_allclose(base[:3, :3].T, quat_to_matrix(spawn[3:]), atol=1e-6)


def test_rover_outside_the_terrain_is_a_one_line_error(scene: ms.Scene, tmp_path: Path) -> None:
    import dataclasses

    export = dataclasses.replace(scene.config.export, rover_xy_m=(500.0, 0.0))
    bad = dataclasses.replace(scene, config=scene.config.replace(export=export))
    with pytest.raises(ms.errors.ExportError, match=r"rover_xy_m.*outside the terrain") as err:
        ms.write_scene(bad, tmp_path / "s", formats=("usd",))
    assert "\n" not in str(err.value)
    with pytest.raises(ms.errors.ConfigError, match="rover_xy_m"):
        ms.SceneConfig.from_dict({"export": {"rover_xy_m": [1.0]}})


def test_build_cli_places_the_rover(tmp_path: Path) -> None:
    pytest.importorskip("click")
    from click.testing import CliRunner

    from marsscene.cli import main

    args = ["build", "--procedural", "--size-m", "40", "40", "--post-m", "0.5",
            "--format", "usda", "--rover-xy", "2", "1"]
    res = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "a")])
    assert res.exit_code == 0, res.output
    stage = Usd.Stage.Open(str(tmp_path / "a" / "scene.usda"))
    origin = np.asarray(UsdGeom.XformCache().GetLocalToWorldTransform(
        stage.GetPrimAtPath("/World/Rover/base_link")))[3, :2]
    assert np.hypot(*(origin - (2.0, 1.0))) < 0.3  # exact pose: the spawn-pose test above
    assert (tmp_path / "a" / "assets" / "rover.usda").is_file()
    res = CliRunner().invoke(main, [*args, "--no-rover", "--out", str(tmp_path / "b")])
    assert res.exit_code == 2 and "drop --no-rover" in res.output
    res = CliRunner().invoke(main, [*args[:-3], "--rover-xy", "900", "0",
                                    "--out", str(tmp_path / "c")])
    assert res.exit_code != 0 and "outside the terrain" in res.output
