"""A rover type's derived quantities from its configuration: wheelbase, centre-of-mass height
and static stability angle.

The static stability angle is the tilt at which the centre of mass passes over the line
through the downhill wheels' contact points (rigid suspension, flat ground):
``atan(d / h)`` with ``d`` the horizontal distance from the centre of mass to that line and
``h`` its height above the ground (Papadopoulos & Rey, "A new measure of tipover stability
margin for mobile manipulators", ICRA 1996; the quasi-static limit). The minimum over the four
sides is the rover's; MER rovers were built to stand a 45 deg tilt in any direction (NASA/JPL,
MER launch press kit, 2003), Curiosity-class rovers the same (NASA/JPL, MSL press kit, 2011).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import wheel_positions_xy
from marsscene.rover.links import link_inertia, rover_links

__all__ = ["centre_of_mass_m", "static_stability_deg", "wheelbase_m"]


def wheelbase_m(cfg: RoverConfig) -> float:
    """Front to rear axle (m)."""
    return cfg.wheelbase_front_m + cfg.wheelbase_rear_m


def centre_of_mass_m(cfg: RoverConfig) -> NDArray[np.float64]:
    """The rover's centre of mass (x, y, z) in m, z above flat ground, in the zero pose."""
    origin: dict[str, NDArray[np.float64]] = {}
    total, moment = 0.0, np.zeros(3)
    for link in rover_links(cfg):
        base = origin[link.parent] if link.parent is not None else np.zeros(3)
        origin[link.name] = base + np.asarray(link.pos_m, dtype=np.float64)
        mass, com, _ = link_inertia(link)
        total += mass
        moment += mass * (origin[link.name] + com)
    return np.asarray(moment / total, dtype=np.float64)


def static_stability_deg(cfg: RoverConfig) -> dict[str, float]:
    """Tip-over angles (deg) of the four sides (``front``, ``rear``, ``left``, ``right``) and
    their minimum (``min``)."""
    com = centre_of_mass_m(cfg)
    xy = wheel_positions_xy(cfg)
    d = {"front": xy[:, 0].max() - com[0], "rear": com[0] - xy[:, 0].min(),
         "left": xy[:, 1].max() - com[1], "right": com[1] - xy[:, 1].min()}
    out = {k: math.degrees(math.atan2(float(v), float(com[2]))) for k, v in d.items()}
    out["min"] = min(out.values())
    return out
