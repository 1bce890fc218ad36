"""The MER-class rover type (``RoverConfig.load("mer")``): its derived quantities from its data
file, its MJCF compiled and settled by MuJoCo, its USD articulation read back by OpenUSD's
physics parser, and a straight drive at its 5 cm/s speed limit."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RoverType, rover_body, rover_types
from marsscene.rover.stability import centre_of_mass_m, static_stability_deg, wheelbase_m

MER = RoverConfig.load("mer")
MER_TOML = rover_types()["mer"]


def test_mer_numbers_come_from_its_data_file_each_with_a_source() -> None:
    doc = tomllib.loads(Path(MER_TOML).read_text())
    assert isinstance(MER, RoverType) and MER.name == "mer"
    for key, value in doc["rover"].items():
        assert getattr(MER, key) == value, key
    assert set(doc["sources"]) >= set(doc["rover"]) | set(doc["body"])
    # the published figures: 185 kg, 25 cm wheels, 5 cm/s top speed (the wheel rate limit)
    assert (MER.mass_kg, 2 * MER.wheel_radius_m, MER.max_speed_m_s) == (185.0, 0.25, 0.05)
    assert MER.wheel_speed_limit_rad_s * MER.wheel_radius_m == pytest.approx(0.05)
    assert rover_body(RoverConfig()) != MER.body


def test_mer_derived_quantities() -> None:
    """Wheelbase 1.35 m (under the 1.6 m long rover), the centre of mass over the middle of the
    wheel footprint, and a static stability angle above the 45 deg the rovers were built to
    stand (module doc of marsscene.rover.stability)."""
    assert wheelbase_m(MER) == pytest.approx(1.35)
    com = centre_of_mass_m(MER)
    assert abs(com[1]) < 1e-9 and -MER.wheelbase_rear_m < com[0] < MER.wheelbase_front_m
    assert 0.3 < com[2] < MER.ride_height_m + 0.1
    angles = static_stability_deg(MER)
    assert angles["min"] > 45.0
    lateral = math.degrees(math.atan2(MER.track_m / 2, com[2]))
    assert angles["left"] == pytest.approx(lateral) == pytest.approx(angles["right"])


def test_a_rover_type_is_a_one_line_error_when_unknown_or_inconsistent(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="unknown; known: perseverance, mer"):
        RoverConfig.load("sojourner")
    bad = tmp_path / "bad.toml"
    bad.write_text('[rover]\nmass_kg = 100.0\n[sources]\n')
    with pytest.raises(ConfigError, match=r"uncited numbers \['mass_kg'\]"):
        RoverConfig.load(str(bad))
    with pytest.raises(ConfigError, match="half the rear wheelbase"):
        dataclasses.replace(MER, wheelbase_rear_m=0.8)
    assert RoverConfig.load("perseverance") == RoverConfig()


def test_mer_mjcf_compiles_and_settles_on_flat_ground_with_its_mass() -> None:
    """On a plane the MER rover weighs 185 kg (MuJoCo's body masses), comes to rest on its six
    wheels with base_link near its ride height, and its middle wheels sit under base_link."""
    mujoco = pytest.importorskip("mujoco")
    from marsscene.sim.rover_model import rover_mjcf

    xml = rover_mjcf(MER).replace(
        "<worldbody>", '<worldbody><geom name="floor" type="plane" size="5 5 0.1" '
                       'contype="1" conaffinity="2" friction="0.8 0.005 0.0001"/>', 1)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    assert model.body_mass.sum() == pytest.approx(185.0)
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base_link")
    mujoco.mj_forward(model, data)
    mid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "wheel_ml")
    assert data.xpos[mid][0] == pytest.approx(0.0, abs=1e-9)
    data.qpos[2] += 0.02  # dropped from 2 cm
    for _ in range(1500):  # 3 s at 2 ms
        mujoco.mj_step(model, data)
    assert np.linalg.norm(data.qvel[:6]) < 1e-2
    assert data.xpos[base][2] == pytest.approx(MER.ride_height_m, abs=0.02)
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    wheels = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(c.geom[1] if c.geom[0] == floor
                                else c.geom[0])) for c in data.contact[:data.ncon]}
    assert {n for n in wheels if n and n.startswith("wheel_")} == {
        f"wheel_{t}" for t in ("fl", "fr", "ml", "mr", "rl", "rr")}
    # the contact forces carry its weight on Mars-free MuJoCo gravity (the model's)
    force = np.zeros(6)
    total = 0.0
    for i in range(data.ncon):
        mujoco.mj_contactForce(model, data, i, force)
        total += force[0]
    assert total == pytest.approx(185.0 * -model.opt.gravity[2], rel=0.02)


def test_mer_usd_articulation_passes_the_physics_parser() -> None:
    """OpenUSD's physics parser (the one Newton's importer uses) reads the MER rover: one
    articulation of 18 rigid bodies, 15 revolute joints (6 drives, 4 steering, 2 rockers,
    2 bogies, the differential) and 4 ball joints (the rods), the chassis box and six wheel
    cylinders as colliders; 185 kg in all, 25 cm wheels."""
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom, UsdPhysics

    from marsscene.export.usd.rover import rover_stage

    stage = rover_stage(MER)
    load = getattr(UsdPhysics, "UsdPhysicsLoadStageFromPrimRange", None) or \
        UsdPhysics.LoadUsdPhysicsFromRange
    parsed = {str(k).rsplit(".", 1)[-1]: len(v[0]) for k, v in load(stage, ["/Rover"]).items()}
    assert {k: parsed.get(k) for k in ("Articulation", "RigidBody", "RevoluteJoint",
                                       "SphericalJoint", "CubeShape", "CylinderShape")} == {
        "Articulation": 1, "RigidBody": 18, "RevoluteJoint": 15, "SphericalJoint": 4,
        "CubeShape": 1, "CylinderShape": 6}
    total = sum(UsdPhysics.MassAPI(p).GetMassAttr().Get() for p in Usd.PrimRange(
        stage.GetPrimAtPath("/Rover")) if p.HasAPI(UsdPhysics.MassAPI))
    assert total == pytest.approx(185.0)
    wheel = UsdGeom.Cylinder(stage.GetPrimAtPath("/Rover/wheel_fl/collision"))
    assert 2 * wheel.GetRadiusAttr().Get() == pytest.approx(0.25)


def test_mer_drives_a_straight_route_at_its_speed_limit(tmp_path: Path) -> None:
    """On a flat 20 m scene a 0.5 m/s command (ten times MER's top speed) saturates its wheel
    rate limit: 8 s cover 8 s x 5 cm/s = 0.4 m (within 10 %: the start from rest and wheel
    slip), straight ahead (under 2 cm sideways), and run.json records the MER rover. (ms.drive
    takes no rover yet: the drive runs sim.driver.drive_sim on a RoverSim of the type.)"""
    pytest.importorskip("mujoco")
    import json

    import marsscene as ms
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20],
                                                "rms_height_m": 0.0, "detail": False},
                                    "rocks": {"enabled": False}, "craters": {"enabled": False}})
    ms.write_scene(ms.build_scene(cfg, seed=3), tmp_path / "scene")
    sim = RoverSim(tmp_path / "scene", rover=MER, start_xy_m=(0.0, 0.0))
    res = drive_sim(sim, command=(0.5, 0.0), seconds=8.0, out_dir=tmp_path / "run",
                    rng=stage_rng(0, "sensors"))
    xyz = res.gt.xyz_m
    travelled = float(np.hypot(*(xyz[-1, :2] - xyz[0, :2])))
    assert travelled == pytest.approx(8.0 * MER.max_speed_m_s, rel=0.1)
    assert abs(xyz[-1, 1] - xyz[0, 1]) < 0.02
    meta = json.loads((tmp_path / "run" / "run.json").read_text())
    assert meta["rover"]["name"] == "mer" and meta["rover"]["mass_kg"] == 185.0
