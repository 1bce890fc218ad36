"""Two stock ROS 2 Jazzy nodes drive a served team (``examples/ros2_team_goto.py``): rclpy on
``rmw_fastrtps_cpp`` from the ``ros-jazzy-*`` wheels, each node in its robot's namespace
(relative ``odom`` and ``cmd_vel``), loopback only through a Fast DDS XML profile. Each robot
reaches its own goal. Skipped without ``MARSSCENE_ROS2_PYTHON`` (see test_rclpy_client.py)."""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve_team

pytest.importorskip("mujoco")
ROS_PYTHON = os.environ.get("MARSSCENE_ROS2_PYTHON", "")
pytestmark = pytest.mark.skipif(not ROS_PYTHON, reason="MARSSCENE_ROS2_PYTHON is not set")

ROOT = Path(__file__).resolve().parents[2]
SUPPORT = ROOT / "tests" / "support"
DOMAIN = 221
#: Each robot's start and goal (map frame, m): the MER-class rover's top speed is 5 cm/s.
GOALS = {"r1": ((-8.0, -4.0), (-4.5, -3.0)), "r2": ((-8.0, 4.0), (-7.6, 4.4))}


def test_two_jazzy_nodes_drive_their_own_robots_to_their_goals(gentle_scene: Path,
                                                                tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CYCLONEDDS_URI")}
    env.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_DOMAIN_ID=str(DOMAIN),
               FASTRTPS_DEFAULT_PROFILES_FILE=str(SUPPORT / "fastdds_loopback.xml"))
    goals = [f"{n}:{g[0]},{g[1]}" for n, (_, g) in GOALS.items()]
    nodes = subprocess.Popen([ROS_PYTHON, str(ROOT / "examples" / "ros2_team_goto.py"),
                              *goals, "--seconds", "60"], stdout=subprocess.PIPE, text=True,
                             env=env)
    robots = [ms.Robot(name="r1", start_xy_m=GOALS["r1"][0]),
              ms.Robot(name="r2", rover="mer", start_xy_m=GOALS["r2"][0])]
    try:
        res = serve_team(gentle_scene, robots, ros=Ros2Options(domain_id=DOMAIN, localhost=True,
                                                               rover_cmd_vel=False),
                         seconds=25.0, out_dir=tmp_path / "team", seed=1)
        got = json.loads(nodes.communicate(timeout=90)[0])
    finally:
        nodes.kill()
    for name, (start, goal) in GOALS.items():
        end = res.robots[name].gt.xyz_m[-1]
        assert math.dist(end[:2], goal) < 0.45, (name, end, got[name])  # ground truth
        assert got[name]["distance_m"] < 0.45  # and as the node's own odometry says
        assert math.dist(got[name]["start_xy_m"], start) < 0.05
        assert res.robots[name].stats["commands"] > 50
