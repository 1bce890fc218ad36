"""``simulation_interfaces`` on a served session, called by the independent client
(``tests/support/sim_client.py``: rmw_cyclonedds's request/reply form, written from its wire
layout and the interface's definitions, nothing from marsscene) on loopback."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve
from marsscene.ros2.sim_control import FEATURES

pytest.importorskip("mujoco")

CLIENT = Path(__file__).resolve().parents[1] / "support" / "sim_client.py"
DOMAIN, DT_S = 217, 1.0 / 50.0  # RunConfig's control rate


def _session(scene: Path, domain: int, namespace: str = "/") -> tuple[dict, ms.DriveRun]:
    ns = [] if namespace == "/" else ["--namespace", namespace]
    peer = subprocess.Popen([sys.executable, str(CLIENT), str(domain), *ns],
                            stdout=subprocess.PIPE, text=True)
    timers: list[threading.Timer] = []

    def watchdog(bridge: Any) -> None:  # a client that fails must not hold the session
        timers.append(threading.Timer(60.0, lambda: setattr(bridge, "done", True)))
        timers[0].start()

    try:
        res = serve(scene, ros=Ros2Options(domain_id=domain, localhost=True, pace="lockstep",
                                           sim_namespace=namespace),
                    config=ms.RunConfig(lidar=ms.LidarConfig(model="simple")), seconds=60.0,
                    seed=3, ready=watchdog)
        out, _ = peer.communicate(timeout=60)
    finally:
        peer.kill()
        for t in timers:
            t.cancel()
    return json.loads(out), res


@pytest.fixture(scope="module")
def runs(gentle_scene: Path) -> list[tuple[dict, ms.DriveRun]]:
    return [_session(gentle_scene, DOMAIN), _session(gentle_scene, DOMAIN + 1, "/gzserver")]


def test_every_service_and_the_action_answer_as_the_interface_says(runs):
    got, res = runs[0]
    assert got["features"] == sorted(FEATURES)
    assert got["pause"] == 1 and got["state"] == 2  # RESULT_OK; STATE_PAUSED
    t0, t1 = got["paused_clock_s"]
    assert t0 == t1 and got["paused_odom"] == 0  # paused: the clock stands still
    assert got["step50"] == 1
    assert got["step50_odom"] == 50  # one odometry message a step
    assert got["step50_clock_s"] == pytest.approx(50 * DT_S, abs=1e-9)
    assert got["set"] == 1
    x0, y0 = got["start_xy"]
    x1, y1, yaw = got["got_xy_yaw"]
    # set on the ground: base_link rides along the fitted plane's normal, so x, y move by
    # up to its height times the tilt; the heading is the request's
    assert math.hypot(x1 - x0 - 2.0, y1 - y0 + 1.0) < 0.6 and yaw == pytest.approx(0.8, abs=0.05)
    assert got["got_again_xy"] == [x1, y1]  # paused: it stays where it was set
    assert got["missing"] == 2  # RESULT_NOT_FOUND
    assert got["reset"] == 1
    xr, yr = got["reset_xy"]
    assert math.hypot(xr - got["origin_xy"][0], yr - got["origin_xy"][1]) < 0.6
    assert math.hypot(xr - x1, yr - y1) > 1.5  # back from the teleport's pose
    assert got["entities"] == ["rover"] and got["info"] == 1  # CATEGORY_ROBOT
    assert got["not_supported"] == [0, 0, 0]  # RESULT_FEATURE_UNSUPPORTED
    assert got["action"] == [True, 4, 1]  # accepted, STATUS_SUCCEEDED, RESULT_OK
    assert got["feedback"] == list(range(1, 11))
    assert got["action_clock_s"] == pytest.approx(10 * DT_S, abs=1e-9)
    assert res.stats["resets"] == 1 and res.stats["teleports"] == 1


def test_the_same_calls_give_the_same_bytes_under_gazebos_namespace(runs):
    (a, _), (b, _) = runs
    assert b["features"] == a["features"]  # every call answered under /gzserver
    assert a["counts"] == b["counts"] and a["counts"]["lidar"] >= 6
    assert a["sha256"] == b["sha256"]  # odometry and LiDAR byte for byte
