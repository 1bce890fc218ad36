"""Published small-crater morphometry and degradation reference values (data, with sources).

The numbers live in ``data/mars_crater_morphometry.toml``, each with its reference and how it
was verified; this module only reads them and evaluates the laws.

* Fresh depth (rim crest to floor): Garvin & Frawley (1998, GRL, doi:10.1029/1998GL900177)
  MOLA simple craters, ``d = 0.14 D^0.90`` (km), held constant below 50 m where Millot et al.
  (2024, JGR Planets, doi:10.1029/2024JE008844) find depth about proportional to diameter.
  Watters et al. (2015, JGR Planets, doi:10.1002/2014JE004630) report that large-crater laws
  overestimate small-crater depths, so this is an upper bound.
* Rim height 0.036 D (Melosh 1989), cavity exponent 1.75 (Watters et al. 2015), ejecta
  exponent 3 (McGetchin et al. 1973).
* Background diffusivities derived from Mars degradation observations (Golombek et al. 2014,
  doi:10.1002/2014JE004658; Warner et al. 2020, doi:10.1029/2019JE006333).
"""

from __future__ import annotations

import math
import tomllib
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "CAVITY_EXPONENT",
    "DEFAULT_DEPTH_TO_DIAMETER",
    "EJECTA_EXPONENT",
    "RIM_HEIGHT_TO_DIAMETER",
    "background_diffusivities",
    "fresh_depth_to_diameter",
    "morphometry_data",
    "range_depth_to_diameter",
]


@cache
def morphometry_data() -> dict[str, Any]:
    """The parsed ``mars_crater_morphometry.toml`` (cached; treat as read-only)."""
    text = resources.files("marsscene.craters").joinpath("data/mars_crater_morphometry.toml")
    return tomllib.loads(text.read_text(encoding="utf-8"))


def fresh_depth_to_diameter(diameter_m: ArrayLike) -> NDArray[np.float64]:
    """Fresh rim-crest-to-floor depth over diameter at ``diameter_m`` (the cited law).

    Examples
    --------
    >>> [round(float(v), 4) for v in fresh_depth_to_diameter([10.0, 50.0, 100.0, 1000.0])]
    [0.1889, 0.1889, 0.1762, 0.14]
    """
    law = morphometry_data()["fresh_depth"]
    d_km = np.maximum(np.asarray(diameter_m, dtype=np.float64), law["constant_below_m"]) / 1e3
    return np.asarray(law["a"] * d_km ** (law["b"] - 1.0), dtype=np.float64)


def range_depth_to_diameter(d_min_m: float, d_max_m: float) -> float:
    """The fresh d/D of a crater population on [d_min_m, d_max_m]: the law at the range's
    geometric mean (one profile shape serves the whole population)."""
    return float(fresh_depth_to_diameter(math.sqrt(d_min_m * d_max_m)))


def background_diffusivities() -> list[dict[str, Any]]:
    """Published-observation reference values for ``craters.diffusivity_m2_per_myr``."""
    return [dict(row) for row in morphometry_data()["background_diffusivity"]]


#: d/D of small fresh craters (D <= 50 m), the default of the profile functions.
DEFAULT_DEPTH_TO_DIAMETER: float = float(fresh_depth_to_diameter(50.0))
RIM_HEIGHT_TO_DIAMETER: float = float(morphometry_data()["rim_height"]["rim_height_to_diameter"])
CAVITY_EXPONENT: float = float(morphometry_data()["cavity"]["exponent"])
EJECTA_EXPONENT: float = float(morphometry_data()["ejecta"]["exponent"])
