"""The one judgement of a navigation step (marsscene.env.judgement) and the one goal test
(marsscene.sim.goal): every judge of arrival calls the same function with the same tolerance;
judge_step's codes, truncation and reward sum on synthetic batches; a reward term added to the
table is one function and one entry."""

from __future__ import annotations

import dataclasses
import importlib.util
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.env import judgement, terminate, terms
from marsscene.env.reward import RewardConfig, compute_reward
from marsscene.env.state import RoverState
from marsscene.env.task import NavTask
from marsscene.env.taskmath import StuckClock
from marsscene.rover.config import GOAL_TOLERANCE_M
from marsscene.runs.tum import Trajectory
from marsscene.sim import driver, goal, pursuit
from marsscene.sim.pursuit import STOP_RADIUS_M, PurePursuit, PursuitConfig
from marsscene.sim.route import Route

TASK = NavTask()


def _state(xy: np.ndarray, yaw: np.ndarray | None = None) -> RoverState:
    n = len(xy)
    yaw = np.zeros(n) if yaw is None else yaw
    quat = np.column_stack([np.cos(yaw / 2), np.zeros(n), np.zeros(n), np.sin(yaw / 2)])
    xyz = np.column_stack([xy, np.zeros(n)])
    return RoverState(xyz_m=xyz, quat_wxyz=quat, yaw_rad=yaw, pose_xy_m=xy, pose_yaw_rad=yaw,
                      twist=np.zeros((n, 2)), accel_m_s2=np.tile([0.0, 0.0, 3.71], (n, 1)),
                      gyro_rad_s=np.zeros((n, 3)))


def _judge(xy: np.ndarray, goal_xy: np.ndarray, *, steps_left: int = 10,
           reward: RewardConfig | None = None, stuck: bool = False) -> judgement.Judgement:
    n = len(xy)
    clock = StuckClock(np.zeros(1), (n,), 1, 100.0 if stuck else 0.0)
    moving = np.ones(n, bool)
    clock(xy, moving)  # one step of history: stuck where it moved less than min_m
    return judgement.judge_step(
        _state(xy), start_xy_m=np.zeros((n, 2)), goal_xy_m=goal_xy,
        bounds_xy_m=np.tile([-50.0, -50.0, 50.0, 50.0], (n, 1)),
        steps_left=np.full(n, steps_left), action=np.zeros((n, 2)),
        last_action=np.zeros((n, 2)), last_distance_m=np.full(n, 3.0),
        collided=np.zeros(n, bool), moving=moving, stuck_clock=clock, task=TASK,
        reward=reward or RewardConfig(), steps_total=100)


def test_every_judge_of_arrival_is_the_one_goal_test() -> None:
    one = goal.goal_reached
    assert judgement.goal_reached is one and terminate.goal_reached is one
    assert pursuit.goal_reached is one and driver.goal_reached is one  # a drive's summary
    if importlib.util.find_spec("cyclonedds") is not None:
        from marsscene.ros2 import bridge

        assert bridge.goal_reached is one  # the live session's /marsscene/goal_reached
    assert TASK.goal_tolerance_m == GOAL_TOLERANCE_M == goal.GOAL_TOLERANCE_M
    # the pursuit's stopping radius is its own, named fact, inside the goal tolerance
    assert PursuitConfig().goal_tolerance_m == STOP_RADIUS_M < GOAL_TOLERANCE_M


@settings(max_examples=80, deadline=None)
@given(d=st.floats(0.0, 1.0), angle=st.floats(-math.pi, math.pi),
       gx=st.floats(-20.0, 20.0), gy=st.floats(-20.0, 20.0))
def test_env_batch_and_pursuit_agree_with_the_goal_test(d: float, angle: float, gx: float,
                                                        gy: float) -> None:
    goal_xy = np.array([[gx, gy]])
    xy = goal_xy + d * np.array([[math.cos(angle), math.sin(angle)]])
    ag, dg = xy.astype(np.float32), goal_xy.astype(np.float32)  # as info holds them
    reached = bool(goal.goal_reached(ag, dg)[0])
    assert reached == (float(np.linalg.norm(ag[0].astype(float) - dg[0])) < 0.5)
    j = _judge(xy, goal_xy)  # the step's judgement (CPU env: N = 1; batch: N)
    assert (int(j.code[0]) == terms.GOAL) == reached == bool(j.terminated[0])
    info = {"termination": "", "steps_left": 10}
    assert terminate.compute_terminated(ag[0], dg[0], info, tolerance_m=0.5) is reached
    # the pursuit stops where the goal test with its stopping radius says so
    route = Route(np.array([[gx - 0.2, gy], [gx, gy]]))
    follower = PurePursuit(route)
    follower.command(float(xy[0, 0]), float(xy[0, 1]), 0.0)
    assert follower.done == bool(goal.goal_reached(xy[0], goal_xy[0], STOP_RADIUS_M))


@pytest.mark.parametrize(("off_m", "reached"), [(0.1, True), (0.45, True), (0.55, False)])
def test_a_drive_summary_says_goal_reached_by_the_goal_test(off_m: float, reached: bool) -> None:
    """A drive along a route reports ``goal_reached`` when it ended within the goal tolerance
    of the route's end, whatever its controller says (a pursuit stops at 0.25 m, a user's
    controller anywhere); without a route, its controller's ``done``."""
    route = Route(np.array([[0.0, 0.0], [10.0, 0.0]]))
    gt = Trajectory(np.array([0.0, 1.0]), np.array([[0.0, 0.0, 0.0], [10.0 - off_m, 0.0, 0.0]]),
                    np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)))

    class Stopped:
        done = False

    assert driver._goal_reached(gt, Stopped(), route) is reached
    assert driver._goal_reached(gt, Stopped(), None) is False
    assert driver._goal_reached(gt, object(), None) is None


def test_codes_truncation_and_reward_sum() -> None:
    goal_xy = np.tile([10.0, 0.0], (4, 1))
    xy = np.array([[10.2, 0.0], [3.0, 0.0], [3.0, 11.5], [3.0, 0.0]])
    j = _judge(xy, goal_xy, steps_left=0)
    names = [terms.TERMINATIONS[c] for c in j.code]
    assert names == ["goal", "", "strayed", ""]
    assert list(j.terminated) == [True, False, True, False]
    assert list(j.truncated) == [False, True, False, True]  # the time limit: the time-out flag
    stuck = _judge(xy, goal_xy, stuck=True)  # the goal wins over a failure judged at it
    assert [terms.TERMINATIONS[c] for c in stuck.code] == ["goal", "stuck", "strayed", "stuck"]
    np.testing.assert_array_equal(j.reward, sum(j.terms.values()))
    assert list(j.terms) == [t.name for t in terms.DENSE_TERMS if not t.optional]
    assert j.terms["stray"][2] == RewardConfig().stray and j.terms["stray"][0] == 0
    assert stuck.terms["goal"][0] > 0 and (stuck.terms["goal"][1:] == 0).all()
    assert (j.terms["goal"] == 0).all()  # no time left: no bonus
    sparse = _judge(xy, goal_xy, reward=RewardConfig(kind="sparse"))
    assert list(sparse.terms) == ["goal"] and list(sparse.reward) == [0.0, -1.0, -1.0, -1.0]


def test_relabelled_reward_is_the_steps_own() -> None:
    goal_xy = np.array([[10.0, 0.0], [-4.0, 7.0]])
    xy = np.array([[10.3, 0.1], [1.0, 2.0]])
    cfg = RewardConfig(progress=0.5)
    j = _judge(xy, goal_xy, reward=cfg)
    other = sum(v for k, v in j.terms.items() if k not in terms.GOAL_TERMS)
    info = {"yaw_rad": np.zeros(2), "steps_left": np.full(2, 10), "reward_other": other}
    again = compute_reward(xy.astype(np.float32), goal_xy.astype(np.float32), info, cfg=cfg,
                           tolerance_m=TASK.goal_tolerance_m, steps_total=100)
    np.testing.assert_allclose(again, j.reward, rtol=1e-6)


def test_a_reward_term_is_one_function_and_one_table_entry(monkeypatch) -> None:
    assert {f.name for f in dataclasses.fields(RewardConfig)} - {"kind"} == set(terms.WEIGHTS)
    assert all(getattr(RewardConfig(), k) == w for k, w in terms.WEIGHTS.items())

    def speed(q: terms.Quantities, w: float) -> np.ndarray:
        return w * q.action[..., 0]

    table = (*terms.DENSE_TERMS, terms.RewardTerm("speed", speed, 0.25, goal=False))
    monkeypatch.setattr(terms, "DENSE_TERMS", table)
    xy = np.array([[3.0, 0.0]])
    j = _judge(xy, np.array([[10.0, 0.0]]))
    assert list(j.terms)[-1] == "speed" and j.terms["speed"][0] == 0.0  # action 0
    base = sum(v for k, v in j.terms.items() if k != "speed")
    np.testing.assert_array_equal(j.reward, base + j.terms["speed"])


@pytest.mark.parametrize("xy", [[0.0, 0.0], [1.0, 2.0]])
def test_goal_distance_is_numpys_norm(xy: list[float]) -> None:
    g = np.array([0.3, -0.4])
    assert goal.goal_distance_m(xy, g) == np.linalg.norm(np.asarray(xy) - g)
    assert goal.goal_reached([0.0, 0.0], [0.0, 0.5]) is np.False_  # strictly inside
