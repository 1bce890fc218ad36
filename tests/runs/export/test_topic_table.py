"""One topic table: the bag's connections (names, types, order, offered QoS) and the live
publisher's topics are its rows, and the DDS QoS is built from its profiles."""

from __future__ import annotations

from pathlib import Path

import pytest

from marsscene.runs.export.topic_table import QOS_PROFILES, topic_table

pytest.importorskip("rosbags")


def test_every_topic_names_a_profile_and_only_static_ones_are_latched():
    table = topic_table(images="both", camera=True, depth=True, stereo=True, lidar=True,
                        depth_cloud=True)
    assert len({t.name for t in table}) == len(table) == 25
    assert {t.qos for t in table} <= set(QOS_PROFILES)
    assert [t.name for t in table if t.latched] == ["/tf_static", "/rover/robot_description"]


@pytest.mark.parametrize("images", ["raw", "compressed", "both"])
def test_the_bag_writes_the_table_in_its_order(stereo_run: Path, tmp_path: Path, images: str):
    from rosbags.highlevel import AnyReader

    from marsscene.runs.export.bag import write_bag
    from marsscene.runs.runlog import RunLog

    bag = write_bag(stereo_run, tmp_path / "bag", images=images, depth_cloud=True)
    run = RunLog(stereo_run)
    cams = run.camera_streams()
    table = topic_table(images=images, imu_true=run.imu_true is not None, camera=True,
                        depth=bool(cams[0].depth_files), stereo=len(cams) > 1,
                        lidar=run.lidar is not None, depth_cloud=True)
    with AnyReader([bag.path]) as reader:
        conns = sorted(reader.connections, key=lambda c: c.id)
        assert [(c.topic, c.msgtype) for c in conns] == [(t.name, t.msgtype) for t in table]
        for c, t in zip(conns, table, strict=True):
            offered = c.ext.offered_qos_profiles
            assert bool(offered) == t.latched, t.name
            for qos in offered:
                p = QOS_PROFILES[t.qos]
                assert (qos.depth, qos.reliability.name, qos.durability.name) == (
                    p.depth, "RELIABLE", "TRANSIENT_LOCAL")


def test_live_publisher_offers_the_table():
    from marsscene.rover.config import NoiseConfig, RoverConfig
    from marsscene.runs.export.bag_topics import ImageOptions
    from marsscene.runs.export.sample_messages import SampleMessages

    intr = {"width": 4, "height": 3, "fx": 2.0, "fy": 2.0, "cx": 2.0, "cy": 1.5}
    sm = SampleMessages(RoverConfig(), NoiseConfig(), imu_hz=100.0, camera=intr,
                        camera_depth=False, images=ImageOptions(images="raw"))
    assert sm.topics() == topic_table(images="raw", camera=True)


def test_dds_qos_is_built_from_the_profiles():
    pytest.importorskip("cyclonedds")
    from cyclonedds.core import Policy

    from marsscene.ros2.dds import QOS

    assert set(QOS) == set(QOS_PROFILES)
    for name, p in QOS_PROFILES.items():
        durability = Policy.Durability.TransientLocal if p.transient_local \
            else Policy.Durability.Volatile
        assert Policy.History.KeepLast(p.depth) in QOS[name], name
        assert durability in QOS[name], name
