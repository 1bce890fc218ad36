"""The bytes on the wire: for every type the live rover publishes or reads, the DDS type made
from the rosbags definition round-trips rosbags' CDR byte for byte through Cyclone DDS's own
serialiser, and a payload written by :class:`RawWriter` arrives at a separate participant as the
rosbags CDR (padded to 4 bytes, as ROS 2's middlewares send it)."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np
import pytest

from marsscene.ros2 import dds
from marsscene.ros2.options import Ros2Options, localhost_from_env
from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.lidar import LidarConfig
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.sample_messages import SampleMessages
from tests.support import DDS_PEER

PEER = str(DDS_PEER)
INTR = {"width": 32, "height": 24, "fx": 20.0, "fy": 20.0, "cx": 16.0, "cy": 12.0}


def _messages(images: str = "both") -> tuple[SampleMessages, list[tuple[str, object]]]:
    """One sample of every stream through SampleMessages (every topic it can make)."""
    rng = np.random.default_rng(0)
    lidar = LidarConfig(model="simple").spec.to_dict()
    sm = SampleMessages(RoverConfig(), NoiseConfig(profile="ln200s"), imu_hz=100.0,
                        lidar=lidar, camera=INTR, stereo={side: {**INTR, "baseline_m": 0.4}
                                                          for side in ("left", "right")},
                        images=ImageOptions(images=images, depth_cloud=True))
    pairs = sm.static(0.0)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    for k in range(2):
        t = 0.02 * k
        pairs += sm.control(t, 0.3, 0.1, rng.normal(size=6), rng.normal(size=4) * 0.1,
                            (np.array([k * 0.01, 0, 0.7]), q), (np.array([k * 0.01, 0, 0.7]), q))
    pairs += sm.imu(0.0, rng.normal(size=3), rng.normal(size=3), np.zeros(3), np.zeros(3))
    rgb = rng.integers(0, 255, (24, 32, 3), dtype=np.uint8)
    pairs += sm.camera(0.0, 0, rgb, rng.uniform(0.5, 30.0, (24, 32)).astype(np.float32))
    pairs += sm.stereo(0.0, 0, (rgb, rgb))
    n = 200
    scan = {"xyz_m": rng.normal(size=(n, 3)).astype(np.float32),
            "intensity": rng.uniform(size=n).astype(np.float32),
            "ring": rng.integers(0, int(lidar["channels"]), n).astype(np.uint16),
            "t_s": np.linspace(0, 0.09, n), "range_m": np.ones(n)}
    pairs += sm.lidar(0.0, 0, scan)
    return sm, pairs


def test_every_published_type_round_trips_rosbags_cdr_through_cyclone():
    sm, pairs = _messages()
    store = sm.b.store
    assert {topic for topic, _ in pairs} == {t.name for t in sm.topics()}  # every topic
    types = {msg.__msgtype__: msg for _, msg in pairs}
    types["geometry_msgs/msg/TwistStamped"] = store.types["geometry_msgs/msg/TwistStamped"](
        header=sm.b.header(1.5, "base_link"), twist=sm.b.twist(0.2, -0.1))
    types["geometry_msgs/msg/PoseStamped"] = store.types["geometry_msgs/msg/PoseStamped"](
        header=sm.b.header(0.0, "map"), pose=store.types["geometry_msgs/msg/Pose"](
            position=store.types["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=0.0),
            orientation=sm.b.quat((0, 0, 0, 1))))
    types["std_msgs/msg/Empty"] = store.types["std_msgs/msg/Empty"]()
    types["std_msgs/msg/Bool"] = store.types["std_msgs/msg/Bool"](data=True)
    for msgtype, msg in sorted(types.items()):
        cdr = bytes(sm.b.serialize(msg))
        cls = dds.dds_type(store, msgtype)
        assert cls.__idl_typename__ == "{}::msg::dds_::{}_".format(*msgtype.split("/msg/"))
        assert cls.__idl_annotations__["extensibility"] == "final"
        again = cls.deserialize(cdr).serialize(use_version_2=False)
        assert again[: len(cdr)] == cdr, msgtype  # Cyclone's CDR of the same value
        assert set(again[len(cdr):]) <= {0} and len(again) - len(cdr) < 4, msgtype


def test_raw_writer_sends_the_rosbags_bytes_on_loopback(tmp_path):
    """A separate process (the independent peer, plain cyclonedds) receives the payloads."""
    sm, pairs = _messages(images="raw")
    want = {"/rover/rgb/image_raw", "/rover/imu_noisy", "/tf", "/rover/depth/points"}
    byname = {t: m for t, m in pairs if t in want}
    spec = {t: [m.__msgtype__, True, False] for t, m in byname.items()}
    peer = subprocess.Popen([sys.executable, PEER, "listen", "211", "4", json.dumps(spec),
                             "--dump", str(tmp_path)], stdout=subprocess.PIPE, text=True)
    part = dds.Participant(211, localhost=True)
    try:
        writers = {t: part.writer(sm.b.store, t, m.__msgtype__, "default")
                   for t, m in byname.items()}
        t0 = time.monotonic()
        while peer.poll() is None and time.monotonic() - t0 < 20.0:
            for t, m in byname.items():
                if writers[t].subscribers:
                    writers[t].write(sm.b.serialize(m))
            time.sleep(0.05)
        out, _ = peer.communicate(timeout=20)
    finally:
        part.close()
    got = json.loads(out)
    for t, m in byname.items():
        assert got[t]["n"] > 0, t
        cdr = bytes(sm.b.serialize(m))
        wire = (tmp_path / (t.strip("/").replace("/", "_") + ".cdr")).read_bytes()
        assert wire == cdr + b"\0" * (-len(cdr) % 4), t


def test_localhost_mode_follows_ros2_switches_and_keeps_a_users_uri():
    assert localhost_from_env({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    assert not localhost_from_env({"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET",
                                   "ROS_LOCALHOST_ONLY": "1"})  # the newer switch wins
    assert localhost_from_env({"ROS_LOCALHOST_ONLY": "1"})
    assert not localhost_from_env({})
    xml = dds.cyclone_config(True, {})
    assert xml is not None
    for part in ('address="127.0.0.1"', "<AllowMulticast>false</AllowMulticast>",
                 '<Peer Address="127.0.0.1"/>'):
        assert part in xml
    user = "file:///etc/cyclone.xml"
    assert dds.cyclone_config(True, {"CYCLONEDDS_URI": user}) == f"{user},{xml}"  # ours last
    assert dds.cyclone_config(False, {"CYCLONEDDS_URI": user}) is None  # Cyclone reads it


def test_options_are_checked_with_one_line_errors(monkeypatch):
    from marsscene.errors import ConfigError

    for bad in ({"pace": "fast"}, {"cmd_vel_topic": "cmd_vel"}, {"realtime_factor": 0},
                {"node_name": "my node"}, {"images": "jpeg"}):
        with pytest.raises(ConfigError) as err:
            Ros2Options.from_dict(bad)
        assert "\n" not in str(err.value)
    monkeypatch.setenv("ROS_DOMAIN_ID", "7")
    assert Ros2Options().domain == 7 and Ros2Options(domain_id=3).domain == 3
    monkeypatch.setenv("ROS_DOMAIN_ID", "x")
    with pytest.raises(ConfigError, match="ROS_DOMAIN_ID"):
        _ = Ros2Options().domain


def test_both_command_topics_are_obeyed_by_default_and_the_namespace_is_checked():
    from marsscene.errors import ConfigError

    assert Ros2Options().cmd_vel_topics == ("/cmd_vel", "/rover/cmd_vel")
    assert Ros2Options(rover_cmd_vel=False).cmd_vel_topics == ("/cmd_vel",)
    assert Ros2Options(cmd_vel_topic="/rover/cmd_vel").cmd_vel_topics == ("/rover/cmd_vel",)
    assert Ros2Options(sim_namespace="/gzserver").sim_namespace == "/gzserver"
    for bad in ("gzserver", "/gz server", "/9x"):
        with pytest.raises(ConfigError, match="sim_namespace"):
            Ros2Options(sim_namespace=bad)
