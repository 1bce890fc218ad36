"""The declared wheel-odometry covariance against Monte Carlo runs of the simulated noise."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import body_twists_from_wheels, wheel_commands
from marsscene.rover.odometry_covariance import pose_covariance, twist_covariance
from marsscene.sensors.odometry import measure_wheels

ROVER = RoverConfig()
NOISE = NoiseConfig(profile="ln200s")


@pytest.mark.parametrize("v, omega", [(0.3, 0.0), (0.3, 0.08), (0.0, 0.1), (0.5, -0.2)])
def test_twist_covariance_matches_monte_carlo(v, omega):
    rates, steer = wheel_commands(v, omega, ROVER)
    n = 20000
    meas_r, meas_s = measure_wheels(np.tile(rates, (n, 1)), np.tile(steer, (n, 1)), NOISE,
                                    rng=np.random.default_rng(3))
    twists = body_twists_from_wheels(meas_r, meas_s, ROVER)
    empirical = np.cov(twists.T)
    (declared,) = twist_covariance(rates[None], steer[None], NOISE, ROVER)
    # a sample variance of 20,000 draws is within ~3 % (2 sigma); the linearisation in the
    # steering noise (0.5 deg) adds well under 1 %
    np.testing.assert_allclose(np.diag(declared), np.diag(empirical), rtol=0.05)
    corr = empirical[0, 1] / np.sqrt(empirical[0, 0] * empirical[1, 1])
    assert declared[0, 1] / np.sqrt(declared[0, 0] * declared[1, 1]) == pytest.approx(
        corr, abs=0.03)


def test_noise_free_profile_declares_zero():
    rates, steer = wheel_commands(0.3, 0.05, ROVER)
    cov = twist_covariance(rates[None], steer[None], NoiseConfig(profile="none"), ROVER)
    assert np.all(cov == 0.0)
    t = np.arange(5) * 0.1
    assert np.all(pose_covariance(t, np.full(5, 0.3), np.zeros(5), np.repeat(cov, 5, 0)) == 0)


def _dead_reckon(t, v, w, eta):
    """Integrate noisy (v, omega) (realisations x steps x 2) from the origin, heading 0."""
    dt = np.diff(t)
    vv, ww = v[:-1] + eta[..., 0], w[:-1] + eta[..., 1]
    yaw = np.concatenate([np.zeros((len(eta), 1)), np.cumsum(ww * dt, axis=1)], axis=1)
    x = np.cumsum(vv * dt * np.cos(yaw[:, :-1]), axis=1)
    y = np.cumsum(vv * dt * np.sin(yaw[:, :-1]), axis=1)
    return np.stack([x[:, -1], y[:, -1], yaw[:, -1]], axis=1)


def test_pose_covariance_matches_monte_carlo_dead_reckoning():
    # a 60 s drive at 0.3 m/s turning at 0.05 rad/s, 50 Hz, the ln200s wheel noise
    t = np.arange(0.0, 60.0 + 1e-9, 0.02)
    v, w = np.full(len(t), 0.3), np.full(len(t), 0.05)
    rates, steer = wheel_commands(0.3, 0.05, ROVER)
    c = np.repeat(twist_covariance(rates[None], steer[None], NOISE, ROVER), len(t), axis=0)
    yaw = w * t  # the true heading at each stamp
    declared = pose_covariance(t, v, yaw, c)[-1]
    rng = np.random.default_rng(11)
    eta = rng.multivariate_normal(np.zeros(2), c[0], size=(3000, len(t) - 1))
    end = _dead_reckon(t, v, w, eta)
    empirical = np.cov(end.T)
    np.testing.assert_allclose(np.diag(declared), np.diag(empirical), rtol=0.1)
    np.testing.assert_allclose(declared, empirical, atol=0.1 * np.sqrt(
        np.outer(np.diag(empirical), np.diag(empirical))).max())
    # the heading variance grows linearly, the lateral position variance ~ t^3
    cov = pose_covariance(t, v, yaw, c)
    assert cov[1500, 2, 2] == pytest.approx(cov[3000, 2, 2] / 2, rel=1e-6)
    assert np.all(np.linalg.eigvalsh(cov[1:]) > -1e-15)


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 400), st.floats(-0.5, 0.5), st.floats(-0.3, 0.3), st.integers(0, 2**31))
def test_pose_covariance_is_symmetric_positive_semidefinite(n, v, w, seed):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.005, 0.1, n))
    a = rng.normal(size=(n, 2, 2)) * 1e-3
    c = a @ a.transpose(0, 2, 1)
    cov = pose_covariance(t, np.full(n, v), np.cumsum(np.full(n, w) * 0.02), c)
    assert cov.shape == (n, 3, 3) and np.all(cov[0] == 0)
    np.testing.assert_allclose(cov, cov.transpose(0, 2, 1), atol=1e-18)
    assert np.all(np.linalg.eigvalsh(cov) > -1e-12 * max(1.0, float(np.abs(cov).max())))
