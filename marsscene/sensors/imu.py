"""IMU measurements with seeded noise (drawn from a ``numpy.random.Generator`` passed in).

The error model per axis is the continuous-time model of IEEE Std 952-1997 (Annex C) as used
by Kalibr and ORB-SLAM3 (Rehder, Nikolic, Schneider, Hinzmann & Siegwart 2016, Extending
kalibr: calibrating the extrinsics of multiple IMUs and of individual axes, ICRA,
doi:10.1109/ICRA.2016.7487628)::

    measured = true + b_fixed + b_on + b_walk(t) + n(t)

* ``n``: white noise of density ``N`` (rad/s/sqrt(Hz), m/s^2/sqrt(Hz)); at a sample rate ``f``
  each sample has ``sigma = N * sqrt(f)``.
* ``b_on``: a constant bias drawn once per run, ``N(0, turn-on sigma)`` (bias repeatability).
* ``b_walk``: a random walk of density ``K``; each step of ``dt = 1/f`` adds
  ``N(0, K * sqrt(dt))``.

Its Allan deviation is ``sqrt(N^2 / tau + K^2 tau / 3)``: slope -1/2 with ``sigma(1 s) = N``,
then slope +1/2 with ``sigma(3 s) = K`` (El-Sheimy, Hou & Niu 2008, Analysis and modeling of
inertial sensors using Allan variance, IEEE Trans. Instrum. Meas. 57(1), 140-149,
doi:10.1109/TIM.2007.908635). Profile numbers and their datasheets:
``marsscene/rover/data/noise_profiles.toml``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene.rover.config import NoiseConfig

__all__ = ["ImuNoise", "allan_deviation", "bias_record", "imu_measure"]


class ImuNoise:
    """The IMU errors of one run: white noise, a per-run turn-on bias and a bias random walk.

    Parameters
    ----------
    noise : NoiseConfig
    rate_hz : float
        IMU sample rate (sets the per-sample sigma and the random-walk step).
    rng : numpy.random.Generator
        Draws the turn-on biases now (only where their sigma is > 0) and every sample's noise
        later, in a fixed order, so a seed reproduces a run. With no turn-on bias and no walk
        the draws are exactly those of :func:`imu_measure` (older runs replay unchanged).

    Examples
    --------
    >>> imu = ImuNoise(NoiseConfig(profile="ln200s"), 100.0, rng=np.random.default_rng(0))
    >>> a, g = imu.measure(np.zeros((1000, 3)), np.zeros((1000, 3)))
    >>> a.shape, bool(np.all(imu.gyro_bias_rad_s != imu.gyro_turn_on_rad_s))
    ((1000, 3), True)
    """

    def __init__(self, noise: NoiseConfig, rate_hz: float, *, rng: np.random.Generator):
        self.noise, self.rate_hz, self.rng = noise, float(rate_hz), rng
        self.gyro_sigma_rad_s, self.accel_sigma_m_s2 = noise.white_sigmas(self.rate_hz)
        root_dt = math.sqrt(1.0 / self.rate_hz)
        self.gyro_step_rad_s = noise.gyro_bias_walk_rad_s2_rthz * root_dt
        self.accel_step_m_s2 = noise.accel_bias_walk_m_s3_rthz * root_dt
        self.gyro_turn_on_rad_s = np.asarray(noise.gyro_bias_rad_s, np.float64) + _draw(
            noise.gyro_turn_on_bias_rad_s, rng)
        self.accel_turn_on_m_s2 = np.asarray(noise.accel_bias_m_s2, np.float64) + _draw(
            noise.accel_turn_on_bias_m_s2, rng)
        self.gyro_bias_rad_s = self.gyro_turn_on_rad_s.copy()
        """Current bias (turn-on + walk so far), rad/s."""
        self.accel_bias_m_s2 = self.accel_turn_on_m_s2.copy()

    def measure(
        self, accel_m_s2: ArrayLike, gyro_rad_s: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Noisy samples of true specific force and rate, shape (3,) or (n, 3) consecutive
        samples (the bias walks one step per sample, then the sample is read)."""
        acc = np.asarray(accel_m_s2, np.float64)
        gyr = np.asarray(gyro_rad_s, np.float64)
        shape = (acc.size // 3, 3)
        rng = self.rng
        a_white = self.accel_sigma_m_s2 * rng.standard_normal(shape)
        g_white = self.gyro_sigma_rad_s * rng.standard_normal(shape)
        g_bias = self._walk("gyro_bias_rad_s", self.gyro_step_rad_s, shape)
        a_bias = self._walk("accel_bias_m_s2", self.accel_step_m_s2, shape)
        a = acc + a_bias.reshape(acc.shape) + a_white.reshape(acc.shape)  # imu_measure's order
        g = gyr + g_bias.reshape(gyr.shape) + g_white.reshape(gyr.shape)
        return a, g

    def _walk(self, attr: str, step: float, shape: tuple[int, int]) -> NDArray[np.float64]:
        bias: NDArray[np.float64] = getattr(self, attr)
        if step <= 0.0:
            return np.broadcast_to(bias, shape)
        path = bias + np.cumsum(step * self.rng.standard_normal(shape), axis=0)
        setattr(self, attr, path[-1].copy())
        return path


def bias_record(gyro_start_rad_s: ArrayLike, gyro_end_rad_s: ArrayLike,
                accel_start_m_s2: ArrayLike, accel_end_m_s2: ArrayLike) -> dict[str, list[float]]:
    """A run's IMU biases as its summary holds them: turn-on (constant part) and at the end
    (after the random walk)."""
    return {k: [float(x) for x in np.asarray(v)] for k, v in (
        ("gyro_start_rad_s", gyro_start_rad_s), ("gyro_end_rad_s", gyro_end_rad_s),
        ("accel_start_m_s2", accel_start_m_s2), ("accel_end_m_s2", accel_end_m_s2))}


def _draw(sigma: float, rng: np.random.Generator) -> NDArray[np.float64]:
    return sigma * rng.standard_normal(3) if sigma > 0.0 else np.zeros(3)


def imu_measure(
    accel_m_s2: NDArray[np.float64],
    gyro_rad_s: NDArray[np.float64],
    noise: NoiseConfig,
    *,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Stateless noisy sample: true value + fixed bias + N(0, sigma) on each axis.

    Uses ``accel_sigma_m_s2`` / ``gyro_sigma_rad_s`` only (no density, turn-on bias or walk:
    those need the run's state, :class:`ImuNoise`).
    """
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


def allan_deviation(
    samples: ArrayLike, rate_hz: float, taus_s: ArrayLike
) -> NDArray[np.float64]:
    """Overlapping Allan deviation of a rate signal (IEEE Std 952-1997, Annex C).

    Parameters
    ----------
    samples : array of shape (n,) or (n, k)
        Rate samples (e.g. rad/s) at ``rate_hz``; columns are independent series.
    rate_hz : float
    taus_s : array of shape (m,)
        Cluster times; each is rounded to a whole number of samples ``c`` with
        ``1 <= c < n / 2``.

    Returns
    -------
    ndarray of shape (m,) or (m, k)
        ``sqrt(sum (theta[i+2c] - 2 theta[i+c] + theta[i])^2 / (2 tau^2 (n + 1 - 2c)))``
        with ``theta`` the integrated signal.

    Examples
    --------
    >>> x = np.random.default_rng(1).standard_normal(200_000) * 0.1 * np.sqrt(100.0)
    >>> round(float(allan_deviation(x, 100.0, [1.0])[0]), 2)  # white: sigma(1 s) = density
    0.1
    """
    y = np.asarray(samples, np.float64)
    y = y - y.mean(axis=0)  # an offset does not change the Allan deviation; keeps theta small
    dt = 1.0 / float(rate_hz)
    theta = np.concatenate([np.zeros((1, *y.shape[1:])), np.cumsum(y, axis=0) * dt])
    n = len(theta)
    out = []
    for tau in np.atleast_1d(np.asarray(taus_s, np.float64)):
        c = round(tau * rate_hz)
        if not 1 <= c < (n - 1) / 2:
            raise ValueError(f"tau = {tau!r} s needs 1 <= tau * rate < n / 2 samples")
        d = theta[2 * c:] - 2.0 * theta[c:n - c] + theta[:n - 2 * c]
        t = c * dt
        out.append(np.sqrt(np.sum(d * d, axis=0) / (2.0 * t * t * (n - 2 * c))))
    return np.asarray(out)
