"""A stock ROS 2 Jazzy node drives a lockstep session and sees the rover's types with their
ROS 2 type hashes: rclpy on ``rmw_fastrtps_cpp`` from the
``ros-jazzy-*`` wheels (no ROS installation), loopback only through a Fast DDS XML profile.

The wheels live in their own environment; point ``MARSSCENE_ROS2_PYTHON`` at its Python
(``python3 -m venv ros && ros/bin/pip install "ros-jazzy-rclpy[fastrtps]"
ros-jazzy-geometry-msgs ros-jazzy-nav-msgs ros-jazzy-rosgraph-msgs ros-jazzy-sensor-msgs``).
Without it the test is skipped."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve

pytest.importorskip("mujoco")
ROS_PYTHON = os.environ.get("MARSSCENE_ROS2_PYTHON", "")
pytestmark = pytest.mark.skipif(not ROS_PYTHON, reason="MARSSCENE_ROS2_PYTHON is not set")

SUPPORT = Path(__file__).resolve().parents[1] / "support"
DOMAIN, STEPS, DT_S = 216, 30, 1.0 / 50.0


def _session(scene: Path, sleep_per_scan_s: float) -> tuple[dict, ms.DriveRun]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CYCLONEDDS_URI")}
    env.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_DOMAIN_ID=str(DOMAIN),
               FASTRTPS_DEFAULT_PROFILES_FILE=str(SUPPORT / "fastdds_loopback.xml"))
    client = subprocess.Popen([ROS_PYTHON, str(SUPPORT / "rclpy_client.py"), str(STEPS),
                               str(DT_S), "0.4", "0.1", "--sleep-per-scan",
                               str(sleep_per_scan_s)], stdout=subprocess.PIPE, text=True, env=env)
    try:
        res = serve(scene, ros=Ros2Options(domain_id=DOMAIN, localhost=True, pace="lockstep"),
                    config=ms.RunConfig(lidar=ms.LidarConfig(model="simple")),
                    seconds=STEPS * DT_S, seed=3)
        out, _ = client.communicate(timeout=120)
    finally:
        client.kill()
    return json.loads(out), res


def test_a_jazzy_node_steps_the_rover_in_lockstep(gentle_scene: Path) -> None:
    runs = [_session(gentle_scene, 0.0), _session(gentle_scene, 0.2)]
    for got, res in runs:
        sent = res.stats["messages"]
        assert "marsscene_rover" in got["nodes"]  # the rover's node in the ROS graph
        assert got["counts"]["lidar"] == sent["/rover/lidar/points"] >= 6
        assert got["counts"]["odom"] == sent["/rover/odom"] == STEPS + 1
    assert runs[0][0]["sha256"] == runs[1][0]["sha256"]  # the slow client saw the same
    for topic, seen in runs[0][0]["type_hashes"].items():  # Jazzy's graph: the rover's type
        assert {n.split()[0] for n in seen} == {"marsscene_rover", "lockstep_client"}, topic
        assert len(set(seen.values())) == 1, seen  # hashes are ROS 2's own
        assert next(iter(seen.values())).startswith("RIHS01_"), seen
