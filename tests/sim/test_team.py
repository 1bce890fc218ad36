"""A team of robots in one world (``ms.drive_team``, ``marsscene drive --team``): one robot
drives as ``ms.drive`` does, byte for byte; each robot's noise is its own; rovers touch and see
each other; a MER-class rover drives beside a Perseverance-class one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.cli import main
from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig
from marsscene.seeding import robot_rng

pytest.importorskip("mujoco")

LOGS = ("gt.tum", "odom.tum", "cmd.csv", "wheels.csv", "imu.csv")
NOISY = ms.RunConfig(noise=ms.NoiseConfig(profile="ln200s"))


def test_a_team_of_one_drives_exactly_as_a_single_drive(gentle_scene: Path, tmp_path: Path):
    wp = [[-6.0, -2.0], [6.0, -2.0]]
    ms.drive(gentle_scene, waypoints=wp, seconds=3.0, out_dir=tmp_path / "single")
    ms.drive_team(gentle_scene, [ms.Robot(name="rover1", waypoints=wp)], seconds=3.0,
                  out_dir=tmp_path / "team")
    for name in LOGS:  # noise-free: the team's loop is the single drive's, step for step
        assert (tmp_path / "team" / "rover1" / name).read_bytes() == \
            (tmp_path / "single" / name).read_bytes(), name


def test_each_robot_has_its_own_noise_and_adding_one_moves_nobody_elses(
        gentle_scene: Path, tmp_path: Path):
    a = ms.Robot(name="rover1", waypoints=[[-6.0, -4.0], [6.0, -4.0]])
    b = ms.Robot(name="rover2", waypoints=[[-6.0, 4.0], [6.0, 4.0]])
    one = ms.drive_team(gentle_scene, [a], seconds=1.0, config=NOISY, seed=5)
    two = ms.drive_team(gentle_scene, [a, b], seconds=1.0, config=NOISY, seed=5)
    bias = lambda run, n: run.robots[n].summary["imu_bias"]["gyro_start_rad_s"]  # noqa: E731
    # the turn-on biases are the first draws of a robot's stream: the same beside a new robot
    assert bias(one, "rover1") == bias(two, "rover1") != bias(two, "rover2")
    draws = [robot_rng(5, "sensors", n).random(4) for n in ("rover1", "rover2", "rover1")]
    assert np.array_equal(draws[0], draws[2]) and not np.array_equal(draws[0], draws[1])


def test_two_rovers_driving_head_on_stop_each_other(flat_scene: Path):
    team = ms.drive_team(flat_scene, [
        ms.Robot(name="west", start_xy_m=(-5.0, 0.0), start_yaw_rad=0.0, command=(0.5, 0.0)),
        ms.Robot(name="east", start_xy_m=(5.0, 0.0), start_yaw_rad=np.pi, command=(0.5, 0.0)),
    ], seconds=16.0)
    west, east = (team.robots[n].gt.xyz_m[-1] for n in ("west", "east"))
    # apart they would pass through each other (8 m each, to x = +3 and -3); they meet instead
    assert west[0] < -0.5 and east[0] > 0.5
    assert east[0] - west[0] > 2.0  # bodies, not points: chassis to chassis
    assert team.robots["west"].summary["path_length_m"] < 5.5


def test_a_mast_camera_sees_the_other_rover(flat_scene: Path):
    from marsscene.sim.team import Placement, TeamSim

    cam = ms.CameraConfig(width_px=64, height_px=48)
    run = ms.RunConfig(camera=cam)
    alone = TeamSim(flat_scene, [Placement("a", RoverConfig(), run, (-4.0, 0.0))])
    pair = TeamSim(flat_scene, [Placement("a", RoverConfig(), run, (-4.0, 0.0)),
                                Placement("b", RoverConfig(), run, (2.0, 0.0))])
    depth = []
    for team in (alone, pair):
        renderer = team.members[0].make_renderer()
        try:
            depth.append(team.members[0].render(renderer)[1])
        finally:
            renderer.close()
    rows, cols = slice(16, 20), slice(30, 34)  # the image centre, below the horizon
    assert depth[0][rows, cols].min() > 7.5  # the ground, 8 to 11 m off
    assert depth[1][rows, cols].max() < 6.5  # rover b, whose front is 4.5 m off


def test_a_mer_rover_drives_beside_a_perseverance_rover(gentle_scene: Path, tmp_path: Path):
    team = ms.drive_team(gentle_scene, [
        ms.Robot(name="rover1", waypoints=[[-6.0, -4.0], [6.0, -4.0]]),
        ms.Robot(name="mer1", rover="mer", waypoints=[[-6.0, 4.0], [6.0, 4.0]]),
    ], seconds=4.0, out_dir=tmp_path / "team")
    mer = RoverConfig.load("mer")
    meta = json.loads((tmp_path / "team" / "mer1" / "run.json").read_text())
    assert meta["rover"]["mass_kg"] == mer.mass_kg and meta["team"] == ["rover1", "mer1"]
    v_mer = mer.wheel_speed_limit_rad_s * mer.wheel_radius_m  # its wheels' top ground speed
    assert team.robots["mer1"].summary["path_length_m"] <= v_mer * 4.0 + 0.02
    assert team.robots["rover1"].summary["path_length_m"] > 1.5
    doc = json.loads((tmp_path / "team" / "team.json").read_text())
    assert [(r["name"], r["rover"]) for r in doc["robots"]] == [("rover1", "perseverance"),
                                                                ("mer1", "mer")]


def test_drive_rover_option_and_team_file_from_the_command_line(gentle_scene: Path,
                                                                 tmp_path: Path):
    wp = tmp_path / "wp.txt"
    wp.write_text("-6 0\n6 0\n")
    res = CliRunner().invoke(main, ["drive", str(gentle_scene), "--waypoints", str(wp),
                                    "--rover", "mer", "--seconds", "1", "--out",
                                    str(tmp_path / "mer")])
    assert res.exit_code == 0, res.output
    meta = json.loads((tmp_path / "mer" / "run.json").read_text())
    assert meta["rover"]["mass_kg"] == RoverConfig.load("mer").mass_kg
    team = tmp_path / "team.toml"
    team.write_text('seconds = 1.0\n[[robots]]\nname = "a"\nwaypoints = [[-6, -4], [6, -4]]\n'
                    '[[robots]]\nname = "b"\nrover = "mer"\nwaypoints = [[-6, 4], [6, 4]]\n'
                    '[robots.run.lidar]\nmodel = "simple"\n')
    res = CliRunner().invoke(main, ["drive", str(gentle_scene), "--team", str(team), "--out",
                                    str(tmp_path / "t"), "--bag", "--keep-lidar-files"])
    assert res.exit_code == 0, res.output
    assert len(list((tmp_path / "t" / "b" / "lidar").glob("*.ply"))) == 11  # 10 Hz, 0 to 1 s
    assert not (tmp_path / "t" / "a" / "lidar").exists()  # a robot's sensors are its own
    assert "bag: " + str(tmp_path / "t" / "b" / "bag") + " (topics under /b)" in res.output
    from rosbags.highlevel import AnyReader

    with AnyReader([tmp_path / "t" / "b" / "bag"]) as r:
        lidar = [c for c in r.connections if c.topic == "/b/lidar/points"]
        assert sum(1 for _ in r.messages(lidar)) == 11


@pytest.mark.parametrize(("text", "says"), [
    ('[[robots]]\nname = "a"\nstart_xy_m = [0, 0]\n[[robots]]\nname = "a"\n'
     'start_xy_m = [9, 0]\n', "names must differ"),
    ('[[robots]]\nname = "a"\nstart_xy_m = [0, 0]\n[[robots]]\nname = "b"\n'
     'start_xy_m = [1, 0]\n', "footprints need"),
    ('[[robots]]\nname = "a"\nspeed = 3\n', "unknown keys ['speed']"),
    ('[[robots]]\nname = "1a"\n', "a letter first"),
    ('[[robots]]\nname = "a"\nrover = "tank"\n', "tank"),
])
def test_a_bad_team_file_is_one_line_and_writes_nothing(gentle_scene: Path, tmp_path: Path,
                                                         text: str, says: str):
    team = tmp_path / "team.toml"
    team.write_text("seconds = 1.0\n" + text)
    res = CliRunner().invoke(main, ["drive", str(gentle_scene), "--team", str(team), "--out",
                                    str(tmp_path / "t")])
    assert res.exit_code != 0 and says in res.output, res.output
    assert "Traceback" not in res.output and len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "t").exists()


def test_robot_names_and_counts_are_checked():
    with pytest.raises(ConfigError, match="letter first"):
        ms.Robot(name="rover/1")
    with pytest.raises(ConfigError, match="at least one robot"):
        ms.drive_team("nowhere", [])


def test_a_lidar_sees_the_other_rover(flat_scene: Path):
    from marsscene.sensors.lidar import Lidar
    from marsscene.sim.team import Placement, TeamSim

    run = ms.RunConfig(lidar=ms.LidarConfig(model="vlp16"))
    alone = TeamSim(flat_scene, [Placement("a", RoverConfig(), run, (-4.0, 0.0))])
    pair = TeamSim(flat_scene, [Placement("a", RoverConfig(), run, (-4.0, 0.0)),
                                Placement("b", RoverConfig(), run, (2.0, 0.0))])
    above = []
    for team in (alone, pair):
        a = team.members[0]
        lidar = Lidar(run.lidar, rng=np.random.default_rng(0))
        scan = lidar.prepare(a.model, a.data, a.lidar_site, a.heightfield,
                             boxes=a.other_robots())()
        rot = a.data.site_xmat[a.lidar_site].reshape(3, 3)
        world = scan["xyz_m"] @ rot.T + a.data.site_xpos[a.lidar_site]
        above.append(world[world[:, 2] > 0.3])  # the flat ground is z = 0
    assert alone.members[0].other_robots() is None and len(above[0]) == 0
    near_x = above[1][:, 0].min()  # rover b's rear, about 1.5 m behind its centre at x = 2
    assert len(above[1]) > 50 and 0.0 < near_x < 1.2
    assert np.abs(above[1][:, 1]).max() < 1.6  # within b's width


def test_each_robots_bag_is_the_single_drives_under_its_namespace(gentle_scene: Path,
                                                                  tmp_path: Path):
    """A team of one writes the single drive's bag, its topics under ``/rover1`` and its
    frames prefixed ``rover1/`` (``map`` shared): the same messages otherwise."""
    from rosbags.highlevel import AnyReader

    wp, bag = [[-6.0, -2.0], [6.0, -2.0]], ms.ExportOptions(bag=ms.BagOptions())
    ms.drive(gentle_scene, waypoints=wp, seconds=1.0, out_dir=tmp_path / "single", export=bag)
    team = ms.drive_team(gentle_scene, [ms.Robot(name="rover1", waypoints=wp)], seconds=1.0,
                         out_dir=tmp_path / "team", export=bag)
    assert team.robots["rover1"].bag is not None
    read = {}
    for key, folder in (("single", tmp_path / "single" / "bag"),
                        ("team", tmp_path / "team" / "rover1" / "bag")):
        with AnyReader([folder]) as r:
            read[key] = [(c.topic, r.deserialize(raw, c.msgtype)) for c, _, raw in r.messages()]
    assert [t.replace("/rover/", "/rover1/") for t, _ in read["single"]] == \
        [t for t, _ in read["team"]]
    prefixed = lambda f: f if f == "map" else f"rover1/{f}"  # noqa: E731
    for (topic, a), (_, b) in zip(read["single"], read["team"], strict=True):
        for x, y in zip(getattr(a, "transforms", [a]), getattr(b, "transforms", [b]),
                        strict=True):
            if hasattr(x, "header"):
                assert y.header.frame_id == prefixed(x.header.frame_id), topic
                assert y.header.stamp == x.header.stamp, topic
            if getattr(x, "child_frame_id", ""):
                assert y.child_frame_id == prefixed(x.child_frame_id), topic
        if topic == "/rover/odom":
            pa, pb = a.pose.pose.position, b.pose.pose.position
            assert (pb.x, pb.y, pb.z) == (pa.x, pa.y, pa.z)
    meta = json.loads((tmp_path / "team" / "rover1" / "run.json").read_text())
    assert meta["ros"] == {"namespace": "rover1", "frame_prefix": "rover1/",
                           "control": "/marsscene/rover1"}


def test_a_scout_flies_over_the_team_and_its_images_pair_with_the_rovers(gentle_scene: Path,
                                                                       tmp_path: Path):
    """A ``[[scouts]]`` table flies over the rovers' terrain in their map frame; each of its
    images seen near a rover pairs with that rover's frame (``crossview.csv``), and the scout's
    noise is its own (its name's stream)."""
    team = tmp_path / "team.toml"
    team.write_text('seconds = 3.0\n[[robots]]\nname = "rover1"\n'
                    'waypoints = [[-6, 0], [6, 0]]\n[robots.run.camera]\nwidth_px = 64\n'
                    'height_px = 48\nshadows = false\n'
                    '[[scouts]]\nname = "heli"\nstart_xy_m = [-12.0, 0.0]\n'
                    'waypoints = [[-6.0, 0.0], [12.0, 0.0]]\naltitude_m = 6.0\n'
                    'camera_hz = 1.0\n')
    res = CliRunner().invoke(main, ["drive", str(gentle_scene), "--team", str(team), "--out",
                                    str(tmp_path / "t"), "--dataset", "tum-rgbd"])
    if "OpenGL" in res.output:
        pytest.skip("no headless OpenGL (EGL/OSMesa) here")
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "t" / "team.json").read_text())
    assert doc["scouts"][0]["name"] == "heli" and doc["scouts"][0]["reached"]
    rgb = (tmp_path / "t" / "rover1" / "tum_rgbd" / "rgb.txt").read_text().splitlines()
    assert len([r for r in rgb if not r.startswith("#")]) == 31  # the rover's dataset: 10 Hz
    rows = (tmp_path / "t" / "crossview.csv").read_text().splitlines()
    from marsscene.runtime.crossview import HEADER

    assert rows[0] == HEADER and len(rows) > 1
    for row in rows[1:]:
        f = row.split(",")
        assert f[0] == "heli" and f[6] == "rover1"
        assert (tmp_path / "t" / f[1]).is_file() and (tmp_path / "t" / f[7]).is_file()
        d = float(f[12])
        assert d <= 5.0 and d == pytest.approx(np.hypot(float(f[3]) - float(f[9]),
                                                        float(f[4]) - float(f[10])), abs=2e-4)
    from marsscene.scout import FlightPlan, fly

    plan, wp = FlightPlan(altitude_m=6.0, camera_hz=1.0), [[-6.0, 0.0], [12.0, 0.0]]
    fly(gentle_scene, wp, plan=plan, start_xy_m=(-12.0, 0.0), out_dir=tmp_path / "alone",
        rng=robot_rng(0, "sensors", "heli"))
    fly(gentle_scene, wp, plan=plan, start_xy_m=(-12.0, 0.0), out_dir=tmp_path / "seed0")
    team_alt = (tmp_path / "t" / "heli" / "altimeter.csv").read_bytes()
    assert team_alt == (tmp_path / "alone" / "altimeter.csv").read_bytes()  # the same flight
    assert team_alt != (tmp_path / "seed0" / "altimeter.csv").read_bytes()  # its own noise
