"""The covariance of the rover's wheel odometry implied by its simulated encoder noise.

A ``nav_msgs/Odometry`` message declares how uncertain its twist and pose are; these functions
give what the drive's :class:`~marsscene.rover.config.NoiseConfig` actually simulated
(:func:`marsscene.sensors.odometry.measure_wheels`), to first order:

* **twist** ``(v, omega)``: each wheel rate reads ``rate (1 + slip) + n`` with
  ``slip ~ N(slip_mean, slip_sigma)`` and ``n ~ N(0, wheel_rate_sigma)``, each steering angle
  ``steer + N(0, steer_sigma)``, all independent per sample; the least-squares solve of
  :func:`~marsscene.rover.geometry.body_twists_from_wheels` is linear in the wheel ground
  velocities, so ``Cov(v, omega) = P J Cov(readings) J^T P^T`` with ``J`` the Jacobian of those
  velocities in the readings. ``slip_mean`` is a bias (odometry over-reads distance by that
  fraction): it is in no covariance.
* **pose** ``(x, y, yaw)`` of planar dead reckoning from the start (where it is exact):
  first-order propagation of the independent twist errors through
  ``x += v dt cos(yaw)``, ``y += v dt sin(yaw)``, ``yaw += omega dt``, the standard odometry
  error model (e.g. Thrun, Burgard & Fox 2005, *Probabilistic Robotics*, MIT Press, ch. 5.4;
  Kelly 2004, Linearized error propagation in odometry, Int. J. Robotics Research 23(2),
  179-218, doi:10.1177/0278364904041326). The sums over past steps are written as cumulative
  sums, so a whole run is computed at once.

Neither includes physical slip on slopes and in loose regolith (the contact model's, not a
sensor's): against ground truth the odometry drifts more than these figures on rough ground.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import NoiseConfig, RoverConfig
from marsscene.rover.geometry import _STEERED, _odometry_pinv

__all__ = ["PoseCovarianceStep", "pose_covariance", "twist_covariance"]


def twist_covariance(
    rates_rad_s: NDArray[np.float64], steer_rad: NDArray[np.float64], noise: NoiseConfig,
    rover: RoverConfig,
) -> NDArray[np.float64]:
    """(N, 2, 2) covariance of ``(v, omega)`` solved from (N, 6) wheel rates, (N, 4) steering."""
    rates = np.asarray(rates_rad_s, dtype=np.float64).reshape(-1, 6)
    delta = np.zeros_like(rates)
    delta[:, _STEERED] = np.asarray(steer_rad, dtype=np.float64).reshape(-1, 4)
    pinv = _odometry_pinv(rover)  # (2, 12): (v, omega) from [u cos d, u sin d]
    cos, sin = np.cos(delta), np.sin(delta)
    r = rover.wheel_radius_m
    # d(v, omega) / d(rate_i) and / d(delta_i): (N, 2, 6)
    d_rate = r * (pinv[None, :, :6] * cos[:, None, :] + pinv[None, :, 6:] * sin[:, None, :])
    u = r * rates
    d_delta = u[:, None, :] * (-pinv[None, :, :6] * sin[:, None, :]
                               + pinv[None, :, 6:] * cos[:, None, :])
    var_rate = noise.wheel_rate_sigma_rad_s**2 + (rates * noise.slip_sigma) ** 2  # (N, 6)
    var_delta = np.zeros_like(rates)
    var_delta[:, _STEERED] = noise.steer_sigma_rad**2
    return (np.einsum("nai,ni,nbi->nab", d_rate, var_rate, d_rate)
            + np.einsum("nai,ni,nbi->nab", d_delta, var_delta, d_delta))


def pose_covariance(
    t_s: NDArray[np.float64], v_m_s: NDArray[np.float64], yaw_rad: NDArray[np.float64],
    twist_cov: NDArray[np.float64],
) -> NDArray[np.float64]:
    """(N, 3, 3) covariance of the dead-reckoned ``(x, y, yaw)`` at each stamp, 0 at the first.

    Step ``i`` (from stamp ``i`` to ``i + 1``, duration ``dt_i``) moves by ``v[i + 1] dt_i``
    along ``yaw_i`` with twist error covariance ``twist_cov[i + 1]``: as the drive does it, the
    odometry at stamp ``i + 1`` integrates the wheel reading taken at that stamp. With
    ``S_k = sum_{j<k} dt_j v_{j+1} (-sin yaw_j, cos yaw_j)``, the error after ``k`` steps
    is ``sum_{i<k} G_ki eta_i`` where ``G_ki = [[dt_i u_i, dt_i (S_k - S_{i+1})], [0, dt_i]]``;
    its covariance expands into cumulative sums over ``i``.
    """
    t = np.asarray(t_s, dtype=np.float64)
    v = np.asarray(v_m_s, dtype=np.float64)
    yaw = np.asarray(yaw_rad, dtype=np.float64)
    n = len(t)
    out = np.zeros((n, 3, 3))
    if n < 2:
        return out
    dt = np.diff(t)
    c = np.asarray(twist_cov, dtype=np.float64)[1:n]
    heading = np.stack([np.cos(yaw[:-1]), np.sin(yaw[:-1])], axis=1)
    normal = np.stack([-heading[:, 1], heading[:, 0]], axis=1)
    s = np.vstack([np.zeros(2), np.cumsum((dt * v[1:])[:, None] * normal, axis=0)])  # S_0..S_n-1
    # H_i = G_ki with S_k = 0: columns (dv, domega); rows (x, y, yaw)
    h = np.zeros((n - 1, 3, 2))
    h[:, :2, 0] = dt[:, None] * heading
    h[:, :2, 1] = -dt[:, None] * s[1:]
    h[:, 2, 1] = dt
    m1 = np.cumsum(np.einsum("nai,nij,nbj->nab", h, c, h), axis=0)
    w = np.cumsum(dt[:, None] * np.einsum("nai,ni->na", h, c[:, :, 1]), axis=0)
    m3 = np.cumsum(dt**2 * c[:, 1, 1])
    sk = np.zeros((n - 1, 3))
    sk[:, :2] = s[1:]
    out[1:] = (m1 + np.einsum("na,nb->nab", sk, w) + np.einsum("na,nb->nab", w, sk)
               + m3[:, None, None] * np.einsum("na,nb->nab", sk, sk))
    return out


class PoseCovarianceStep:
    """:func:`pose_covariance` one stamp at a time, for odometry published as it is made.

    ``step(dt_s, v_m_s, yaw_prev_rad, twist_cov)`` integrates the step from the previous stamp
    (heading ``yaw_prev_rad`` there) with the twist ``v_m_s`` and its (2, 2) covariance read at
    the new stamp, and returns the (3, 3) covariance of ``(x, y, yaw)`` there; the same sums as
    the batch function, kept as running totals.
    """

    def __init__(self) -> None:
        self.s = np.zeros(2)
        self.m1 = np.zeros((3, 3))
        self.w = np.zeros(3)
        self.m3 = 0.0

    def step(self, dt_s: float, v_m_s: float, yaw_prev_rad: float,
             twist_cov: NDArray[np.float64]) -> NDArray[np.float64]:
        c = np.asarray(twist_cov, dtype=np.float64)
        heading = np.array([np.cos(yaw_prev_rad), np.sin(yaw_prev_rad)])
        self.s = self.s + dt_s * v_m_s * np.array([-heading[1], heading[0]])
        h = np.zeros((3, 2))
        h[:2, 0] = dt_s * heading
        h[:2, 1] = -dt_s * self.s
        h[2, 1] = dt_s
        self.m1 = self.m1 + h @ c @ h.T
        self.w = self.w + dt_s * (h @ c[:, 1])
        self.m3 += dt_s**2 * float(c[1, 1])
        sk = np.array([self.s[0], self.s[1], 0.0])
        return (self.m1 + np.outer(sk, self.w) + np.outer(self.w, sk)
                + self.m3 * np.outer(sk, sk))
