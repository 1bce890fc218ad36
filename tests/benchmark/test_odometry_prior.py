"""The LiDAR baseline's odometry prior takes its travel from the wheels and its rotation from
the gyro, so a tilt change or a skid the planar wheel odometry misses is in the prior."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from marsscene.benchmark.slam.odometry_prior import WheelGyroPrior

MOUNT = np.eye(4)
MOUNT[:3, 3] = (0.4, 0.0, 1.9)  # a mast-top LiDAR, axes as the base's


def _feed(prior: WheelGyroPrior, rate_rad_s: np.ndarray, wheel_yaw_rate: float,
          seconds: float) -> list[np.ndarray | None]:
    """0.5 m/s straight by the wheels (turning at ``wheel_yaw_rate``), the gyro at
    ``rate_rad_s``; control 50 Hz, IMU 100 Hz, a scan every 0.1 s."""
    steps = []
    for k in range(round(seconds * 100) + 1):
        t = k / 100
        prior.imu(t, rate_rad_s)
        if k % 2 == 0:
            yaw = wheel_yaw_rate * t
            q = Rotation.from_euler("z", yaw).as_quat()  # x y z w
            prior.control(t, (0.5 * t, 0.0, 0.0), q[[3, 0, 1, 2]])
        if k % 10 == 0:
            steps.append(prior.step(t))
    return steps


@settings(max_examples=30, deadline=None)
@given(pitch_rate=st.floats(-0.3, 0.3), roll_rate=st.floats(-0.3, 0.3),
       yaw_rate=st.floats(-0.3, 0.3), wheel_yaw_rate=st.floats(-0.3, 0.3))
def test_rotation_from_the_gyro_travel_from_the_wheels(pitch_rate: float, roll_rate: float,
                                                       yaw_rate: float,
                                                       wheel_yaw_rate: float) -> None:
    rate = np.array([roll_rate, pitch_rate, yaw_rate])
    steps = _feed(WheelGyroPrior(MOUNT), rate, wheel_yaw_rate, 1.0)
    assert steps[0] is None  # the first scan has no step
    base_turn = Rotation.from_rotvec(rate * 0.1).as_matrix()  # 10 samples of a constant rate
    for step in steps[1:]:
        assert step is not None
        base = MOUNT @ step @ np.linalg.inv(MOUNT)  # back to the base frame
        np.testing.assert_allclose(base[:3, :3], base_turn, atol=1e-9)
        assert np.linalg.norm(base[:3, 3]) == pytest.approx(0.05, abs=1e-9)  # the wheels' 5 cm
        assert abs(base[2, 3]) < 1e-12  # along the base's own axes


def test_without_the_gyro_the_planar_wheels_turn_it() -> None:
    """``gyro=False`` (or no IMU yet): the step's rotation is the planar odometry's, which
    misses the pitch the rover makes."""
    steps = _feed(WheelGyroPrior(MOUNT, gyro=False), np.array([0.0, 0.2, 0.0]), 0.1, 0.5)
    for step in steps[1:]:
        assert step is not None
        base = MOUNT @ step @ np.linalg.inv(MOUNT)
        np.testing.assert_allclose(base[:3, :3], Rotation.from_euler("z", 0.01).as_matrix(),
                                   atol=1e-12)
    tilted = _feed(WheelGyroPrior(MOUNT), np.array([0.0, 0.2, 0.0]), 0.1, 0.5)[1]
    assert tilted is not None
    pitch_deg = np.degrees(Rotation.from_matrix(tilted[:3, :3]).as_rotvec()[1])
    assert pitch_deg == pytest.approx(np.degrees(0.02), rel=1e-9)
