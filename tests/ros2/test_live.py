"""A live session end to end, with independent peers (plain cyclonedds + rosbags processes that
import nothing from marsscene): every topic arrives at its rate and decodes, and a ``/cmd_vel``
publisher moves the rover exactly as ``ms.drive(command=...)`` does with the same commands."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve
from marsscene.runs.export.topic_table import topic_table
from marsscene.runs.tum import read_tum
from tests.support import DDS_PEER

pytest.importorskip("mujoco")

PEER = str(DDS_PEER)
DOMAIN = 212
SECONDS = 3.0
TOPICS = {  # name: [msgtype, reliable, transient local] as a ROS 2 subscriber would ask
    "/clock": ["rosgraph_msgs/msg/Clock", False, False],
    "/tf": ["tf2_msgs/msg/TFMessage", True, False],
    "/tf_static": ["tf2_msgs/msg/TFMessage", True, True],
    "/rover/robot_description": ["std_msgs/msg/String", True, True],
    "/rover/odom": ["nav_msgs/msg/Odometry", True, False],
    "/rover/GT_Trajectory": ["nav_msgs/msg/Odometry", False, False],
    "/rover/joint_states": ["sensor_msgs/msg/JointState", False, False],
    "/rover/imu": ["sensor_msgs/msg/Imu", False, False],
    "/rover/imu_noisy": ["sensor_msgs/msg/Imu", False, False],
    "/rover/lidar/points": ["sensor_msgs/msg/PointCloud2", False, False],
    "/rover/scan": ["sensor_msgs/msg/LaserScan", False, False],
    "/rover/rgb/image_raw/compressed": ["sensor_msgs/msg/CompressedImage", False, False],
    "/rover/depth/image_raw/compressedDepth": ["sensor_msgs/msg/CompressedImage", False, False],
    "/rover/rgb/camera_info": ["sensor_msgs/msg/CameraInfo", False, False],
    "ros_discovery_info": ["rmw_dds_common/msg/ParticipantEntitiesInfo", True, True],
}
RATES_HZ = {"/clock": 100, "/tf": 50, "/rover/odom": 50, "/rover/GT_Trajectory": 50,
            "/rover/joint_states": 50, "/rover/imu": 100, "/rover/imu_noisy": 100,
            "/rover/lidar/points": 10, "/rover/scan": 10, "/rover/rgb/image_raw/compressed": 10,
            "/rover/depth/image_raw/compressedDepth": 10, "/rover/rgb/camera_info": 10}


@pytest.fixture(scope="module")
def session(gentle_scene: Path, tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("live") / "run"
    listen = subprocess.Popen([sys.executable, PEER, "listen", str(DOMAIN), "--until-idle",
                               "2", "40",
                               json.dumps(TOPICS)], stdout=subprocess.PIPE, text=True)
    cmd = subprocess.Popen([sys.executable, PEER, "cmd", str(DOMAIN), "40", "0.4", "0.05"],
                           stdout=subprocess.PIPE, text=True)
    config = ms.RunConfig(camera=ms.CameraConfig(width_px=64, height_px=48, shadows=False),
                          lidar=ms.LidarConfig(model="simple"))

    def ready(bridge) -> None:  # wait for the listener before the clock starts
        t0 = time.monotonic()
        while time.monotonic() - t0 < 20.0 and not all(
                bridge.writers[t].subscribers for t in RATES_HZ):
            time.sleep(0.05)

    try:
        res = serve(gentle_scene, ros=Ros2Options(domain_id=DOMAIN, localhost=True),
                    config=config, seconds=SECONDS, out_dir=out, seed=5, ready=ready,
                    record=ms.BagOptions(), progress=_PROGRESS.append)
    except ms.MarsSceneError as err:
        if "OpenGL" in str(err):
            pytest.skip("no headless OpenGL (EGL/OSMesa) here")
        raise
    finally:
        cmd.kill()
    yield res, out, listen
    listen.kill()


#: What serve's progress callback received (the session fixture's).
_PROGRESS: list = []


def test_the_session_records_its_bag_and_reports_only_its_progress(session):
    """``record`` writes the bag through the drive's exports; ``progress`` hears the session
    (a DriveProgress a simulated second), never the bag export's own progress."""
    from marsscene.runtime import DriveProgress

    res, out, _ = session
    assert res.bag is not None and res.bag.path == out / "bag" and res.bag.path.is_dir()
    assert len(_PROGRESS) >= int(SECONDS) - 1
    assert all(isinstance(p, DriveProgress) for p in _PROGRESS)
    assert 0 < res.wall_s < 60.0


def test_every_topic_arrives_at_its_rate_and_decodes(session):
    res, _, listen = session
    got_text, _ = listen.communicate(timeout=30)
    assert res.result.summary["sim_time_s"] == pytest.approx(SECONDS)
    assert res.realtime_factor < 1.1  # paced to the wall clock (never ahead; a busy CI lags)
    got = json.loads(got_text) if got_text else {}
    for topic, hz in RATES_HZ.items():
        stamps = got[topic]["stamps"]
        assert len(stamps) >= 0.9 * (hz * SECONDS + 1), (topic, len(stamps))
        assert stamps[0] == pytest.approx(0.0) and np.all(np.diff(stamps) > 0), topic
    assert got["/tf_static"]["n"] == 1 and got["/rover/robot_description"]["n"] == 1
    # the node as `ros2 node list` reads it: 5 readers (/cmd_vel, /rover/cmd_vel, reset,
    # teleport, goal) and a writer per published topic, and the services' (12 + the action's
    # 3: a request reader and a reply writer each; the action's feedback and status writers)
    ns, name, readers, writers = got["ros_discovery_info"]["nodes"][-1]
    assert (ns, name, readers) == ("/", "marsscene_rover", 5 + 15)
    table = topic_table(camera=True, depth=True, lidar=True, images="both")
    assert writers == len(table) - 1 + 1 + 15 + 2  # not /rover/cmd_vel; + goal_reached


def test_cmd_vel_moves_the_rover_as_drive_with_the_same_commands(session, gentle_scene):
    res, out, _ = session
    cmd = np.loadtxt(out / "cmd.csv", delimiter=",", skiprows=1)
    assert res.stats["commands"] > 20 and np.any(cmd[:, 1] == 0.4)
    table = {round(t / 0.02): (v, w) for t, v, w in cmd}

    def replay(t_s: float) -> tuple[float, float]:
        return table[round(t_s / 0.02)]

    again = ms.drive(gentle_scene, command=replay, seconds=SECONDS, seed=5)
    live = read_tum(out / "gt.tum")
    assert live.path_length_m() > 0.5
    np.testing.assert_allclose(again.gt.xyz_m, live.xyz_m, atol=1e-6)
