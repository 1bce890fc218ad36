"""The thresholds of the traversability map (one dataclass, each limit with its physical reason
and source) and the rover geometry they are measured against.

Tags as ``marsscene/rover/data/soils.toml``: [P] read in the primary source, [S] quoted by
others, [M] a modelling choice stated here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from marsscene._validate import check_range
from marsscene.rover.config import RoverConfig
from marsscene.rover.links import CHASSIS_HALF_M, CHASSIS_Z_M
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["RoverFootprint", "TraversabilityConfig"]


@dataclass(frozen=True, slots=True, kw_only=True)
class TraversabilityConfig:
    """Limits of the hazard mask and the grid's budget (lengths in m, angles in degrees).

    Each term's cost is its value over its limit, clipped to [0, 1]; a cell is a hazard where
    any value reaches its limit (the combined cost is then 1).
    """

    max_slope_deg: float = 30.0
    """Footprint tilt at which a cell is a hazard. Perseverance and Curiosity are rated not to
    overturn below 45 degrees in any direction and their fault protection stops a drive past
    30 degrees of tilt (NASA Mars 2020 mission pages) [S]; GESTALT's tilt term saturates at a
    rover's configured maximum tilt (Goldberg et al. 2002) [P, abstract]."""
    step_limit_wheel_diameters: float = 1.0
    """Height a wheel meets over its own diameter (terrain steps, rocks), in wheel diameters,
    at which it is a hazard: the rocker-bogie drives over obstacles of about one wheel
    diameter (NASA's figure for MSL and Mars 2020, 0.5 m class) [S]; a single wheel pushed by
    its bogie cannot lift its hub over a taller edge [M]."""
    roughness_limit_clearances: float = 0.25
    """RMS residual of the footprint's plane fit, in belly clearances, at which a cell is a
    hazard: with Gaussian residuals, +/- 2 sigma bumps then reach half the clearance under the
    belly and the suspension rocks over them (GESTALT's roughness term: the plane fit's
    residual, Goldberg et al. 2002) [M]."""
    max_slip: float = 0.5
    """Predicted uphill slip at which a cell is a hazard: the rover then covers half the ground
    its wheels turn for, sinkage grows with slip (Ding et al. 2011) and MER/MSL drives are
    stopped by visual-odometry slip checks of this order (Maimone et al. 2007) [M]."""
    cell_m: float | None = None
    """Grid spacing: None picks the terrain's post spacing, or whole multiples of it while the
    grid would exceed ``max_cells``; a value is rounded to a whole number of posts."""
    max_cells: int = 4_000_000
    """The grid's budget in cells (about 0.5 GB of working arrays at 4 M cells)."""

    def __post_init__(self) -> None:
        check_range("traversability.max_slope_deg", self.max_slope_deg, 0.0, 90.0,
                    lo_open=True, hi_open=True)
        check_range("traversability.step_limit_wheel_diameters",
                    self.step_limit_wheel_diameters, 0.0, 10.0, lo_open=True)
        check_range("traversability.roughness_limit_clearances",
                    self.roughness_limit_clearances, 0.0, 10.0, lo_open=True)
        check_range("traversability.max_slip", self.max_slip, 0.0, 1.0, lo_open=True)
        if self.cell_m is not None:
            check_range("traversability.cell_m", self.cell_m, 0.0, 1000.0, lo_open=True)
        check_range("traversability.max_cells", self.max_cells, 1000, 1e9)


@dataclass(frozen=True, slots=True)
class RoverFootprint:
    """The rover's geometry as the map measures it, orientation-free (any heading).

    Attributes
    ----------
    wheel_radius_m, wheel_width_m : float
    footprint_radius_m : float
        The circle through the corner wheels' contact points, ``hypot(max wheelbase,
        track / 2)``: the disc the plane is fitted over (GESTALT's rover-sized patch).
    wheel_inner_m, wheel_outer_m : float
        The ring any wheel can sit on at some heading: from the middle wheels' inner edge
        (``track / 2 - width / 2``) to the corner wheels' outer edge.
    belly_radius_m : float
        The chassis box's half diagonal: the disc the belly covers at some heading.
    belly_clearance_m : float
        The chassis box's underside above the wheels' ground plane on level ground.
    weight_n : float
        The rover's weight on Mars.
    friction : float
        Wheel--ground Coulomb friction on rigid ground.
    """

    wheel_radius_m: float
    wheel_width_m: float
    footprint_radius_m: float
    wheel_inner_m: float
    wheel_outer_m: float
    belly_radius_m: float
    belly_clearance_m: float
    weight_n: float
    friction: float

    @classmethod
    def of(cls, rover: RoverConfig | None = None) -> RoverFootprint:
        """The footprint of ``rover`` (default: the Perseverance-class :class:`RoverConfig`)."""
        r = rover if rover is not None else RoverConfig()
        reach = max(r.wheelbase_front_m, r.wheelbase_rear_m)
        corner = math.hypot(reach, r.track_m / 2)
        return cls(
            wheel_radius_m=r.wheel_radius_m, wheel_width_m=r.wheel_width_m,
            footprint_radius_m=corner,
            wheel_inner_m=r.track_m / 2 - r.wheel_width_m / 2,
            wheel_outer_m=corner + r.wheel_width_m / 2,
            belly_radius_m=math.hypot(CHASSIS_HALF_M[0], CHASSIS_HALF_M[1]),
            belly_clearance_m=r.ride_height_m + CHASSIS_Z_M - CHASSIS_HALF_M[2],
            weight_n=r.mass_kg * MARS_GRAVITY_M_S2, friction=r.friction)
