"""The rover stands, drives straight, turns, climbs 15 deg and a 0.3 m rock at a 2 ms step."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from marsscene.errors import RuntimeSimError
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import body_twist_from_wheels, wheel_commands
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.rover_sim import RoverSim
from tests.support.drive import step


def _no_warnings(sim: RoverSim) -> None:
    bad = [mujoco.mjtWarning(i).name for i, w in enumerate(sim.data.warning) if w.number]
    assert not bad, bad


def test_rover_model_mass_and_compile() -> None:
    m = mujoco.MjModel.from_xml_string(rover_mjcf())
    assert m.body_mass.sum() == pytest.approx(1025.0)
    assert m.nu == 10  # 6 drive + 4 steering actuators
    assert m.opt.timestep == pytest.approx(0.002)
    wheel = m.geom(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "wheel_fl"))
    assert wheel.size[0] == pytest.approx(0.2625)
    # differential: rocker_left = -rocker_right
    assert m.eq_type[0] == mujoco.mjtEq.mjEQ_JOINT
    np.testing.assert_allclose(m.eq_data[0, :5], [0, -1, 0, 0, 0])


def test_wheel_kinematics_roundtrip() -> None:
    cfg = RoverConfig()
    for v, w in [(0.3, 0.0), (0.5, 0.2), (0.2, -0.15), (0.0, 0.2), (-0.3, 0.1)]:
        rates, steer = wheel_commands(v, w, cfg)
        assert np.all(np.abs(steer) <= math.pi / 2 + 1e-12)
        assert body_twist_from_wheels(rates, steer, cfg) == pytest.approx((v, w), abs=1e-12)


def test_settles_with_six_wheels_in_contact(flat_scene) -> None:
    sim = RoverSim(flat_scene, start_xy_m=(0.0, 0.0), start_yaw_rad=0.3)
    assert sim.time_s == 0.0
    assert sim.wheels_in_contact().all()
    pos, _ = sim.pose()
    assert pos[2] == pytest.approx(0.75, abs=0.03)  # ride height on flat ground
    assert sim.yaw_rad() == pytest.approx(0.3, abs=0.01)
    assert np.abs(sim.data.qvel).max() < 0.02
    _no_warnings(sim)


def test_straight_3m_in_10s(flat_scene) -> None:
    sim = RoverSim(flat_scene, start_xy_m=(-5.0, 0.0))
    p0 = sim.pose()[0]
    for _ in range(500):
        step(sim, 0.3, 0.0)
    d = np.linalg.norm(sim.pose()[0][:2] - p0[:2])
    assert d == pytest.approx(3.0, rel=0.05)
    assert abs(sim.yaw_rad()) < 0.02
    _no_warnings(sim)


@pytest.mark.parametrize(("v", "omega"), [(0.3, 0.1), (0.0, 0.2), (0.4, -0.2)])
def test_turn_follows_yaw_rate(flat_scene, v: float, omega: float) -> None:
    sim = RoverSim(flat_scene)
    for _ in range(50):  # 1 s: steering reaches its angles
        step(sim, v, omega)
    yaw0 = np.unwrap([sim.yaw_rad()])[0]
    yaws = []
    for _ in range(250):
        step(sim, v, omega)
        yaws.append(sim.yaw_rad())
    dyaw = np.unwrap(np.r_[yaw0, yaws])[-1] - yaw0
    assert dyaw / 5.0 == pytest.approx(omega, rel=0.05)


def test_climbs_15_degree_slope(slope_scene) -> None:
    sim = RoverSim(slope_scene, start_xy_m=(-12.0, 0.0))
    p0 = sim.pose()[0]
    for _ in range(1000):  # 20 s at 0.3 m/s
        step(sim, 0.3, 0.0)
    p1 = sim.pose()[0]
    travelled = np.linalg.norm(p1 - p0)
    assert travelled > 0.9 * 6.0
    assert (p1[2] - p0[2]) / (p1[0] - p0[0]) == pytest.approx(math.tan(math.radians(15)), rel=0.05)
    _no_warnings(sim)


def test_climbs_0p3m_rock(flat_scene) -> None:
    def add_rock(spec) -> None:  # type: ignore[no-untyped-def]
        g = spec.worldbody.add_geom()  # a half-buried ellipsoid boulder standing 0.3 m tall
        g.name, g.type = "rock", mujoco.mjtGeom.mjGEOM_ELLIPSOID
        g.size = [0.35, 0.35, 0.3]
        g.pos = [-1.0, 1.0, 0.0]  # under the left wheel track
        g.friction = [0.8, 0.02, 0.002]

    sim = RoverSim(flat_scene, start_xy_m=(-4.0, 0.0), edit_spec=add_rock)
    p0 = sim.pose()[0]
    roll_max = z_max = 0.0
    for _ in range(1250):  # 25 s at 0.3 m/s: all three left wheels cross the rock
        step(sim, 0.3, float(np.clip(-sim.yaw_rad(), -0.2, 0.2)))  # heading hold
        w, x, y, z = sim.pose()[1]
        roll_max = max(roll_max, abs(math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))))
        z_max = max(z_max, sim.pose()[0][2])
    p1 = sim.pose()[0]
    assert p1[0] - p0[0] > 0.9 * 7.5
    assert abs(p1[1] - p0[1]) < 0.2
    assert z_max - p0[2] > 0.03  # chassis lifted: the rock was climbed, not missed
    assert math.degrees(roll_max) > 2.0
    assert p1[2] == pytest.approx(p0[2], abs=0.02)  # back on the ground, upright
    _no_warnings(sim)


def test_missing_scene_xml_error(tmp_path) -> None:
    with pytest.raises(RuntimeSimError, match=r"scene\.xml is missing"):
        RoverSim(tmp_path)


def test_spawn_outside_terrain_error(flat_scene) -> None:
    with pytest.raises(RuntimeSimError, match="outside the terrain"):
        RoverSim(flat_scene, start_xy_m=(100.0, 0.0))


def test_scene_xml_stays_rover_free_and_rover_xml(flat_scene, tmp_path) -> None:
    sim = RoverSim(flat_scene)
    assert "rover" not in (flat_scene / "mjcf" / "scene.xml").read_text()
    path = sim.write_rover_xml(tmp_path / "rover.xml")
    m = mujoco.MjModel.from_xml_path(str(path))
    assert m.body_mass.sum() == pytest.approx(1025.0)


def test_sphere_wheels_drive_straight(flat_scene) -> None:
    sim = RoverSim(flat_scene, rover=RoverConfig(wheel_collision="sphere"))
    assert sim.wheels_in_contact().all()
    p0 = sim.pose()[0]
    for _ in range(250):
        step(sim, 0.3, 0.0)
    assert np.linalg.norm(sim.pose()[0][:2] - p0[:2]) == pytest.approx(1.5, rel=0.05)


def test_reset_respawns_exactly(flat_scene) -> None:
    """``reset`` puts the rover back at the pose asked for, settled, with the clock at 0, and
    does it the same way each time (a Gymnasium episode's start: the environment draws any
    randomisation of the pose itself)."""
    sim = RoverSim(flat_scene)
    poses = []
    for xy, yaw in (((1.0, -0.5), 0.4), ((1.0, -0.5), 0.4), ((-2.0, 1.0), -0.3)):
        step(sim, 0.3, 0.1)
        sim.reset(xy_m=xy, yaw_rad=yaw)
        assert sim.time_s == 0.0 and sim.wheels_in_contact().all()
        poses.append(np.r_[sim.pose()[0][:2], sim.yaw_rad()])
        assert poses[-1] == pytest.approx([*xy, yaw], abs=0.02)
    np.testing.assert_array_equal(poses[0], poses[1])


def test_scene_obstacles_from_rock_geoms(flat_scene) -> None:
    from marsscene.sim.world import scene_obstacles

    def add_rock(spec) -> None:  # type: ignore[no-untyped-def]
        g = spec.worldbody.add_geom()
        g.type, g.size, g.pos = mujoco.mjtGeom.mjGEOM_BOX, [0.3, 0.4, 0.25], [5.0, -3.0, 0.1]

    obs = scene_obstacles(RoverSim(flat_scene, edit_spec=add_rock))
    np.testing.assert_allclose(obs.xy_m, [[5.0, -3.0]])
    np.testing.assert_allclose(obs.radius_m, [0.5])
    np.testing.assert_allclose(obs.height_m, [0.35])
