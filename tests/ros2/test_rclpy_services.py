"""A stock ROS 2 Jazzy client on Fast DDS (Jazzy's default) calls a service of the session:
it finds the service but its call is never answered (ROS 2 services do not cross middleware
vendors), and the server's log says, in one line, what to set and which topics do the job.

Needs ``MARSSCENE_ROS2_PYTHON`` as ``test_rclpy_client.py`` (plus the
``ros-jazzy-simulation-interfaces`` wheel in that environment); skipped without it."""

from __future__ import annotations

import json
import logging
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
DOMAIN = 218


def test_a_fast_dds_call_times_out_and_the_log_says_why(gentle_scene: Path, caplog) -> None:
    from marsscene.ros2 import services

    services._said_other[0] = False
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CYCLONEDDS_URI")}
    env.update(RMW_IMPLEMENTATION="rmw_fastrtps_cpp", ROS_DOMAIN_ID=str(DOMAIN),
               FASTRTPS_DEFAULT_PROFILES_FILE=str(SUPPORT / "fastdds_loopback.xml"))
    client = subprocess.Popen([ROS_PYTHON, str(SUPPORT / "rclpy_sim_client.py")],
                              stdout=subprocess.PIPE, text=True, env=env)
    try:
        with caplog.at_level(logging.WARNING, logger="marsscene"):
            serve(gentle_scene, ros=Ros2Options(domain_id=DOMAIN, localhost=True, pace="realtime"),
                  config=ms.RunConfig(), seconds=20.0, seed=3)
        out, _ = client.communicate(timeout=60)
    finally:
        client.kill()
    got = json.loads(out)
    assert got["answered"] is False
    hints = [r.getMessage() for r in caplog.records if "rmw_cyclonedds_cpp" in r.getMessage()]
    assert len(hints) == 1 and "Fast DDS" in hints[0] and "/marsscene/reset" in hints[0]
