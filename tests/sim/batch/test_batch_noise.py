"""The batch's noise (``BatchNoise``: every drive's wheel-encoder and IMU noise at once) is the
CPU drive's, number for number: each drive's own generator, the same draws in the same order,
and a drive that stops keeps the biases it stopped with."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.rover.config import NoiseConfig
from marsscene.seeding import stage_rng
from marsscene.sensors.imu import ImuNoise
from marsscene.sensors.odometry import measure_wheels
from marsscene.sim.batch.noise import BLOCK, BatchNoise

SEEDS = (1, 2, 7)
TICKS = 3 * BLOCK // 40  # several refills of the drawn-ahead block
STOP = {2: 41}  # drive 2 logs its last control row at tick 41, then stops


def _schedule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(ticks, N) control and IMU masks: control every 2nd tick, IMU every tick."""
    control = np.zeros((TICKS, n), bool)
    control[::2] = True
    sense = np.ones((TICKS, n), bool)
    for i, k in STOP.items():
        control[k + 1:, i] = False
        sense[k:, i] = False  # the stop tick logs control, no sensor
    return control, sense


@pytest.mark.parametrize("profile", ["ln200s", "none", "adis16495"])
def test_batch_noise_is_each_drives_cpu_noise(profile: str) -> None:
    noise = NoiseConfig(profile=profile)
    rng = np.random.default_rng(0)
    n = len(SEEDS)
    truth = rng.normal(size=(TICKS, n, 16))  # wheel rates 6, steering 4, accel 3, gyro 3
    control, sense = _schedule(n)
    batch = BatchNoise(noise, 100.0, SEEDS)
    got: list[list[np.ndarray]] = [[] for _ in SEEDS]
    for k in range(TICKS):
        if control[k].any():
            rates, steer = batch.wheels(truth[k, :, :6], truth[k, :, 6:10])
            for i in np.flatnonzero(control[k]):
                got[i] += [rates[i], steer[i]]
        if sense[k].any():
            a, g, bias = batch.imu(truth[k, :, 10:13], truth[k, :, 13:16], sense[k])
            for i in np.flatnonzero(sense[k]):
                got[i] += [a[i], g[i], bias[i]]
    for i, seed in enumerate(SEEDS):
        r = stage_rng(seed, "sensors")
        imu = ImuNoise(noise, 100.0, rng=r)
        want: list[np.ndarray] = []
        for k in range(TICKS):
            if control[k, i]:
                want += list(measure_wheels(truth[k, i, :6], truth[k, i, 6:10], noise, rng=r))
            if sense[k, i]:
                a, g = imu.measure(truth[k, i, 10:13], truth[k, i, 13:16])
                want += [a, g, np.hstack([imu.gyro_bias_rad_s, imu.accel_bias_m_s2])]
        assert len(got[i]) == len(want)
        assert all(np.array_equal(x, y) for x, y in zip(got[i], want, strict=True))
        end = batch.bias_summary(i)
        assert end["gyro_end_rad_s"] == list(imu.gyro_bias_rad_s)
        assert end["accel_start_m_s2"] == list(imu.accel_turn_on_m_s2)
    if profile == "ln200s":  # the noise is there, and each drive's own
        assert not np.array_equal(got[0][0], got[1][0])
