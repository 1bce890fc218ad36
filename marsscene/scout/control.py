"""Cascaded waypoint flight control (Grip et al. 2019: an outer position loop commanding an
acceleration, hence a thrust vector, and an inner attitude loop commanding body torques).

Outer loop: ``a = kp (p_ref - p) + kd (v_ref - v)``, the horizontal part clipped to
``tan(max_tilt) g``; thrust vector ``f = m (a + g z)``; the collective is ``f . b_z`` (the
thrust along the current body axis). Inner loop: the geometric attitude error of Lee, Leok &
McClamroch (2010), ``e_R = vee(R_d^T R - R^T R_d) / 2``, torque ``-kR e_R - kw w`` (scaled by
the inertia). The reference moves along each leg at ``speed_m_s`` (a carrot), so the vehicle
tracks a straight line between waypoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.scout.config import ScoutConfig
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["FlightGains", "flight_command"]


@dataclass(frozen=True, kw_only=True)
class FlightGains:
    """Gains of the two loops (natural frequencies in rad/s, damping ratios)."""

    position_hz_rad_s: float = 1.2
    position_zeta: float = 1.0
    attitude_rad_s: float = 12.0
    attitude_zeta: float = 0.9
    max_tilt_deg: float = 20.0


def _vee(m: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([m[2, 1], m[0, 2], m[1, 0]])


def _desired_rotation(z_d: NDArray[np.float64], yaw_rad: float) -> NDArray[np.float64]:
    x_c = np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    y_d = np.cross(z_d, x_c)
    y_d /= np.linalg.norm(y_d)
    return np.column_stack([np.cross(y_d, z_d), y_d, z_d])


def flight_command(cfg: ScoutConfig, gains: FlightGains, p_ref: NDArray[np.float64],
                   v_ref: NDArray[np.float64], yaw_ref_rad: float,
                   state: tuple[NDArray[np.float64], ...]) -> NDArray[np.float64]:
    """(thrust N, roll, pitch, yaw torques N m) for the reference and the state
    ``(p, v, R, w)`` (:meth:`~marsscene.scout.vehicle.ScoutSim.state`)."""
    p, v, rot, w = state
    wn, z = gains.position_hz_rad_s, gains.position_zeta
    a = wn * wn * (p_ref - p) + 2 * z * wn * (v_ref - v)
    a_max = math.tan(math.radians(gains.max_tilt_deg)) * MARS_GRAVITY_M_S2
    h = float(np.hypot(a[0], a[1]))
    if h > a_max:
        a[:2] *= a_max / h
    a[2] = max(a[2], -0.8 * MARS_GRAVITY_M_S2)
    f = cfg.mass_kg * (a + np.array([0.0, 0.0, MARS_GRAVITY_M_S2]))
    thrust = float(f @ rot[:, 2])
    r_d = _desired_rotation(f / np.linalg.norm(f), yaw_ref_rad)
    e_r = 0.5 * _vee(r_d.T @ rot - rot.T @ r_d)
    wa = gains.attitude_rad_s
    inertia = np.asarray(cfg.inertia_kg_m2)
    torque = -inertia * (wa * wa * e_r + 2 * gains.attitude_zeta * wa * w)
    return np.array([max(thrust, 0.0), *torque])
