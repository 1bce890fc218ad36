"""Rotor thrust and power of a coaxial helicopter from momentum theory (Leishman 2006).

Thrust ``T = C_T rho A (Omega R)^2`` with one system thrust coefficient ``C_T`` fixed by the
published hover (1.8 kg at 2,537 rpm in 0.0175 kg/m^3: ``hover_rpm_ref``, ``density_ref``), so
the top speed 2,900 rpm bounds the thrust (Balaram et al. 2018). Hover power
``P = kappa T^1.5 / sqrt(2 rho A) / (FM eta)``: the ideal induced power of one disk of area ``A``
times the coaxial factor ``kappa``, over the figure of merit and the drive efficiency. At
Ingenuity's mass and 0.0175 kg/m^3 this is 341 W, the ~350 W class of Balaram et al. 2018.
"""

from __future__ import annotations

import math

from marsscene.scout.config import ScoutConfig
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["endurance_s", "hover_power_w", "max_thrust_n", "rotor_power_w", "thrust_coefficient"]


def _tip_speed_m_s(cfg: ScoutConfig, rpm: float) -> float:
    return rpm * 2.0 * math.pi / 60.0 * cfg.rotor_diameter_m / 2.0


def thrust_coefficient(cfg: ScoutConfig) -> float:
    """The system ``C_T`` of the published hover."""
    weight = cfg.mass_kg * MARS_GRAVITY_M_S2
    return weight / (cfg.density_ref_kg_m3 * cfg.disk_area_m2
                     * _tip_speed_m_s(cfg, cfg.hover_rpm_ref) ** 2)


def max_thrust_n(cfg: ScoutConfig, density_kg_m3: float) -> float:
    """Thrust at the top rotor speed ``rpm_max`` (N)."""
    return (thrust_coefficient(cfg) * density_kg_m3 * cfg.disk_area_m2
            * _tip_speed_m_s(cfg, cfg.rpm_max) ** 2)


def rotor_power_w(cfg: ScoutConfig, thrust_n: float, density_kg_m3: float) -> float:
    """Electrical power (W) to make ``thrust_n`` in axial flight at rest (hover)."""
    ideal = max(thrust_n, 0.0) ** 1.5 / math.sqrt(2.0 * density_kg_m3 * cfg.disk_area_m2)
    return (cfg.coaxial_factor * ideal / (cfg.figure_of_merit * cfg.drive_efficiency)
            + cfg.avionics_power_w)


def hover_power_w(cfg: ScoutConfig, density_kg_m3: float) -> float:
    """Hover power (W) at the vehicle's weight on Mars."""
    return rotor_power_w(cfg, cfg.mass_kg * MARS_GRAVITY_M_S2, density_kg_m3)


def endurance_s(cfg: ScoutConfig, density_kg_m3: float) -> float:
    """Energy-limited hover time (s) on the whole battery."""
    return cfg.battery_energy_wh * 3600.0 / hover_power_w(cfg, density_kg_m3)
