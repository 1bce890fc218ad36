"""Mars constants used across marsscene (:doc:`/science/dem`)."""

from __future__ import annotations

#: Mars 2000 / IAU sphere radius used by HiRISE, ISIS and USGS map products (in m).
MARS_RADIUS_M = 3_396_190.0
#: Surface gravity exported to USD and MJCF (in m s^-2). GM/R_mean^2 = 3.7278; equatorial 3.71.
MARS_GRAVITY_M_S2 = 3.72
#: Length of a mean solar day, a sol (in s).
SOL_S = 88_775.24415
