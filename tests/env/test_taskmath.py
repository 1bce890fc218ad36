"""The task's arithmetic on batches (marsscene.env.taskmath) against the one-rover code it
replaced: the stuck clock against a deque of timed positions, the scan sampler against
Heightfield.sample, the batched wheel kinematics against the scalar ones; and, where PyTorch is
installed, PyTorch against numpy."""

from __future__ import annotations

import math
from collections import deque
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene._xp import namespace
from marsscene.env import taskmath
from marsscene.env.observe import HeightScan
from marsscene.env.reward import RewardConfig
from marsscene.env.task import NavTask
from marsscene.env.terms import TERMINATIONS, Quantities, reward_terms
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import body_twist_from_wheels, body_twists_from_wheels, wheel_commands
from marsscene.terrain.heightfield import Heightfield


def _deque_stuck(moves: list[bool], xys: np.ndarray, window_s: float, hz: float,
                 min_m: float) -> list[bool]:
    """The stuck rule as the CPU environment judged it before (a deque of (t, x, y))."""
    track: deque[tuple[float, float, float]] = deque()
    out = []
    for k, (moving, xy) in enumerate(zip(moves, xys, strict=True)):
        t = (k + 1) / hz
        if not moving:
            track.clear()
            out.append(False)
            continue
        track.append((t, xy[0], xy[1]))
        while t - track[0][0] > window_s + 1e-9:
            track.popleft()
        t0, x0, y0 = track[0]
        out.append(t - t0 >= window_s - 1e-9 and math.hypot(xy[0] - x0, xy[1] - y0) < min_m)
    return out


@settings(max_examples=60, deadline=None)
@given(moves=st.lists(st.booleans(), min_size=1, max_size=60),
       window=st.integers(1, 12), seed=st.integers(0, 2**31))
def test_stuck_clock_is_the_deque_rule(moves: list[bool], window: int, seed: int) -> None:
    hz = 5.0
    rng = np.random.default_rng(seed)
    xys = np.cumsum(rng.normal(0.0, 0.03, (len(moves), 2)), axis=0)
    want = _deque_stuck(moves, xys, window / hz, hz, 0.2)
    clock = taskmath.StuckClock(np.zeros(1), (), window, 0.2)
    got = [bool(clock(xy, np.asarray(m))) for m, xy in zip(moves, xys, strict=True)]
    assert got == want


def test_scan_heights_is_heightfield_sample() -> None:
    rng = np.random.default_rng(3)
    hf = Heightfield(rng.normal(0, 1, (40, 57)).astype(np.float32), 0.25, (-3.0, 2.0))
    x = rng.uniform(-6.0, 15.0, 500)  # inside and outside (clamped) the footprint
    y = rng.uniform(-1.0, 15.0, 500)
    got = taskmath.scan_heights(hf.z_m, np.asarray(hf.origin_xy_m), hf.cell_size_m, x, y)
    np.testing.assert_array_equal(got, hf.sample(x, y))
    stack = np.stack([hf.z_m, hf.z_m[::-1] * 2])  # two worlds, points of world 1
    origins = np.array([hf.origin_xy_m, (1.0, -1.0)])
    both = taskmath.scan_heights(stack, origins, 0.25, np.stack([x, x + 4]),
                                 np.stack([y, y - 3]), np.array([0, 1]))
    other = Heightfield(stack[1], 0.25, (1.0, -1.0))
    np.testing.assert_array_equal(both[0], hf.sample(x, y))
    np.testing.assert_array_equal(both[1], other.sample(x + 4, y - 3))


def test_batched_kinematics_are_the_scalar_ones() -> None:
    cfg = RoverConfig()
    rng = np.random.default_rng(5)
    v, w = rng.uniform(-0.5, 0.5, 64), rng.uniform(-0.2, 0.2, 64)
    v[:4], w[:4] = 0.0, (0.0, 0.1, -0.1, 0.0)  # standing, turning in place
    rates, steer = wheel_commands(v, w, cfg)
    for k in range(64):
        r1, s1 = wheel_commands(float(v[k]), float(w[k]), cfg)
        np.testing.assert_array_equal(rates[k], r1)
        np.testing.assert_array_equal(steer[k], s1)
        np.testing.assert_allclose(body_twists_from_wheels(rates[k], steer[k], cfg)[0],
                                   body_twist_from_wheels(r1, s1, cfg), atol=1e-12)
    np.testing.assert_allclose(body_twists_from_wheels(rates, steer, cfg),
                               np.column_stack([v, w]), atol=1e-12)


def test_failures_are_judged_in_order() -> None:
    task = NavTask()
    level = np.array([1.0, 0.0, 0.0, 0.0])
    tilted = np.array([math.cos(0.4), math.sin(0.4), 0.0, 0.0])  # 46 deg roll
    q = np.stack([tilted, level, level, level, level])
    xy = np.array([[0.5, 0.0], [0.5, 0.0], [5.0, 20.0], [5.0, 0.0], [5.0, 0.0]])
    bounds = np.tile([-30.0, -30.0, 30.0, 30.0], (5, 1))
    bounds[1] = (0.0, -30.0, 30.0, 30.0)  # x = 0.5 is 0.5 m from the edge
    start, goal = np.zeros((5, 2)), np.tile([10.0, 0.0], (5, 1))
    stuck = np.array([True, True, True, True, False])
    code = taskmath.failure_code(q, xy, bounds, start, goal, stuck, task)
    assert [TERMINATIONS[c] for c in code] == ["tipped", "left_world", "strayed", "stuck", ""]


def _batch_inputs(n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = rng.normal(0, 1, (n, 4))
    return {"xy": rng.uniform(-20, 20, (n, 2)), "yaw": rng.uniform(-4, 4, n),
            "goal": rng.uniform(-20, 20, (n, 2)), "twist": rng.normal(0, 0.3, (n, 2)),
            "acc": rng.normal([0, 0, 3.7], 0.5, (n, 3)), "gyr": rng.normal(0, 0.1, (n, 3)),
            "act": rng.uniform(-1, 1, (n, 2)), "last": rng.uniform(-1, 1, (n, 2)),
            "q": q / np.linalg.norm(q, axis=1, keepdims=True),
            "grid": rng.normal(0, 1, (3, 30, 30)), "world": rng.integers(0, 3, n)}


def _all_terms(x: dict[str, np.ndarray], xp_asarray: Any) -> dict[str, Any]:
    a = {k: xp_asarray(v) for k, v in x.items()}
    cfg, task = RewardConfig(progress=0.3), NavTask()
    fwd, left = taskmath.scan_grid_m(HeightScan(size_m=3.0, resolution_m=0.5))
    out = {"obs": taskmath.observation_vector(a["xy"], a["yaw"], a["goal"], a["twist"], a["acc"],
                                              a["gyr"], a["last"]),
           "scan": taskmath.height_scan(a["grid"], xp_asarray(np.zeros((3, 2))), 0.5,
                                        a["acc"] * 0.3 + 5, a["yaw"], xp_asarray(fwd),
                                        xp_asarray(left), a["world"])}
    b = taskmath.bearing_rad(a["xy"], a["goal"], a["yaw"])
    d = a["xy"][:, 0] * 0 + 3.0
    xp = namespace(d)
    q = Quantities(xp=xp, zero=d * 0, dist_m=d, bearing_rad=abs(b), reached=d < 5,
                   steps_left=d * 0 + 10, steps_total=750.0, action=a["act"], last_action=a["last"],
                   collided=a["act"][:, 0] > 0, strayed=a["act"][:, 1] > 0,
                   progress_m=a["yaw"] * 0.1)
    out.update(reward_terms(q, cfg))
    out["code"] = taskmath.failure_code(a["q"], a["xy"], xp_asarray(np.tile(
        [-15.0, -15.0, 15.0, 15.0], (len(x["yaw"]), 1))), a["xy"] * 0, a["goal"],
        a["act"][:, 0] > 0.5, task)
    return out


def test_pytorch_gives_numpy_results() -> None:
    torch = pytest.importorskip("torch")
    x = _batch_inputs(200, 11)
    want = _all_terms(x, np.asarray)
    got = _all_terms(x, torch.as_tensor)
    assert set(got) == set(want)
    for key, value in want.items():
        np.testing.assert_allclose(got[key].numpy(), value, rtol=1e-12, atol=1e-6,
                                   err_msg=key)
