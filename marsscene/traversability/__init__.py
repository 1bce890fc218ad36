"""Ground-truth traversability: what the scene knows exactly (terrain, rock catalogue, soil map)
measured against the rover's geometry, as cost and hazard grids a planner is judged on.

Each cell is evaluated for the rover centred there at any heading (an orientation-free,
conservative configuration-space map), in the terms Mars rover navigation uses:

- **slope**: the tilt of a least-squares plane over the footprint disc (the circle through the
  corner wheels), and **roughness**, the RMS residual of that fit -- GESTALT's tilt and
  roughness over a rover-sized patch (Goldberg, Maimone & Matthies 2002);
- **step**: the largest terrain height range over a wheel's diameter anywhere a wheel can
  stand (GESTALT's step hazard, against what a wheel can climb);
- **rock**: the tallest catalogue rock where a wheel can stand, against the same limit;
- **belly**: how far terrain and rocks rise under the chassis above the plane fitted where the
  wheels stand, against the belly clearance -- Mars 2020 ENav's approximate clearance
  evaluation (Otsu et al. 2020; Toupet et al. 2020) without its heading;
- **slip**: the steady uphill slip on the cell's soil at that slope, from the Wong--Reece model
  the simulated wheels use (:mod:`marsscene.traversability.slip`).

Each term's cost is its value over its limit (:class:`TraversabilityConfig`, every limit with
its physical reason); the combined cost is the largest, in [0, 1] (GESTALT's goodness is the
least of its terms' goodness), and the hazard mask marks cells where any term reaches its
limit or the wheels leave the terrain. :func:`compute` returns a :class:`Traversability` of
NumPy grids; :mod:`marsscene.traversability.scene` reads a built scene folder and writes
``traversability/`` (GeoTIFF, PNG preview, JSON summary).

References: Goldberg, S. B., Maimone, M. W., Matthies, L. (2002), Stereo vision and rover
navigation software for planetary exploration, IEEE Aerospace Conference Proceedings (Big Sky,
Montana), vol. 5, 2025-2036, doi:10.1109/AERO.2002.1035370; Otsu, K., Matheron, G., Ghosh, S.,
Toupet, O., Ono, M. (2020), Fast approximate clearance evaluation for rovers with articulated
suspension systems, J. Field Robotics 37(5), 768-785, arXiv:1808.00031; Toupet, O. et al.
(2020), A ROS-based simulator for testing the Enhanced Autonomous Navigation of the Mars 2020
rover, IEEE Aerospace Conference; Maimone, M., Cheng, Y., Matthies, L. (2007), Two years of
visual odometry on the Mars Exploration Rovers, J. Field Robotics 24(3), 169-186; Ding et al.
(2011), J. Terramechanics 48(1), 27-45 (slip sinkage).
"""

from marsscene.traversability.compute import HAZARD_BITS, LAYERS, Traversability, compute
from marsscene.traversability.config import RoverFootprint, TraversabilityConfig

__all__ = ["HAZARD_BITS", "LAYERS", "RoverFootprint", "Traversability", "TraversabilityConfig",
           "compute"]
