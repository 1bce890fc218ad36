"""Crater stage configuration (``[craters]`` and ``[[craters.resurfacing]]`` tables).

Example::

    [craters]
    system = "neukum-ivanov-2001"    # or "ivanov-2001", "hartmann-2005", "hartmann-daubar-2016"
    age_ga = 3.5
    d_min_m = 2.0
    d_max_m = 20.0
    equilibrium = "hartmann-1984"    # or "none"
    profile = "watters-2015"         # or "fassett-thomson-2014", "ftmod"
    degradation = "diffusion"        # or "none"

    [[craters.resurfacing]]
    age_ga = 1.0
    rule = "sharp"                   # erase craters < d_max_m formed before the event
    d_max_m = 8.0
    polygon_xy_m = [[-50, -50], [50, -50], [50, 50], [-50, 50]]
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from marsscene._validate import check_choice, check_range, dataclass_from_mapping
from marsscene.craters.morphometry import (
    CAVITY_EXPONENT,
    EJECTA_EXPONENT,
    RIM_HEIGHT_TO_DIAMETER,
    range_depth_to_diameter,
)
from marsscene.errors import ConfigError

__all__ = ["CraterConfig", "ResurfacingEvent"]

_SYSTEMS = ("neukum-ivanov-2001", "ivanov-2001", "hartmann-2005", "hartmann-daubar-2016")
_PROFILES = ("watters-2015", "fassett-thomson-2014", "ftmod")
_RULES = ("sharp", "burial", "ramp")
_MAX_AGE_GA = 4.5  # chronology functions' range (data/mars_crater_functions.toml)


def _polygon(key: str, value: object) -> tuple[tuple[float, float], ...] | None:
    if value is None:
        return None
    try:
        pts = tuple((float(p[0]), float(p[1])) for p in value)  # type: ignore[attr-defined]
        ok = all(len(p) == 2 for p in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError, IndexError):
        ok, pts = False, ()
    if not ok or len(pts) < 3:
        raise ConfigError(f"{key} = {value!r} must be a list of at least 3 [x, y] pairs")
    return pts


@dataclass(frozen=True, slots=True, kw_only=True)
class ResurfacingEvent:
    """One partial resurfacing event (Michael & Neukum 2010 forward model).

    Craters formed before ``age_ga`` whose centre is inside the mask are erased by ``rule``:
    ``"sharp"`` erases every crater smaller than ``d_max_m``; ``"burial"`` erases craters whose
    relief (floor depth + rim height, degraded to the event time) is below ``thickness_m``;
    ``"ramp"`` erases with probability 1 below ``d_min_m`` falling linearly in log D to 0 at
    ``d_max_m``. The mask is one of ``polygon_xy_m`` (scene metres), ``polygon_lonlat_deg``
    (needs a georeferenced terrain) or ``mask_path`` (a ``.npy`` raster of the terrain's shape,
    row 0 = south, values 0-1 = erasure probability); none means the whole scene.
    """

    age_ga: float
    """Event age (in Ga), younger than the surface age."""
    rule: str = "sharp"
    d_max_m: float | None = None
    """Largest erased diameter (``sharp``), upper end of the ramp (``ramp``) (in m)."""
    d_min_m: float | None = None
    """Lower end of the ramp (``ramp``) (in m)."""
    thickness_m: float | None = None
    """Burial thickness (``burial``) (in m)."""
    polygon_xy_m: tuple[tuple[float, float], ...] | None = None
    polygon_lonlat_deg: tuple[tuple[float, float], ...] | None = None
    mask_path: str | None = None

    def __post_init__(self) -> None:
        check_range("craters.resurfacing.age_ga", self.age_ga, 0.0, _MAX_AGE_GA, lo_open=True)
        check_choice("craters.resurfacing.rule", self.rule, _RULES)
        need = {"sharp": ("d_max_m",), "burial": ("thickness_m",), "ramp": ("d_min_m", "d_max_m")}
        for key in need[self.rule]:
            value = getattr(self, key)
            if value is None:
                raise ConfigError(f"craters.resurfacing rule {self.rule!r} needs {key}")
            check_range(f"craters.resurfacing.{key}", value, 0.0, lo_open=True)
        if self.rule == "ramp" and self.d_min_m >= self.d_max_m:  # type: ignore[operator]
            raise ConfigError(
                f"craters.resurfacing: d_min_m = {self.d_min_m!r} must be < d_max_m = "
                f"{self.d_max_m!r}"
            )
        masks = [k for k in ("polygon_xy_m", "polygon_lonlat_deg", "mask_path")
                 if getattr(self, k) is not None]
        if len(masks) > 1:
            raise ConfigError(f"craters.resurfacing: give at most one mask; got {masks}")
        for key in ("polygon_xy_m", "polygon_lonlat_deg"):
            poly = _polygon(f"craters.resurfacing.{key}", getattr(self, key))
            object.__setattr__(self, key, poly)


@dataclass(frozen=True, slots=True, kw_only=True)
class CraterConfig:
    """Crater population, morphology and degradation parameters.

    Defaults give sub-DEM-scale craters (2-20 m) on a 3.5 Ga surface capped at the Hartmann
    (1984) equilibrium, which keeps the default build fast and does not duplicate the craters
    a 1 m DEM already resolves. See :doc:`/craters`.
    """

    enabled: bool = True
    """Generate and stamp craters."""
    system: str = "hartmann-daubar-2016"
    """Chronology system: production function + chronology function. The scene default is
    Hartmann & Daubar (2016), whose production table covers craters from ~1 m; the Ivanov (2001)
    polynomial of ``"neukum-ivanov-2001"`` (the default of the pure functions) is valid only
    from 15 m and would be extrapolated over the default 2-20 m range."""
    age_ga: float = 3.5
    """Surface (crater retention) age (in Ga), 0 < age <= 4.5."""
    d_min_m: float = 2.0
    """Smallest crater diameter (in m)."""
    d_max_m: float = 20.0
    """Largest crater diameter (in m)."""
    equilibrium: str = "hartmann-1984"
    """Cap small-crater densities at saturation equilibrium (``"hartmann-1984"`` or ``"none"``)."""
    profile: str = "watters-2015"
    """Fresh profile model: ``"watters-2015"``, ``"fassett-thomson-2014"`` or ``"ftmod"``."""
    depth_to_diameter: float | None = None
    """Fresh rim-crest-to-floor depth over diameter (``watters-2015`` and ``ftmod``). Default:
    the Garvin & Frawley (1998) MOLA law, held constant below 50 m (Millot et al. 2024), at the
    geometric mean of [d_min_m, d_max_m] (0.189 for craters up to ~50 m); see
    :mod:`marsscene.craters.morphometry`."""
    rim_height_to_diameter: float = RIM_HEIGHT_TO_DIAMETER
    """Fresh rim height over diameter (``watters-2015``; Melosh 1989)."""
    cavity_exponent: float = CAVITY_EXPONENT
    """Power-law cavity exponent (Watters et al. 2015 average)."""
    ejecta_exponent: float = EJECTA_EXPONENT
    """Ejecta thickness decay exponent, ``(r/R)^-beta`` (McGetchin et al. 1973)."""
    ejecta_reach: float = 2.5
    """Radius (in crater radii) at which the ejecta blanket reaches zero."""
    degradation: str = "diffusion"
    """``"diffusion"`` (topographic diffusion with age) or ``"none"`` (all craters fresh)."""
    diffusivity_m2_per_myr: float = 0.0
    """Background (non-impact, e.g. aeolian) topographic diffusivity (in m^2/Myr), added to the
    impact-driven degradation implied by the equilibrium. 0 keeps the recognisable craters at
    ``min(production, equilibrium)``; a positive value removes small craters faster and lowers
    their density below equilibrium (see :doc:`/science/craters` for published Mars values)."""
    axis_ratio_min: float = 1.0
    """Minor/major axis ratio drawn uniformly in [axis_ratio_min, 1] (1 = circular)."""
    resurfacing: tuple[ResurfacingEvent, ...] = ()
    """Partial resurfacing events (``[[craters.resurfacing]]``)."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"craters.enabled must be true or false; got {self.enabled!r}")
        check_choice("craters.system", self.system, _SYSTEMS)
        check_range("craters.age_ga", self.age_ga, 0.0, _MAX_AGE_GA, lo_open=True)
        check_range("craters.d_min_m", self.d_min_m, 0.0, 1e6, lo_open=True)
        check_range("craters.d_max_m", self.d_max_m, 0.0, 1e6, lo_open=True)
        if self.d_min_m >= self.d_max_m:
            raise ConfigError(
                f"craters.d_min_m = {self.d_min_m!r} must be < craters.d_max_m = {self.d_max_m!r}"
            )
        check_choice("craters.equilibrium", self.equilibrium, ("hartmann-1984", "none"))
        check_choice("craters.profile", self.profile, _PROFILES)
        if self.depth_to_diameter is not None:
            check_range("craters.depth_to_diameter", self.depth_to_diameter, 0.05, 0.5)
        check_range("craters.rim_height_to_diameter", self.rim_height_to_diameter, 0.0, 0.1)
        check_range("craters.cavity_exponent", self.cavity_exponent, 1.0, 4.0)
        check_range("craters.ejecta_exponent", self.ejecta_exponent, 1.0, 6.0)
        check_range("craters.ejecta_reach", self.ejecta_reach, 1.0, 5.0, lo_open=True)
        check_choice("craters.degradation", self.degradation, ("diffusion", "none"))
        check_range("craters.diffusivity_m2_per_myr", self.diffusivity_m2_per_myr, 0.0, 1e3)
        check_range("craters.axis_ratio_min", self.axis_ratio_min, 0.2, 1.0)
        events = []
        for i, ev in enumerate(self.resurfacing):
            if isinstance(ev, Mapping):
                ev = dataclass_from_mapping(ResurfacingEvent, ev, f"craters.resurfacing[{i}]")
            if not isinstance(ev, ResurfacingEvent):
                raise ConfigError(f"craters.resurfacing[{i}] must be a table; got {ev!r}")
            if ev.age_ga >= self.age_ga:
                raise ConfigError(
                    f"craters.resurfacing[{i}].age_ga = {ev.age_ga!r} must be younger than "
                    f"craters.age_ga = {self.age_ga!r}"
                )
            events.append(ev)
        object.__setattr__(self, "resurfacing", tuple(events))

    @property
    def effective_depth_to_diameter(self) -> float:
        """``depth_to_diameter``, or the cited default for this diameter range."""
        if self.depth_to_diameter is not None:
            return float(self.depth_to_diameter)
        return round(range_depth_to_diameter(self.d_min_m, self.d_max_m), 6)

    def profile_kwargs(self) -> dict[str, float | str]:
        """Keyword arguments of :func:`marsscene.craters.profile_family` for this config."""
        return {
            "model": self.profile,
            "depth_to_diameter": self.effective_depth_to_diameter,
            "rim_height_to_diameter": self.rim_height_to_diameter,
            "cavity_exponent": self.cavity_exponent,
            "ejecta_exponent": self.ejecta_exponent,
            "ejecta_reach": self.ejecta_reach,
        }
