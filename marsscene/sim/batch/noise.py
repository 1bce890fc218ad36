"""The sensor noise of a batch of drives, computed for every drive at once.

Each drive keeps its own generator (``stage_rng(seed, "sensors")``) and draws what a CPU drive
draws, in the CPU drive's order (:mod:`marsscene.sim.session`): the IMU's turn-on biases
(:class:`~marsscene.sensors.imu.ImuNoise`), then per control step the wheel encoders
(:func:`~marsscene.sensors.odometry.measure_wheels`: slip, rate noise, steering noise) and per
IMU sample the IMU (white accelerometer, white gyro, gyro walk, accelerometer walk). A
generator's normals are one stream however many are drawn at a call, so each drive fills a
block of its stream ahead and every step reads the next columns of all the drives' blocks at
once: the same numbers as the CPU drive's draws, in one array operation a step instead of a
few generator calls a drive.

Every drive still running has drawn the same count (all draw at every step until they stop),
so one read position serves the batch; a stopped drive's later columns go unread.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.seeding import stage_rng
from marsscene.sensors.imu import ImuNoise, bias_record

__all__ = ["BatchNoise"]

#: normals a drive draws ahead at a refill (8 KiB a drive)
BLOCK = 1024


class BatchNoise:
    """Wheel-encoder and IMU noise of drives seeded ``seeds`` (one :class:`NoiseConfig`).

    Parameters
    ----------
    noise : NoiseConfig
    imu_hz : float
    seeds : sequence of int
        Each drive's seed (its generator is ``stage_rng(seed, "sensors")``).
    """

    def __init__(self, noise: Any, imu_hz: float, seeds: Any) -> None:
        self.noise = noise
        self.rngs = [stage_rng(int(s), "sensors") for s in seeds]
        imus = [ImuNoise(noise, imu_hz, rng=r) for r in self.rngs]  # the turn-on biases
        one = imus[0]
        self.sigma_a, self.sigma_g = one.accel_sigma_m_s2, one.gyro_sigma_rad_s
        self.step_g, self.step_a = one.gyro_step_rad_s, one.accel_step_m_s2
        self.gyro_turn_on_rad_s = np.array([m.gyro_turn_on_rad_s for m in imus])
        self.accel_turn_on_m_s2 = np.array([m.accel_turn_on_m_s2 for m in imus])
        self.gyro_bias_rad_s = self.gyro_turn_on_rad_s.copy()
        self.accel_bias_m_s2 = self.accel_turn_on_m_s2.copy()
        self._pool = np.zeros((len(self.rngs), 0))
        self._at = 0

    def _take(self, k: int) -> NDArray[np.float64]:
        """The next ``k`` normals of every drive's stream, (N, k)."""
        if self._at + k > self._pool.shape[1]:
            fresh = np.stack([r.standard_normal(max(BLOCK, k)) for r in self.rngs])
            self._pool = np.concatenate([self._pool[:, self._at:], fresh], axis=1)
            self._at = 0
        out = self._pool[:, self._at: self._at + k]
        self._at += k
        return out

    def wheels(self, rates_rad_s: Any, steer_rad: Any) -> tuple[NDArray[np.float64], ...]:
        """Encoder readings of (N, 6) wheel rates and (N, 4) steering angles
        (:func:`~marsscene.sensors.odometry.measure_wheels` per row, the same arithmetic)."""
        rates = np.asarray(rates_rad_s, dtype=np.float64)
        steer = np.asarray(steer_rad, dtype=np.float64)
        n, nw, ns = self.noise, rates.shape[1], steer.shape[1]
        z = self._take(2 * nw + ns)
        slip = n.slip_mean + n.slip_sigma * z[:, :nw]
        meas = rates * (1.0 + slip) + n.wheel_rate_sigma_rad_s * z[:, nw: 2 * nw]
        return meas, steer + n.steer_sigma_rad * z[:, 2 * nw:]

    def imu(self, accel_m_s2: Any, gyro_rad_s: Any,
            sampled: Any) -> tuple[NDArray[np.float64], ...]:
        """One noisy sample of (N, 3) true specific force and rate each, and the (N, 6) bias
        inside it (gyro xyz, accel xyz) (:meth:`ImuNoise.measure` per row); the biases walk
        only where ``sampled`` (N,) is true (a stopped drive's stay as they ended)."""
        acc = np.asarray(accel_m_s2, dtype=np.float64)
        gyr = np.asarray(gyro_rad_s, dtype=np.float64)
        walks = (self.step_g > 0.0) + (self.step_a > 0.0)
        z = self._take(6 + 3 * walks)
        a_white, g_white, col = self.sigma_a * z[:, 0:3], self.sigma_g * z[:, 3:6], 6
        if self.step_g > 0.0:
            walked = self.gyro_bias_rad_s + self.step_g * z[:, col: col + 3]
            self.gyro_bias_rad_s = np.where(sampled[:, None], walked, self.gyro_bias_rad_s)
            col += 3
        if self.step_a > 0.0:
            walked = self.accel_bias_m_s2 + self.step_a * z[:, col: col + 3]
            self.accel_bias_m_s2 = np.where(sampled[:, None], walked, self.accel_bias_m_s2)
        a = acc + self.accel_bias_m_s2 + a_white
        g = gyr + self.gyro_bias_rad_s + g_white
        return a, g, np.hstack([self.gyro_bias_rad_s, self.accel_bias_m_s2])

    def bias_summary(self, i: int) -> dict[str, list[float]]:
        """Drive ``i``'s IMU biases at the start and now (a CPU drive's ``imu_bias``)."""
        return bias_record(self.gyro_turn_on_rad_s[i], self.gyro_bias_rad_s[i],
                           self.accel_turn_on_m_s2[i], self.accel_bias_m_s2[i])
