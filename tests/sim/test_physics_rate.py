"""A coarser physics step drives the same route: 100 Hz (10 ms) against the scene's 500 Hz."""

from __future__ import annotations

import numpy as np
import pytest

import marsscene as ms
from marsscene.errors import ConfigError


def test_a_10_ms_physics_step_drives_the_same_route_within_5_cm(gentle_scene):
    wp = [[-12.0, -10.0], [4.0, -10.0], [6.0, 4.0]]
    runs = {hz: ms.drive(gentle_scene, waypoints=wp, config=ms.RunConfig(physics_hz=hz),
                         seed=1) for hz in (None, 100.0)}
    ref, fast = runs[None], runs[100.0]
    assert ref.summary["goal_reached"] and fast.summary["goal_reached"]
    assert ref.summary["path_length_m"] > 25.0
    # compare the two paths at the same times (the 50 Hz control steps of both)
    n = min(len(ref.gt), len(fast.gt))
    gap = np.hypot(*(ref.gt.xyz_m[:n, :2] - fast.gt.xyz_m[:n, :2]).T)
    assert gap.max() < 0.05, gap.max()
    assert abs(ref.summary["cross_track_rms_m"] - fast.summary["cross_track_rms_m"]) < 0.02
    assert abs(ref.summary["sim_time_s"] - fast.summary["sim_time_s"]) < 1.0


def test_rates_must_divide_the_physics_rate():
    with pytest.raises(ConfigError, match=r"divide the 100 Hz physics rate"):
        ms.RunConfig(physics_hz=100.0, imu_hz=30.0)
    with pytest.raises(ConfigError, match=r"lidar\.rate_hz"):
        ms.RunConfig(physics_hz=100.0, lidar=ms.LidarConfig(rate_hz=15.0))
    assert ms.RunConfig(physics_hz=200.0, control_hz=40.0).control_hz == 40.0
