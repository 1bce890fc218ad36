"""A stock ROS 2 Jazzy client on Fast DDS (Jazzy's default) calls a service of the session:
it finds the service but its call is never answered (ROS 2 services do not cross middleware
vendors), and the server's log says, in one line, what to set and which topics do the job.

Needs ``MARSSCENE_ROS2_PYTHON`` as ``test_rclpy_client.py``; skipped without it. PyPI has no
``ros-jazzy-simulation-interfaces`` wheel, so unless that environment imports
``simulation_interfaces`` already, the test uses the package built by
``tools/ros_interfaces.py`` in ``MARSSCENE_ROS2_INTERFACES`` (its ``--out``) or builds it once per
session (gcc and g++, about a minute)."""

from __future__ import annotations

import json
import logging
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve
from tests.support.session_cache import shared_folder

pytest.importorskip("mujoco")
ROS_PYTHON = os.environ.get("MARSSCENE_ROS2_PYTHON", "")
pytestmark = pytest.mark.skipif(not ROS_PYTHON, reason="MARSSCENE_ROS2_PYTHON is not set")

SUPPORT = Path(__file__).resolve().parents[1] / "support"
BUILDER = Path(__file__).resolve().parents[2] / "tools" / "ros_interfaces.py"
DOMAIN = 218


def _ros_env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CYCLONEDDS_URI")}
    return {**env, **extra}


@pytest.fixture(scope="module")
def interfaces_env(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """What the client's environment needs to import ``simulation_interfaces``."""
    probe = [ROS_PYTHON, "-c", "import simulation_interfaces.srv"]
    if subprocess.run(probe, env=_ros_env(), capture_output=True).returncode == 0:
        return {}  # installed in the ROS environment
    out = os.environ.get("MARSSCENE_ROS2_INTERFACES", "")
    if not out:
        if not (shutil.which("gcc") and shutil.which("g++")):
            pytest.skip("no simulation_interfaces for rclpy, and no gcc/g++ to build it")
        def build(folder: Path) -> None:
            done = subprocess.run([sys.executable, str(BUILDER), "--ros-python", ROS_PYTHON,
                                   "--out", str(folder)], capture_output=True, text=True)
            assert done.returncode == 0, done.stdout + done.stderr

        out = str(shared_folder(tmp_path_factory, "ros-interfaces", ROS_PYTHON, build))
    extra = {"PYTHONPATH": out, "LD_LIBRARY_PATH": os.pathsep.join(
        p for p in (str(Path(out) / "lib"), os.environ.get("LD_LIBRARY_PATH", "")) if p)}
    done = subprocess.run(probe, env=_ros_env(**extra), capture_output=True, text=True)
    assert done.returncode == 0, f"{out}: {done.stderr}"
    return extra


def test_a_fast_dds_call_times_out_and_the_log_says_why(gentle_scene: Path, caplog,
                                                        interfaces_env: dict) -> None:
    from marsscene.ros2 import services

    services._said_other[0] = False
    env = _ros_env(**interfaces_env)
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
