"""IMU measurements with seeded noise (drawn from a ``numpy.random.Generator`` passed in)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import NoiseConfig

__all__ = ["imu_measure"]


def imu_measure(
    accel_m_s2: NDArray[np.float64],
    gyro_rad_s: NDArray[np.float64],
    noise: NoiseConfig,
    *,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Noisy IMU sample: true value + bias + N(0, sigma) on each axis."""
    a = (
        accel_m_s2
        + np.asarray(noise.accel_bias_m_s2)
        + noise.accel_sigma_m_s2 * rng.standard_normal(3)
    )
    g = (
        gyro_rad_s
        + np.asarray(noise.gyro_bias_rad_s)
        + noise.gyro_sigma_rad_s * rng.standard_normal(3)
    )
    return a, g
