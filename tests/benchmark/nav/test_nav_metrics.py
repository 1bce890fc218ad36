"""SPL (Anderson et al. 2018) on known cases and an episode's scores on made-up drives."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.benchmark.nav.metrics import episode_scores, spl, summarise


def test_spl_known_cases() -> None:
    assert spl([1], [10.0], [10.0]) == 1.0  # the shortest path, arrived
    assert spl([1], [10.0], [20.0]) == 0.5  # twice as long
    assert spl([0], [10.0], [10.0]) == 0.0  # not arrived: nothing, however short
    assert spl([1], [10.0], [8.0]) == 1.0  # shorter than the "shortest" (grid): capped at 1
    assert spl([1, 1, 0, 1], [10.0, 4.0, 5.0, 6.0], [12.5, 4.0, 5.0, 12.0]) == pytest.approx(
        (0.8 + 1.0 + 0.0 + 0.5) / 4)


def _grid() -> PlanGrid:
    hazard = np.zeros((30, 30), bool)
    hazard[10:20, 14:16] = True  # a wall at x = 14..15 m, y = 10..19 m
    return PlanGrid(np.zeros((30, 30), np.float32), hazard, 1.0, (0.0, 0.0))


def _line(a: tuple[float, float], b: tuple[float, float], n: int = 201) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)[:, None]
    xy = np.asarray(a) + t * (np.asarray(b) - np.asarray(a))
    return np.column_stack([xy, np.zeros(n)])


def test_episode_through_a_hazard_arrives() -> None:
    xyz = _line((5.0, 15.0), (25.0, 15.0))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(xyz), 1))
    t = np.linspace(0.0, 40.0, len(xyz))
    s = episode_scores(t, xyz, q, odom_length_m=25.0, goal_xy_m=(25.0, 15.0), shortest_m=26.0,
                       grid=_grid())
    assert s["success"] and s["spl"] == 1.0
    assert s["path_m"] == pytest.approx(20.0)
    assert s["slip"] == pytest.approx(0.2)  # 20 m moved for 25 m of wheel travel
    assert s["hazard_entries"] == 1  # one crossing of the wall
    assert s["hazard_time_s"] == pytest.approx(2.0 * 40.0 / 20.0, abs=0.5)  # ~2 m of 20 m
    assert not s["tip_over"] and not s["stuck"]


def test_stuck_and_tipped() -> None:
    xyz = np.column_stack([np.full(300, 3.0), np.full(300, 3.0), np.zeros(300)])
    tilt = np.radians(50.0)  # rolled 50 degrees about x
    q = np.tile([np.sin(tilt / 2), 0.0, 0.0, np.cos(tilt / 2)], (300, 1))
    t = np.linspace(0.0, 120.0, 300)
    s = episode_scores(t, xyz, q, odom_length_m=0.0, goal_xy_m=(20.0, 3.0), shortest_m=17.0,
                       grid=_grid())
    assert not s["success"] and s["stuck"] and s["tip_over"]
    assert s["max_tilt_deg"] == pytest.approx(50.0, abs=0.01)
    rows = [{**s, "status": "ok"}, {"status": "failed"}]
    summary = summarise(rows)
    assert summary["episodes"] == 2 and summary["failed"] == 1
    assert summary["success"] == 0.0 and summary["stuck"] == 1 and summary["tip_overs"] == 1
