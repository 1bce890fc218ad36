"""Large landforms added to procedural terrain: the shapes of the reference scenes (pure).

``"fbm"`` / ``"plain"``
    No landform (a plain is fBm with a small RMS height, set by the preset).
``"crater"``
    One fresh-ish simple crater centred on the footprint, the radial profile of
    :func:`marsscene.craters.crater_profile` (Watters et al. 2015 power-law cavity, Melosh rim,
    McGetchin ejecta) with the Garvin & Frawley (1998) fresh depth ``d = 0.14 D^0.90`` (km) and
    a little diffusion (``diffusion_fraction`` of the radius) so the rim crest is rounded.
``"canyon"``
    A steep-walled, flat-floored canyon running east-west through the centre with a gently
    meandering axis: the cross-section is ``-depth`` on the floor, rising over the wall width
    ``w`` along a half cosine (largest wall gradient ``pi depth / (2 w)``), 0 on the plateau.
    Defaults (250 m deep, 400 m walls) give a mean wall slope of 32 deg (about the angle of
    repose of loose granular material) and a steepest slope of 44 deg mid-wall. This is a
    geometric design for "steep walls and strong relief", not a fitted model of a real canyon.

Every landform is a pure, deterministic function of the grid: the seeded fBm underneath carries
the randomness, so the landform never changes another stage's random draws.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from marsscene.craters.morphology import crater_profile
from marsscene.craters.morphometry import fresh_depth_to_diameter
from marsscene.terrain.heightfield import Heightfield

__all__ = ["LANDFORMS", "LANDFORM_CITATIONS", "add_landform", "canyon_height_m", "crater_height_m",
           "default_size_m"]

LANDFORMS = ("fbm", "plain", "crater", "canyon")
LANDFORM_CITATIONS = {
    "crater": "Watters et al. 2015, doi:10.1002/2014JE004630 (cavity); Garvin & Frawley 1998, "
              "doi:10.1029/1998GL900177 (fresh depth)",
    "canyon": "geometric half-cosine canyon walls (design, no cited model)",
}


def crater_height_m(
    x_m: NDArray[np.float64], y_m: NDArray[np.float64], *, diameter_m: float,
    diffusion_fraction: float = 0.05,
) -> NDArray[np.float64]:
    """Height (in m) of a crater of ``diameter_m`` centred on the origin, at ``(x_m, y_m)``."""
    rho = np.hypot(x_m, y_m) / (diameter_m / 2.0)
    dd = float(fresh_depth_to_diameter(diameter_m))
    h = crater_profile(rho, diameter_m=diameter_m, depth_to_diameter=dd,
                       diffusion_length_m=diffusion_fraction * diameter_m / 2.0)
    return np.asarray(h, dtype=np.float64)


def canyon_height_m(
    x_m: NDArray[np.float64], y_m: NDArray[np.float64], *, floor_width_m: float,
    depth_m: float, wall_width_m: float, meander_m: float | None = None,
    wavelength_m: float = 2000.0,
) -> NDArray[np.float64]:
    """Height (in m) of an east-west canyon through the origin, at ``(x_m, y_m)``.

    The axis meanders as ``y = meander_m sin(2 pi x / wavelength_m)`` (default amplitude a
    quarter of the floor width).
    """
    amp = 0.25 * floor_width_m if meander_m is None else meander_m
    u = np.abs(y_m - amp * np.sin(2.0 * np.pi * x_m / wavelength_m))
    t = np.clip((u - floor_width_m / 2.0) / wall_width_m, 0.0, 1.0)  # 0 floor edge, 1 rim
    return np.asarray(-depth_m * 0.5 * (1.0 + np.cos(np.pi * t)), dtype=np.float64)


def default_size_m(landform: str, short_side_m: float) -> float:
    """Default crater rim diameter (40 % of the footprint's shorter side) or canyon floor width
    (10 %) (in m)."""
    return (0.4 if landform == "crater" else 0.1) * short_side_m


def add_landform(
    hf: Heightfield, landform: str, *, size_m: float | None = None,
    depth_m: float | None = None,
) -> Heightfield:
    """Return ``hf`` with a landform added (a new heightfield; ``hf`` is not modified).

    Parameters
    ----------
    hf : Heightfield
        Procedural terrain centred on the origin.
    landform : {"fbm", "plain", "crater", "canyon"}
    size_m : float, optional
        Crater rim diameter (default 40 % of the shorter side) or canyon floor width (default
        10 % of the shorter side) (in m).
    depth_m : float, optional
        Canyon depth (default 250 m); a crater's depth follows Garvin & Frawley (1998).

    Examples
    --------
    >>> hf = Heightfield.centered(np.zeros((201, 201), np.float32), 10.0)
    >>> z = add_landform(hf, "crater", size_m=1000.0).z_m
    >>> round(float(z[100, 100]), 1)  # floor ~ rim 0.036 D - d (d/D = 0.14 at 1 km), diffused
    -102.7
    """
    if landform in ("fbm", "plain"):
        return hf
    short = min(hf.size_m)
    xv, yv = hf.grid_xy()
    x, y = xv[None, :], yv[:, None]
    size = size_m if size_m is not None else default_size_m(landform, short)
    if landform == "crater":
        h = crater_height_m(x, y, diameter_m=size)
    elif landform == "canyon":
        w = size
        h = canyon_height_m(x, y, floor_width_m=w, depth_m=250.0 if depth_m is None else depth_m,
                            wall_width_m=400.0)
    else:
        raise ValueError(f"unknown landform {landform!r}; choose one of {list(LANDFORMS)}")
    return hf._with_owned_z(hf.z_m + h.astype(np.float32))
