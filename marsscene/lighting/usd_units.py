"""The one mapping from irradiance (W m^-2) to USD light intensity.

UsdLux (``inputs:normalize = true``): a ``DistantLight``'s ``intensity * 2^exposure`` is the
illuminance on a surface facing the light, in lux; a ``DomeLight``'s is its luminance in nits
(cd m^-2), and a uniform dome of luminance ``L`` gives a horizontal illuminance ``pi L``. So:

* sun: ``intensity = k * E_direct_normal``
* sky: ``intensity = k * E_diffuse_horizontal / pi``  (isotropic sky; :doc:`/science/atmosphere`)

with ``k = luminous_efficacy_lm_per_w`` for ``units="lux"`` (default 98 lm/W) or ``k = 1`` for
``units="w_m2"`` (radiometric: renderers then treat 1 W m^-2 as "1 lux"). ``exposure`` is left 0.
Change the mapping here (or with ``[lighting] usd_units`` / ``luminous_efficacy_lm_per_w``).
"""

from __future__ import annotations

import math

from marsscene._validate import check_choice, check_range

__all__ = ["usd_dome_intensity", "usd_light_intensity"]


def usd_light_intensity(
    irradiance_w_m2: float, *, units: str = "lux", luminous_efficacy_lm_per_w: float = 98.0
) -> float:
    """USD ``inputs:intensity`` (exposure 0, normalize on) for an irradiance in W m^-2.

    Examples
    --------
    >>> usd_light_intensity(500.0)
    49000.0
    >>> usd_light_intensity(500.0, units="w_m2")
    500.0
    """
    check_choice("usd_units", units, ("lux", "w_m2"))
    check_range("irradiance_w_m2", irradiance_w_m2, 0.0)
    k = luminous_efficacy_lm_per_w if units == "lux" else 1.0
    return float(irradiance_w_m2) * k


def usd_dome_intensity(
    diffuse_horizontal_w_m2: float, *, units: str = "lux", luminous_efficacy_lm_per_w: float = 98.0
) -> float:
    """USD ``DomeLight`` intensity for a uniform sky giving ``diffuse_horizontal_w_m2``."""
    return usd_light_intensity(diffuse_horizontal_w_m2 / math.pi, units=units,
                               luminous_efficacy_lm_per_w=luminous_efficacy_lm_per_w)
