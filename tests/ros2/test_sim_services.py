"""``simulation_interfaces`` on a served session, called by the independent client
(``tests/support/sim_client.py``: rmw_cyclonedds's request/reply form, written from its wire
layout and the interface's definitions, nothing from marsscene) on loopback; and the
``SimulateSteps`` action's goal book-keeping on a stand-in host, without DDS."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import threading
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

import marsscene as ms
from marsscene.ros2 import Ros2Options, serve
from marsscene.ros2.sim_action import PAUSED, SimulateStepsAction, StepRun
from marsscene.ros2.sim_control import FEATURES
from marsscene.ros2.sim_types import register

pytest.importorskip("mujoco")

CLIENT = Path(__file__).resolve().parents[1] / "support" / "sim_client.py"
DOMAIN, DT_S = 217, 1.0 / 50.0  # RunConfig's control rate
LONG_GOAL = 100_000  # the client's goal that it cancels
# GoalStatus codes; CancelGoal return codes; Result codes
EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = 2, 3, 4, 5, 6
ERROR_NONE, ERROR_UNKNOWN_GOAL_ID, ERROR_GOAL_TERMINATED = 0, 2, 3
RESULT_OK, RESULT_OPERATION_FAILED = 1, 4


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


@pytest.fixture(scope="module")
def slope_run(slope_scene: Path) -> tuple[dict, ms.DriveRun]:
    return _session(slope_scene, DOMAIN + 2)


def _teleported(got: dict) -> None:
    """base_link where SetEntityState asked, heading as asked; within 2 cm after 1 s at rest."""
    x, y, yaw = got["asked_xy_yaw"]
    x1, y1, yaw1 = got["got_xy_yaw"]
    assert math.hypot(x1 - x, y1 - y) < 1e-3 and yaw1 == pytest.approx(yaw, abs=1e-3)
    assert got["got_again_xy"] == [x1, y1]  # paused: it stays where it was set
    assert got["settle"] == 1
    x2, y2, yaw2 = got["settled_xy_yaw"]  # settling: the wheels' creep on their brakes
    assert math.hypot(x2 - x, y2 - y) < 0.02 and yaw2 == pytest.approx(yaw, abs=0.01)


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
    assert got["asked_xy_yaw"][:2] == pytest.approx([x0 + 2.0, y0 - 1.0], abs=1e-12)
    _teleported(got)
    x1, y1, _ = got["got_xy_yaw"]
    assert got["missing"] == 2  # RESULT_NOT_FOUND
    assert got["reset"] == 1
    xr, yr = got["reset_xy"]  # base_link back where it started
    assert math.hypot(xr - got["origin_xy"][0], yr - got["origin_xy"][1]) < 0.01
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


def test_set_entity_state_on_a_slope_puts_base_link_where_asked(slope_run):
    """On the 15 degree plane the fitted plane's normal leans 0.2 m downhill at base_link's
    ride height: the teleport spawns uphill of the request so base_link lands on it."""
    got, res = slope_run
    assert got["pause"] == 1 and got["set"] == 1
    _teleported(got)
    xr, yr = got["reset_xy"]
    assert math.hypot(xr - got["origin_xy"][0], yr - got["origin_xy"][1]) < 0.01
    assert res.stats["teleports"] == 1


@pytest.mark.parametrize("which", [0, 1])
def test_a_long_goal_is_cancelled_between_steps(runs, which):
    got, _ = runs[which]
    assert got["cancel_accepted"]
    assert got["cancel"] == [ERROR_NONE, [got["cancel_gid"]]]  # goals_canceling: that one
    status, code, text = got["canceled"]
    assert (status, code) == (CANCELED, RESULT_OPERATION_FAILED) and "canceled" in text
    assert got["canceled_again"] == [CANCELED, RESULT_OPERATION_FAILED]  # get_result again
    fb = got["cancel_feedback"]
    k = len(fb)
    assert 5 <= k < LONG_GOAL and fb == [[i, LONG_GOAL - i] for i in range(1, k + 1)]
    assert f"{k} of {LONG_GOAL} steps" in text
    assert got["cancel_clock_s"] == pytest.approx(k * DT_S, abs=1e-9)  # k steps, no more
    assert got["cancel_odom"] == k
    st = got["cancel_statuses"]  # the status topic: executing, canceling, canceled
    assert st[-1] == CANCELED and set(st) <= {EXECUTING, CANCELING, CANCELED} and st == sorted(st)
    assert got["cancel_terminated"] == ERROR_GOAL_TERMINATED
    assert got["cancel_unknown"] == ERROR_UNKNOWN_GOAL_ID
    assert got["cancel_all_idle"] == [ERROR_NONE, 0]  # nothing running: nothing to cancel
    assert got["state_after_cancel"] == PAUSED


class _Part:
    """Stands in for a Participant: writers keep what they are given, readers read nothing."""

    guid = bytes(16)

    def __init__(self) -> None:
        self.written: dict[str, list[bytes]] = {}

    def writer(self, store: Any, topic: str, *_a: Any, **_k: Any) -> Any:
        out = self.written.setdefault(topic, [])
        return SimpleNamespace(write=lambda b: out.append(bytes(b)), subscribers=1)

    def reader(self, *_a: Any, **_k: Any) -> Any:
        return SimpleNamespace(take=lambda: [])


class _Host:
    """The least an :class:`ActionHost` is: a state, the run, results, stamps."""

    def __init__(self, store: Any) -> None:
        self.T, self.state = store.types, PAUSED
        self.run: StepRun | None = None

    def result(self, code: int = RESULT_OK, text: str = "") -> Any:
        return self.T["simulation_interfaces/msg/Result"](result=code, error_message=text)

    def stamp(self) -> Any:
        t = self.T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
        return self.T["std_msgs/msg/Header"](stamp=t, frame_id="map")

    def abort_run(self) -> None:
        run, self.run = self.run, None
        if run is not None:
            run.finish(run)


def test_the_action_aborts_a_goal_the_simulation_leaves_and_keeps_its_status():
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    register(store)
    T, a = store.types, "simulation_interfaces/action/SimulateSteps"
    host, part = _Host(store), _Part()
    act = SimulateStepsAction(host, part, store, "/gz")
    uuid = [T["unique_identifier_msgs/msg/UUID"](uuid=np.full(16, i, np.uint8)) for i in (1, 2)]
    replies: list[Any] = []
    ok = act._send_goal(T[f"{a}_SendGoal_Request"](goal_id=uuid[0], goal=T[f"{a}_Goal"](
        steps=3)), None)
    assert ok.accepted and host.run is not None
    busy = act._send_goal(T[f"{a}_SendGoal_Request"](goal_id=uuid[1], goal=T[f"{a}_Goal"](
        steps=3)), None)
    assert not busy.accepted  # one goal's steps at a time
    assert act._get_result(T[f"{a}_GetResult_Request"](goal_id=uuid[0]), replies.append) is None
    host.run.completed = 1
    host.state = 1  # SetSimulationState(PLAYING) under the goal
    host.abort_run()
    (rep,) = replies
    assert (rep.status, rep.result.result.result) == (ABORTED, RESULT_OPERATION_FAILED)
    assert "1 of 3 steps" in rep.result.result.error_message
    rejected = act._get_result(T[f"{a}_GetResult_Request"](goal_id=uuid[1]), replies.append)
    assert rejected.status == ABORTED and "steps are being taken" in \
        rejected.result.result.error_message
    last = part.written["/gz/simulate_steps/_action/status"][-1]
    arr = store.deserialize_cdr(last, "action_msgs/msg/GoalStatusArray")
    assert [(bytes(s.goal_info.goal_id.uuid), s.status) for s in arr.status_list] == [
        (bytes(uuid[0].uuid), ABORTED)]  # accepted goals only
    cancel = T["action_msgs/srv/CancelGoal_Request"](goal_info=arr.status_list[0].goal_info)
    done = act._cancel_goal(cancel, None)  # an id and a stamp: those before it, none running
    assert (done.return_code, list(done.goals_canceling)) == (ERROR_NONE, [])
