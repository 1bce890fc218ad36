"""The IMU noise a run declares, in the EuRoC / Kalibr convention, for the exporters that state
it (EuRoC ``imu0/sensor.yaml``, ORB-SLAM3 settings, the bag's IMU covariances)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.runs.runlog import RunLog

__all__ = ["EUROC_IMU_KEYS", "imu_noise_declared", "imu_noise_of", "rate_hz"]

#: EuRoC imu0/sensor.yaml noise keys (Kalibr convention: continuous-time densities).
EUROC_IMU_KEYS = ("gyroscope_noise_density", "gyroscope_random_walk",
                  "accelerometer_noise_density", "accelerometer_random_walk")


def rate_hz(stamps: NDArray[np.float64]) -> float:
    """The median rate of a stream's stamps (0 for fewer than two)."""
    return float(1.0 / np.median(np.diff(stamps))) if len(stamps) > 1 else 0.0


def imu_noise_declared(run: RunLog) -> dict[str, Any]:
    """The simulated IMU noise of a run in the EuRoC/Kalibr convention (from ``run.json``).

    White-noise densities (rad/s/sqrt(Hz), m/s^2/sqrt(Hz)) combine the profile's density with
    any per-sample sigma: ``sqrt(density^2 + sigma^2 / rate)``; random walks are the bias
    random-walk densities (rad/s^2/sqrt(Hz), m/s^3/sqrt(Hz)). Keys: ``profile``, ``rate_hz``
    and :data:`EUROC_IMU_KEYS`. Runs from before noise profiles read as profile ``none``.
    """
    return imu_noise_of(run.meta.get("noise", {}), rate_hz(run.imu[:, 0]))


def imu_noise_of(noise: dict[str, Any], rate: float) -> dict[str, Any]:
    """:func:`imu_noise_declared` of a noise configuration (``run.json``'s ``noise``, or
    ``asdict(NoiseConfig)``) sampled at ``rate`` Hz."""

    def get(key: str) -> float:
        return float(noise.get(key, 0.0))

    def density(nd_key: str, sigma_key: str) -> float:
        per_rate = get(sigma_key) ** 2 / rate if rate > 0 else get(sigma_key) ** 2
        return math.sqrt(get(nd_key) ** 2 + per_rate)

    return {
        "profile": str(noise.get("profile", "none")),
        "rate_hz": rate,
        "gyroscope_noise_density": density("gyro_noise_density_rad_s_rthz", "gyro_sigma_rad_s"),
        "gyroscope_random_walk": get("gyro_bias_walk_rad_s2_rthz"),
        "accelerometer_noise_density": density("accel_noise_density_m_s2_rthz",
                                               "accel_sigma_m_s2"),
        "accelerometer_random_walk": get("accel_bias_walk_m_s3_rthz"),
    }
