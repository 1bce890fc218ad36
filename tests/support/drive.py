"""One control period of ``cmd_vel`` on a :class:`~marsscene.sim.rover_sim.RoverSim`, through
the public calls a drive session makes (``apply`` then ``advance``)."""

from __future__ import annotations

from typing import Any


def step(sim: Any, v_m_s: float, omega_rad_s: float) -> None:
    """Apply ``cmd_vel`` (m/s, rad/s) and advance one control period (``sim.substeps``)."""
    sim.apply(v_m_s, omega_rad_s)
    sim.advance(sim.substeps)
