"""The bridge's control step without a network: commands and their time-out, reset, teleport
and the goal, decoded from rosbags CDR as they arrive from DDS."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("mujoco")

import marsscene as ms
from marsscene.ros2 import Ros2Options
from marsscene.ros2.bridge import RateLimitedWarning
from marsscene.ros2.live import _bridge
from marsscene.sim.mission import prepare_drive


class Inbox:
    """Stands in for a DDS reader: ``take()`` returns what was put since the last take."""

    topic = "/cmd_vel"

    def __init__(self) -> None:
        self.items: list[bytes] = []

    def take(self, n: int = 64) -> list[bytes]:
        out, self.items = self.items, []
        return out


@pytest.fixture(scope="module")
def bridge(gentle_scene):
    config = ms.RunConfig()
    sim, _ = prepare_drive(gentle_scene, config, options=ms.DriveOptions(start_xy_m=(0.0, 0.0)))
    b = _bridge(sim, config, Ros2Options(domain_id=214, localhost=True, pace="max",
                                         stop_at_goal=True, cmd_timeout_s=0.5))
    b.cmd_reader = Inbox()
    b.cmd_readers = [b.cmd_reader]
    b.control_readers = {t: Inbox() for t in b.control_readers}
    yield b
    b.part.close()


def _obs(t_s: float, xy=(0.0, 0.0)) -> SimpleNamespace:
    return SimpleNamespace(t_s=t_s, gt_xyz_m=np.array([xy[0], xy[1], 0.0]))


def _cdr(b, msg) -> bytes:
    return bytes(b.msgs.b.serialize(msg))


def _pose(b, x: float, y: float, yaw: float):
    t = b.store.types
    return t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                      w=math.cos(yaw / 2)))


def test_commands_apply_until_the_time_out(bridge):
    b = bridge
    assert b(_obs(0.0)) == (0.0, 0.0)
    b.cmd_reader.items.append(_cdr(b, b.msgs.b.twist(0.3, -0.1)))
    assert b(_obs(0.02)) == (0.3, -0.1)
    assert b(_obs(0.50)) == (0.3, -0.1)  # 0.48 s old
    assert b(_obs(0.54)) == (0.0, 0.0)  # 0.52 s old: stopped
    assert b(_obs(0.56)) == (0.0, 0.0) and b.stats.timeouts == 1
    b.cmd_reader.items.append(_cdr(b, b.msgs.b.twist(float("nan"), 0.0)))  # ignored
    assert b(_obs(0.58)) == (0.0, 0.0) and b.stats.commands == 1


def test_bad_commands_are_dropped_with_a_rate_limited_warning(bridge, caplog):
    b = bridge
    b.bad_input = RateLimitedWarning()  # (the module's bridge warned in the test above)
    commands = b.stats.commands
    b.cmd_reader.items.append(_cdr(b, b.msgs.b.twist(0.2, 0.0)))
    assert b(_obs(10.0)) == (0.2, 0.0)
    for k in range(30):  # a flood of NaNs and of bytes that are not a Twist
        b.cmd_reader.items.append(_cdr(b, b.msgs.b.twist(float("nan"), float("inf"))))
        b.cmd_reader.items.append(b"\x00\x01 not cdr")
        assert b(_obs(10.0 + 0.01 * (k + 1))) == (0.2, 0.0)  # the last good command stays
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert len(warned) == 1 and "not finite" in warned[0] and "nan" in warned[0]
    b.bad_input.last -= b.bad_input.period_s  # the period has passed
    b.cmd_reader.items.append(_cdr(b, b.msgs.b.twist(float("nan"), 0.0)))
    b(_obs(10.4))
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert len(warned) == 2 and "59 more" in warned[1]
    assert b.stats.commands == commands + 1


def test_teleport_reset_and_a_refused_pose(bridge, caplog):
    b, sim = bridge, bridge.sim
    sim.advance(50)
    clock = sim.time_s
    b.control_readers["teleport"].items.append(_cdr(b, _pose(b, 5.0, -3.0, 1.0)))
    b(_obs(1.0))
    xyz, _ = sim.pose()
    assert xyz[:2] == pytest.approx((5.0, -3.0), abs=0.02)  # set on the ground's normal
    assert sim.yaw_rad() == pytest.approx(1.0, abs=0.05)
    assert sim.time_s == clock > 0.0  # a teleport does not touch the clock
    b.control_readers["teleport"].items.append(_cdr(b, _pose(b, 500.0, 0.0, 0.0)))
    b(_obs(1.02))
    assert "teleport refused" in caplog.text and sim.pose()[0][0] == pytest.approx(5.0, abs=0.02)
    empty = b.store.types["std_msgs/msg/Empty"]()
    b.control_readers["reset"].items.append(_cdr(b, empty))
    b(_obs(1.04))
    assert sim.pose()[0][:2] == pytest.approx((0.0, 0.0), abs=0.02)
    assert (b.stats.teleports, b.stats.resets) == (1, 1)


def test_goal_reached_ends_the_session(bridge):
    b = bridge
    t = b.store.types
    goal = t["geometry_msgs/msg/PoseStamped"](header=b.msgs.b.header(0.0, "map"),
                                              pose=_pose(b, 10.0, 0.0, 0.0))
    b.control_readers["goal"].items.append(_cdr(b, goal))
    b(_obs(2.0, (0.0, 0.0)))
    assert b.goal_xy == (10.0, 0.0) and not b.done
    b(_obs(2.02, (9.7, 0.1)))
    assert b.done and b.stats.goal_reached_t_s == pytest.approx(2.02)
