"""Rock stage configuration (``[rocks]`` table).

The size-frequency model is Golombek & Rapp (1997) / Golombek et al. (2003, 2008):
``F_k(D) = k exp(-q(k) D)`` with ``q(k) = 1.79 + 0.152 / k``; see :mod:`marsscene.rocks.sfd`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError

__all__ = ["COLLISION_MODES", "CONTACT_MIN_DIAMETER_M", "PLACEMENTS", "SMALL_ROCK_RULES",
           "RockConfig"]

PLACEMENTS = ("uniform", "clustered", "ejecta")
COLLISION_MODES = ("convex_hull", "coacd")
SMALL_ROCK_RULES = ("drop", "bake")
#: Rocks at least this wide are physics colliders by default, in MJCF and USD alike (m). With an
#: exposed height of 0.35-0.65 D (``rocks.height_ratio``), a 0.2 m rock stands 0.07-0.13 m tall:
#: under half the Perseverance-class wheel radius (0.2625 m), a sixth of the chassis' 0.75 m ride
#: height; smaller rocks are gravel that the wheel rolls over (rendered only).
CONTACT_MIN_DIAMETER_M = 0.2


def _range_pair(key: str, value: float | tuple[float, float], lo: float, hi: float) -> None:
    """Accept a fixed number or a ``[low, high]`` uniform range inside ``[lo, hi]``."""
    if isinstance(value, tuple):
        if len(value) != 2:
            raise ConfigError(f"{key} = {value!r}; give a number or [low, high]")
        check_range(key, value[0], lo, hi)
        check_range(key, value[1], lo, hi)
        if value[1] < value[0]:
            raise ConfigError(f"{key} = {list(value)!r}; low must be <= high")
    else:
        check_range(key, value, lo, hi)


@dataclass(frozen=True, slots=True, kw_only=True)
class RockConfig:
    """Rock population, placement, shape and export parameters (lengths in m).

    ``height_ratio``, ``burial_fraction`` and ``aspect_ratio`` take either a fixed number or a
    ``[low, high]`` range sampled uniformly per rock.
    """

    enabled: bool = True
    """Sample and place rocks."""
    k: float = 0.05
    """Total fractional area covered by rocks of all sizes, F_k(0), in (0, 0.9]."""
    d_min_m: float = 0.1
    """Smallest sampled rock diameter (in m); N(>D) diverges as D -> 0, so it is mandatory."""
    d_max_m: float = 3.0
    """Largest sampled rock diameter (in m)."""
    outer_d_min_m: float = 1.0
    """Smallest rock outside the focus square of a two-level scene (in m; the focus square gets
    the full size-frequency distribution from ``d_min_m``): the rocks orbital mapping and a
    distant camera resolve. Raised where the budget (``max_rocks``) needs it, and stated in the
    manifest; ``<= d_min_m``: every rock everywhere (:mod:`marsscene.rocks.budget`)."""
    height_ratio: float | tuple[float, float] = (0.35, 0.65)
    """Exposed height / diameter: number or [low, high] (default mean 0.5; convention, [U])."""
    burial_fraction: float | tuple[float, float] = (0.0, 0.5)
    """Buried fraction of each rock's total height: number or [low, high] in [0, 0.9]."""
    aspect_ratio: float | tuple[float, float] = (1.0, 1.6)
    """Horizontal elongation (long / short axis): number or [low, high] in [1, 4]."""
    max_tilt_deg: float = 20.0
    """Largest tilt of a rock's up axis from vertical (it follows the surface normal up to
    this angle) (in deg)."""
    tilt_jitter_deg: float = 5.0
    """Random extra tilt added to the surface normal (in deg)."""
    placement: str = "ejecta"
    """"uniform" (Poisson), "clustered" (Thomas process) or "ejecta" (crater-weighted; uniform
    when there are no craters)."""
    ejecta_boost: float = 4.0
    """Rock density on a fresh crater rim relative to the background (>= 1)."""
    ejecta_extent_radii: float = 2.0
    """Outer edge of the rocky ejecta blanket, in crater radii from the centre."""
    ejecta_fade_ga: float = 4.0
    """Crater age at which the ejecta enhancement has faded to zero (in Ga)."""
    cluster_radius_m: float = 2.0
    """Thomas-process cluster standard deviation (in m)."""
    rocks_per_cluster: float = 40.0
    """Mean number of rocks per cluster (Thomas process)."""
    max_slope_deg: float = 35.0
    """Rocks are not placed where the terrain is steeper than this (in deg)."""
    slope_baseline_m: float = 1.0
    """Slopes (for ``max_slope_deg`` and tilt) are measured over max(D, this) (in m); 1 m is
    the HiRISE DTM post, the finest scale at which Mars slopes are measured."""
    field_polygon_xy_m: tuple[tuple[float, float], ...] | None = None
    """Optional rock-field polygon [[x, y], ...] in the scene frame (in m)."""
    field_k: float = 0.3
    """k inside ``field_polygon_xy_m`` (k applies outside)."""
    prototypes: int = 8
    """Number of procedural rock prototypes (spread over the size classes)."""
    size_classes_m: tuple[float, ...] = (0.3, 1.0)
    """Diameter boundaries of the prototype size classes (in m)."""
    collision: str = "convex_hull"
    """Collision parts per prototype: "convex_hull" (default, ms) or "coacd" (cached)."""
    coacd_threshold: float = 0.08
    """coacd concavity threshold (only with ``collision = "coacd"``)."""
    mjcf_min_diameter_m: float = CONTACT_MIN_DIAMETER_M
    """Only rocks at least this large become MJCF collision geoms (in m)."""
    mjcf_max_rocks: int = 1000
    """At most this many rocks (the largest) become MJCF geoms (MuJoCo performance)."""
    mjcf_region_xy_m: tuple[float, float] | None = None
    """Optional centre of the MJCF rock region (in m); with ``mjcf_region_radius_m``."""
    mjcf_region_radius_m: float | None = None
    """Only rocks within this distance of ``mjcf_region_xy_m`` become MJCF geoms (in m)."""
    mjcf_small_rocks: str = "drop"
    """Rocks not exported as MJCF geoms are "drop"ped or "bake"d into the hfield as bumps."""
    max_rocks: int = 2_000_000
    """The rock budget: most rocks expected in a scene (~1 GiB while placing at the default).
    A whole footprint over it gets two levels (:mod:`marsscene.rocks.budget`); raise it to
    place the full population everywhere."""

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise ConfigError(f"rocks.enabled must be true or false; got {self.enabled!r}")
        check_range("rocks.k", self.k, 0.0, 0.9, lo_open=True)
        check_range("rocks.d_min_m", self.d_min_m, 0.0, 100.0, lo_open=True)
        check_range("rocks.outer_d_min_m", self.outer_d_min_m, 0.0, 100.0, lo_open=True)
        check_range("rocks.d_max_m", self.d_max_m, 0.0, 100.0, lo_open=True)
        if not self.d_min_m < self.d_max_m:
            raise ConfigError(
                f"rocks.d_min_m = {self.d_min_m!r} must be < rocks.d_max_m = {self.d_max_m!r}"
            )
        _range_pair("rocks.height_ratio", self.height_ratio, 0.05, 2.0)
        _range_pair("rocks.burial_fraction", self.burial_fraction, 0.0, 0.9)
        _range_pair("rocks.aspect_ratio", self.aspect_ratio, 1.0, 4.0)
        check_range("rocks.max_tilt_deg", self.max_tilt_deg, 0.0, 90.0)
        check_range("rocks.tilt_jitter_deg", self.tilt_jitter_deg, 0.0, 45.0)
        check_choice("rocks.placement", self.placement, PLACEMENTS)
        check_range("rocks.ejecta_boost", self.ejecta_boost, 1.0, 100.0)
        check_range("rocks.ejecta_extent_radii", self.ejecta_extent_radii, 1.0, 10.0)
        check_range("rocks.ejecta_fade_ga", self.ejecta_fade_ga, 0.0, 5.0, lo_open=True)
        check_range("rocks.cluster_radius_m", self.cluster_radius_m, 0.0, 1000.0, lo_open=True)
        check_range("rocks.rocks_per_cluster", self.rocks_per_cluster, 1.0, 1e6)
        check_range("rocks.max_slope_deg", self.max_slope_deg, 0.0, 90.0, lo_open=True)
        check_range("rocks.slope_baseline_m", self.slope_baseline_m, 0.0, 100.0)
        if self.field_polygon_xy_m is not None:
            poly = tuple(tuple(float(c) for c in p) for p in self.field_polygon_xy_m)
            if len(poly) < 3 or any(len(p) != 2 for p in poly):
                raise ConfigError(
                    f"rocks.field_polygon_xy_m = {self.field_polygon_xy_m!r}; "
                    "give at least 3 [x, y] vertices"
                )
            object.__setattr__(self, "field_polygon_xy_m", poly)
        check_range("rocks.field_k", self.field_k, 0.0, 0.9, lo_open=True)
        _check_int("rocks.prototypes", self.prototypes, 1, 64)
        if isinstance(self.size_classes_m, float | int) or any(
            not math.isfinite(float(b)) or b <= 0 for b in self.size_classes_m
        ) or list(self.size_classes_m) != sorted(self.size_classes_m):
            raise ConfigError(
                f"rocks.size_classes_m = {self.size_classes_m!r}; give increasing positive "
                "diameters"
            )
        check_choice("rocks.collision", self.collision, COLLISION_MODES)
        check_range("rocks.coacd_threshold", self.coacd_threshold, 0.01, 1.0)
        check_range("rocks.mjcf_min_diameter_m", self.mjcf_min_diameter_m, 0.0, 100.0)
        _check_int("rocks.mjcf_max_rocks", self.mjcf_max_rocks, 0, 100_000)
        if (self.mjcf_region_xy_m is None) != (self.mjcf_region_radius_m is None):
            raise ConfigError(
                "rocks.mjcf_region_xy_m and rocks.mjcf_region_radius_m go together; got "
                f"{self.mjcf_region_xy_m!r} and {self.mjcf_region_radius_m!r}"
            )
        if self.mjcf_region_radius_m is not None:
            check_range("rocks.mjcf_region_radius_m", self.mjcf_region_radius_m, 0.0, 1e6,
                        lo_open=True)
        check_choice("rocks.mjcf_small_rocks", self.mjcf_small_rocks, SMALL_ROCK_RULES)
        _check_int("rocks.max_rocks", self.max_rocks, 1, 10**9)

    def range_of(self, name: str) -> tuple[float, float]:
        """``(low, high)`` of a number-or-range field (``height_ratio``, ...)."""
        v = getattr(self, name)
        return (float(v[0]), float(v[1])) if isinstance(v, tuple) else (float(v), float(v))


def _check_int(key: str, value: int, lo: int, hi: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ConfigError(f"{key} = {value!r} is out of range; allowed integers [{lo}, {hi}]")
