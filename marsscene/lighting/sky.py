"""Dusty-sky appearance as pure functions of the dust optical depth tau: sky colour and
brightness, shadow (ground) contrast, extinction and visibility.

Colours are **linear** RGB (Rec.709 primaries), normalised to a maximum of 1; brightness is
carried separately by the irradiances. The values are an engineering approximation of the
published descriptions, not a radiative-transfer result (marked [U] in the docs):

* Daytime sky: "butterscotch" (Pathfinder IMP colour, Smith et al. 1997, Science 278, 1758;
  Thomas et al. 1999, JGR 104(E4), 8795) -- red-brown from dust absorbing in the blue.
* Around the sun at low elevation: blue aureole, forward scattering by ~1.5 um dust is more
  efficient in the blue (Lemmon et al. 2004, Science 306, 1753; Curiosity sunset images).
* Visibility: the surface extinction coefficient of dust mixed with scale height ``H`` is
  ``beta = tau / H`` (for n(h) ~ exp(-h/H), tau = beta_0 H); Koschmieder's visibility
  ``V = ln(1/0.02) / beta = 3.912 H / tau`` (2 % contrast threshold).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._validate import check_range, plain
from marsscene.errors import ConfigError

__all__ = [
    "DAY_SKY_RGB",
    "KOSCHMIEDER_THRESHOLD",
    "SUNSET_AUREOLE_RGB",
    "contrast_transmission",
    "extinction_coefficient_per_m",
    "shadow_contrast",
    "sky_color_rgb",
    "sun_color_rgb",
    "visibility_m",
]

#: Daytime Martian sky, linear RGB (sRGB ~ #D2A06A "butterscotch"). [U] engineering value.
DAY_SKY_RGB = (1.0, 0.56, 0.24)
#: Heavily dusty sky (tau >~ 3): duller, less saturated. [U]
DUSTY_SKY_RGB = (1.0, 0.66, 0.40)
#: Blue aureole around a low sun. [U]
SUNSET_AUREOLE_RGB = (0.45, 0.62, 1.0)
#: Relative dust extinction per channel (R, G, B) used to redden the direct beam slightly. [U]
SUN_RELATIVE_EXTINCTION = (0.96, 1.0, 1.05)
#: Contrast threshold of the meteorological visibility (Koschmieder 1924).
KOSCHMIEDER_THRESHOLD = 0.02
#: Default dust scale height (m): dust well mixed with the gas near the surface (Conrath 1975,
#: Icarus 24, 36), taken equal to the ~11 km gas scale height. [U] for any given day.
DEFAULT_DUST_SCALE_HEIGHT_M = 11_000.0


def _lerp(a: tuple[float, ...], b: tuple[float, ...], w: float) -> tuple[float, float, float]:
    out = [x + (y - x) * w for x, y in zip(a, b, strict=True)]
    m = max(out)
    return (out[0] / m, out[1] / m, out[2] / m)


def _check_tau(tau: float) -> None:
    check_range("tau", tau, 0.0, 50.0)


def sky_color_rgb(tau: float, *, sun_elevation_deg: float, near_sun: bool = False
                  ) -> tuple[float, float, float]:
    """Sky colour (linear RGB, max 1).

    Parameters
    ----------
    tau : float
        Dust optical depth.
    sun_elevation_deg : float
        Sun elevation; the blue aureole appears below ~20 deg.
    near_sun : bool
        ``True`` for the sky within ~10-20 deg of the sun (aureole), ``False`` for the sky as a
        whole (used for the dome colour and the fog colour).
    """
    _check_tau(tau)
    base = _lerp(DAY_SKY_RGB, DUSTY_SKY_RGB, min(tau / 3.0, 1.0))
    if not near_sun:
        return base
    low_sun = min(max((20.0 - sun_elevation_deg) / 20.0, 0.0), 1.0)
    clear = 1.0 - min(max((tau - 1.0) / 2.0, 0.0), 1.0)  # washed out in dust storms
    return _lerp(base, SUNSET_AUREOLE_RGB, 0.8 * low_sun * clear)


def sun_color_rgb(tau: float, *, air_mass: float) -> tuple[float, float, float]:
    """Colour of the direct beam after ``exp(-tau m k_c)`` per channel (linear RGB, max 1)."""
    _check_tau(tau)
    depth = tau * min(air_mass, 40.0)
    vals = [math.exp(-depth * (k - 1.0)) for k in SUN_RELATIVE_EXTINCTION]
    m = max(vals)
    return (vals[0] / m, vals[1] / m, vals[2] / m)


def extinction_coefficient_per_m(
    tau: ArrayLike, *, dust_scale_height_m: float = DEFAULT_DUST_SCALE_HEIGHT_M
) -> NDArray[np.float64]:
    """Horizontal extinction coefficient at the surface ``beta = tau / H`` (m^-1)."""
    check_range("dust_scale_height_m", dust_scale_height_m, 0.0, 1e6, lo_open=True)
    t = np.asarray(tau, dtype=np.float64)
    if np.any(~np.isfinite(t)) or np.any(t < 0):
        raise ConfigError(f"tau = {plain(tau)!r} is out of range; optical depth must be >= 0")
    return t / dust_scale_height_m


def visibility_m(
    tau: ArrayLike, *, dust_scale_height_m: float = DEFAULT_DUST_SCALE_HEIGHT_M
) -> NDArray[np.float64]:
    """Meteorological visibility ``ln(1/0.02) / beta`` in m (inf for tau = 0).

    Examples
    --------
    >>> round(float(visibility_m(1.0)))  # 3.912 * 11 km
    43032
    """
    beta = extinction_coefficient_per_m(tau, dust_scale_height_m=dust_scale_height_m)
    with np.errstate(divide="ignore"):
        return np.where(beta > 0, -math.log(KOSCHMIEDER_THRESHOLD) / np.maximum(beta, 1e-300),
                        np.inf)


def contrast_transmission(
    distance_m: ArrayLike, *, tau: float, dust_scale_height_m: float = DEFAULT_DUST_SCALE_HEIGHT_M
) -> NDArray[np.float64]:
    """Apparent/intrinsic contrast of an object against the horizon sky, ``exp(-beta d)``."""
    beta = extinction_coefficient_per_m(tau, dust_scale_height_m=dust_scale_height_m)
    return np.exp(-beta * np.asarray(distance_m, dtype=np.float64))


def shadow_contrast(direct_horizontal_w_m2: ArrayLike, diffuse_horizontal_w_m2: ArrayLike
                    ) -> NDArray[np.float64]:
    """Lit/shadow ground contrast ``(E_lit - E_shadow) / E_lit = direct / global`` (0..1).

    Falls from ~0.8 at tau = 0.3 to ~0 at tau = 6: shadows fade as dust loads the sky.
    """
    b = np.asarray(direct_horizontal_w_m2, dtype=np.float64)
    d = np.asarray(diffuse_horizontal_w_m2, dtype=np.float64)
    g = b + d
    return np.where(g > 0, b / np.where(g > 0, g, 1.0), 0.0)
