"""Topographic shading of a procedural scene's orthoimage: the terrain under the orbiter's sun.

A HiRISE image is the surface's albedo times its shading under the sun of the moment the image
was taken, blurred by the camera. Mars Reconnaissance Orbiter flies a sun-synchronous orbit
that crosses the equator on the day side at about 15:00 local mean solar time (Zurek & Smrekar
2007, JGR 112, E05S01, doi:10.1029/2006JE002701), so HiRISE sees the afternoon surface, lit from
the west. The orthoimage model (:mod:`marsscene.orbital.model`) picks one such sun for every
procedural scene, ``image_sun_incidence_deg`` = 48 deg and ``image_sun_azimuth_deg`` = 252 deg
(clockwise from north): Jezero crater's (18.4 N, 77.5 E) sun at 15:00 local true solar time at
the equinox (Ls 0, Mars Year 36), from the Mars24 algorithm of
:func:`marsscene.lighting.sun_position_at_local_time` (47.9 deg, 252.5 deg). Over a Mars year
the same hour gives 42-62 deg of incidence and 226-288 deg of azimuth there; 48 deg is in the
middle of that range. A scene elsewhere, or a given image's sun, is two model parameters away.

The photometric law is **Lambert's** (Lambert 1760, *Photometria*): the reflectance factor is
``I/F = A * mu0``, ``mu0 = max(0, n . s)`` with ``n`` the surface's unit normal and ``s`` the unit
vector towards the sun. It is the simplest photometric function of photoclinometry, the
``L = 0`` case of the Lunar-Lambert function ``2 L mu0 / (mu0 + mu) + (1 - L) mu0`` (McEwen 1991,
Icarus 92, 298-311, doi:10.1016/0019-1035(91)90053-V); it needs no coefficient. The normal is
that of the surface at the image's pixels: the terrain (with the orbiter's resolved rocks raised
in, as in the DTM) sampled bilinearly at the pixel centres, its slope by central differences
(a baseline of two pixels). The product ``albedo * mu0`` is then blurred by the image's PSF.

Not modelled: cast shadows (only the local incidence counts: a facet turned more than
``90 - incidence`` away from the sun is black, a facet in a neighbour's shadow is not),
skylight and atmospheric path radiance (which fill shadows and lower the contrast, more so in
dust), the emission angle (the view is nadir), and limb darkening beyond Lambert's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["SHADING_LAWS", "lambert_mu0", "sun_vector"]

#: The orthoimage's shading laws: ``"lambert"`` (this module) or ``"none"`` (albedo only).
SHADING_LAWS = ("lambert", "none")


def sun_vector(incidence_deg: float, azimuth_deg: float) -> NDArray[np.float64]:
    """Unit vector towards the sun (x east, y north, z up) at ``incidence_deg`` from the
    zenith and ``azimuth_deg`` clockwise from north.

    >>> [round(float(v), 6) for v in sun_vector(90.0, 270.0)]
    [-1.0, -0.0, 0.0]
    """
    i, a = math.radians(incidence_deg), math.radians(azimuth_deg)
    return np.array([math.sin(a) * math.sin(i), math.cos(a) * math.sin(i), math.cos(i)])


def lambert_mu0(z_m: NDArray[np.floating[Any]], cell_m: float, incidence_deg: float,
                azimuth_deg: float) -> NDArray[np.float64]:
    """Cosine of the local incidence, ``max(0, n . s)``, of each post of a south-up grid.

    Parameters
    ----------
    z_m : ndarray of shape (rows, cols)
        Elevation (in m), row 0 = south, row along +y (north), column along +x (east).
    cell_m : float
        Post spacing (in m).
    incidence_deg, azimuth_deg : float
        The sun (:func:`sun_vector`).

    Returns
    -------
    ndarray of shape (rows, cols)
        ``mu0`` in [0, 1]: ``cos(incidence_deg)`` on flat ground.
    """
    dz_dy, dz_dx = np.gradient(np.asarray(z_m, dtype=np.float64), cell_m)
    s = sun_vector(incidence_deg, azimuth_deg)
    dot = (s[2] - s[0] * dz_dx - s[1] * dz_dy) / np.sqrt(1.0 + dz_dx * dz_dx + dz_dy * dz_dy)
    return np.clip(dot, 0.0, None)
