"""A served team end to end: two robots in one world, each driven by its own independent DDS
peer on its own namespace (``/r1/cmd_vel``, ``/r2/cmd_vel``), heard by a third that imports
nothing from marsscene; then each robot's bag, read back with ``rosbags``."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve_team
from tests.support import DDS_PEER

pytest.importorskip("mujoco")

PEER = str(DDS_PEER)
DOMAIN = 214
SECONDS = 3.0
COMMANDS = {"r1": (0.4, 0.0), "r2": (0.04, 0.2)}  # (v m/s, omega rad/s); MER's top: 5 cm/s
TOPICS = {
    "/clock": ["rosgraph_msgs/msg/Clock", False, False],
    "/tf": ["tf2_msgs/msg/TFMessage", True, False],
    "/tf_static": ["tf2_msgs/msg/TFMessage", True, True],
    **{f"/{n}/odom": ["nav_msgs/msg/Odometry", True, False] for n in COMMANDS},
    **{f"/{n}/imu_noisy": ["sensor_msgs/msg/Imu", False, False] for n in COMMANDS},
}


@pytest.fixture(scope="module")
def team(gentle_scene: Path, tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("live_team") / "team"
    listen = subprocess.Popen([sys.executable, PEER, "listen", str(DOMAIN), "--until-idle",
                               "2", "40", json.dumps(TOPICS)], stdout=subprocess.PIPE, text=True)
    drivers = [subprocess.Popen([sys.executable, PEER, "cmd", str(DOMAIN), "40", str(v), str(w),
                                 "--topic", f"/{name}/cmd_vel"], stdout=subprocess.PIPE, text=True)
               for name, (v, w) in COMMANDS.items()]
    robots = [ms.Robot(name="r1", start_xy_m=(-8.0, -4.0)),
              ms.Robot(name="r2", rover="mer", start_xy_m=(-8.0, 4.0))]
    made: dict = {}

    def ready(bridges) -> None:  # wait for the listener and both drivers
        made.update(bridges)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 20.0 and not all(
                b.writers[f"/{n}/odom"].subscribers for n, b in bridges.items()):
            time.sleep(0.05)
        time.sleep(1.0)  # the drivers' writers match too

    try:
        res = serve_team(gentle_scene, robots, ros=Ros2Options(domain_id=DOMAIN, localhost=True),
                         seconds=SECONDS, out_dir=out, seed=5, ready=ready,
                         export=ms.ExportOptions(bag=ms.BagOptions()))
    finally:
        for d in drivers:
            d.kill()
    yield res, out, listen, made
    listen.kill()


def test_each_robot_obeys_its_own_namespace(team):
    res, out, _, _ = team
    assert sorted(res.robots) == ["r1", "r2"]
    for name, (v, w) in COMMANDS.items():
        cmd = np.loadtxt(out / name / "cmd.csv", delimiter=",", skiprows=1)
        got = {(round(a, 3), round(b, 3)) for a, b in cmd[:, 1:3]}
        assert (v, w) in got and got <= {(v, w), (0.0, 0.0)}, (name, got)
        assert res.robots[name].stats["commands"] > 20
    gt = {n: np.loadtxt(out / n / "gt.tum", comments="#") for n in COMMANDS}
    assert np.ptp(gt["r1"][:, 2]) < 0.05 < gt["r1"][-1, 1] - gt["r1"][0, 1]  # straight, east
    turn = {n: float(np.diff(Rotation.from_quat(g[[0, -1], 4:8]).as_euler("zyx")[:, 0])[0])
            for n, g in gt.items()}
    assert turn["r2"] > 0.1 and abs(turn["r1"]) < 0.02  # only r2 was told to turn


def test_one_clock_and_prefixed_frames_under_one_map(team):
    _, _, listen, _ = team
    got = json.loads(listen.communicate(timeout=30)[0])
    clock = np.array(got["/clock"]["stamps"])
    assert len(clock) >= 0.9 * (100 * SECONDS) and np.all(np.diff(clock) > 0)  # one writer
    pairs = {tuple(p) for p in got["/tf"]["frames"]}
    for n in COMMANDS:
        assert {("map", f"{n}/odom"), (f"{n}/odom", f"{n}/base_link")} <= pairs
        assert {tuple(p) for p in got[f"/{n}/odom"]["frames"]} == {(f"{n}/odom",
                                                                    f"{n}/base_link")}
        assert {tuple(p) for p in got[f"/{n}/imu_noisy"]["frames"]} == {(f"{n}/imu_link", "")}
        assert (f"{n}/base_link", f"{n}/lidar_link") in {tuple(p) for p in
                                                        got["/tf_static"]["frames"]}


def test_the_lead_serves_every_robot_as_an_entity(team):
    _, _, _, bridges = team
    srv = bridges["r1"].control_srv
    assert bridges["r2"].control_srv is None  # one set of services for the team
    filters = SimpleNamespace(filter="", tags=SimpleNamespace(tags=[]),
                              bounds=SimpleNamespace(type=0), categories=[])
    assert list(srv._get_entities(SimpleNamespace(filters=filters), None).entities) == [
        "r1", "r2"]
    filters.filter = "^r2$"
    assert list(srv._get_entities(SimpleNamespace(filters=filters), None).entities) == ["r2"]
    got = srv._get_entity_state(SimpleNamespace(entity="/r2"), None)
    assert got.result.result == 1  # OK
    pose = got.state.pose.position
    assert pose.y == pytest.approx(bridges["r2"].sim.pose()[0][1])


def test_each_robots_bag_is_its_namespace(team):
    from rosbags.highlevel import AnyReader

    res, out, _, _ = team
    for n in COMMANDS:
        assert res.robots[n].bag is not None
        with AnyReader([out / n / "bag"]) as reader:
            topics = {c.topic for c in reader.connections}
            assert {f"/{n}/odom", f"/{n}/cmd_vel", "/clock", "/tf"} <= topics
            assert not any(t.startswith("/rover/") for t in topics)
            conn = next(c for c in reader.connections if c.topic == f"/{n}/odom")
            _, _, raw = next(reader.messages([conn]))
            msg = reader.deserialize(raw, conn.msgtype)
            assert (msg.header.frame_id, msg.child_frame_id) == (f"{n}/odom", f"{n}/base_link")
