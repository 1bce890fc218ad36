"""Lockstep (``pace="lockstep"``): sim time advances only when a command comes, so a slow
subscriber misses no sample and the same commands give the same bytes. The client is the
independent DDS peer (plain cyclonedds + rosbags, nothing from marsscene)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve
from tests.support import DDS_PEER

pytest.importorskip("mujoco")

DOMAIN = 215
STEPS = 30
DT_S = 1.0 / 50.0  # RunConfig's control rate
CONFIG = ms.RunConfig(lidar=ms.LidarConfig(model="simple"))


def _session(scene: Path, sleep_per_scan_s: float) -> tuple[dict, ms.DriveRun]:
    peer = subprocess.Popen([sys.executable, str(DDS_PEER), "lockstep", str(DOMAIN),
                             str(STEPS), str(DT_S), "0.4", "0.1", "--sleep-per-scan",
                             str(sleep_per_scan_s)], stdout=subprocess.PIPE, text=True)
    try:
        res = serve(scene, ros=Ros2Options(domain_id=DOMAIN, localhost=True, pace="lockstep"),
                    config=CONFIG, seconds=STEPS * DT_S, seed=3)
        out, _ = peer.communicate(timeout=60)
    finally:
        peer.kill()
    return json.loads(out), res


@pytest.fixture(scope="module")
def runs(gentle_scene: Path) -> list[tuple[dict, ms.DriveRun]]:
    return [_session(gentle_scene, 0.0), _session(gentle_scene, 0.2)]


def test_a_slow_subscriber_receives_every_scan(runs):
    for got, res in runs:
        sent = res.stats["messages"]
        assert got["counts"]["lidar"] == sent["/rover/lidar/points"] >= 6  # 10 Hz over 0.6 s
        assert got["counts"]["odom"] == sent["/rover/odom"] == STEPS + 1
        assert res.stats["commands"] == STEPS + 1 and res.stats["command_timeouts"] == 0
    slow = runs[1][0]
    assert slow["wall_s"] >= 0.2 * (slow["counts"]["lidar"] - 1)  # it did wait for them


def test_the_same_commands_give_the_same_bytes(runs):
    (fast, _), (slow, _) = runs
    assert fast["sha256"] == slow["sha256"]
    assert fast["counts"] == slow["counts"]
