"""The rock stage's budget: how many rocks a scene places, and where.

Rocks scale like the terrain (:func:`marsscene.pipeline.terrain.resolve_lod`): one level while
the whole footprint's population fits ``rocks.max_rocks``, two levels when it would not (or when
the terrain itself has two):

* **focus square** (``terrain.focus_size_m`` around ``terrain.focus_xy_m``, where the rover
  drives): the full Golombek–Huertas population from ``rocks.d_min_m``;
* **outside it**: rocks of at least the *cut-off*, ``rocks.outer_d_min_m`` (1 m by default: the
  rocks that orbital (HiRISE) rock maps and a distant camera resolve, and twice the wheel
  radius tall, so every rock a planner must route round far away), raised to the smallest
  diameter whose expected count still fits the budget.

``rocks.outer_d_min_m <= rocks.d_min_m`` asks for every rock everywhere (refused, with the memory
it needs, when over ``rocks.max_rocks``; raise that to place it). Counts are expected values of
the Poisson populations (slope thinning only removes rocks), so the plan is decided before a rock
is drawn and its memory stated before placing starts.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from marsscene.errors import ConfigError, ExtrapolationWarning
from marsscene.rocks.config import RockConfig
from marsscene.rocks.sfd import expected_count

__all__ = ["BYTES_PER_ROCK", "RockLevels", "expected_rocks", "gib", "plan_levels"]

#: Working memory per rock while placing, with margin (measured peak ~290-340 B for 0.06-1.0 M
#: rocks; the table keeps 112 B).
BYTES_PER_ROCK = 500
#: Cut-offs are stated to this step (m), rounded up (the count then stays within the budget).
CUTOFF_STEP_M = 0.01

Bounds = tuple[float, float, float, float]


def gib(rocks: float) -> float:
    """Working memory of ``rocks`` rocks while placing (in GiB)."""
    return rocks * BYTES_PER_ROCK / 2**30


def _area(bounds: Bounds) -> float:
    x0, y0, x1, y1 = bounds
    return max(0.0, x1 - x0) * max(0.0, y1 - y0)


def _polygon_area_m2(poly: tuple[tuple[float, float], ...]) -> float:
    xy = np.asarray(poly, dtype=np.float64)
    x, y = xy[:, 0], xy[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def expected_rocks(area_m2: float, cfg: RockConfig, d_min_m: float) -> float:
    """Expected rocks of at least ``d_min_m`` (below ``cfg.d_max_m``) on ``area_m2``.

    A rock-field polygon counts at ``field_k`` over its area (at most ``area_m2``): an upper bound
    where the polygon leaves the area.
    """
    if d_min_m >= cfg.d_max_m or area_m2 <= 0.0:
        return 0.0
    field = 0.0
    if cfg.field_polygon_xy_m is not None:
        field = min(area_m2, _polygon_area_m2(cfg.field_polygon_xy_m))
    with warnings.catch_warnings():  # place_rocks warns of an extrapolated k once
        warnings.simplefilter("ignore", ExtrapolationWarning)
        n = expected_count(area_m2 - field, k=cfg.k, d_min_m=d_min_m, d_max_m=cfg.d_max_m)
        if field > 0.0:
            n += expected_count(field, k=cfg.field_k, d_min_m=d_min_m, d_max_m=cfg.d_max_m)
    return float(n)


@dataclass(frozen=True, slots=True)
class RockLevels:
    """Where the scene's rocks go: one level, or a focus square and an outer cut-off."""

    focus_bounds_xy_m: Bounds | None
    """The square with the full population (``None``: one level over the whole footprint)."""
    outer_d_min_m: float
    """Smallest rock outside the focus square (``d_min_m`` with one level; in m)."""
    focus_expected: float
    """Expected rocks in the focus square (the whole footprint with one level)."""
    outer_expected: float
    """Expected rocks outside it."""
    raised: bool = False
    """The cut-off was raised above ``rocks.outer_d_min_m`` to fit ``rocks.max_rocks``."""

    @property
    def two_level(self) -> bool:
        return self.focus_bounds_xy_m is not None

    @property
    def expected(self) -> float:
        return self.focus_expected + self.outer_expected

    def describe(self, d_min_m: float) -> str:
        """One line for the log and the manifest's notes."""
        mem = f"~{gib(self.expected):.2g} GiB while placing"
        if not self.two_level:
            return (f"rocks: one level, about {self.expected:.3g} rocks from {d_min_m:g} m "
                    f"over the footprint ({mem})")
        x0, y0, x1, y1 = self.focus_bounds_xy_m  # type: ignore[misc]
        why = (" (raised from rocks.outer_d_min_m to fit rocks.max_rocks)" if self.raised
               else " (rocks.outer_d_min_m)")
        return (f"rocks: two levels, about {self.focus_expected:.3g} rocks from {d_min_m:g} m in "
                f"the focus square [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m and "
                f"{self.outer_expected:.3g} from a cut-off of {self.outer_d_min_m:g} m outside"
                f"{why} ({mem})")


def _cutoff(cfg: RockConfig, outer_area_m2: float, room: float) -> tuple[float, bool]:
    """The smallest diameter >= ``cfg.outer_d_min_m`` (on the ``CUTOFF_STEP_M`` grid) whose
    expected count on ``outer_area_m2`` is at most ``room``."""
    lo = max(cfg.outer_d_min_m, cfg.d_min_m)
    if expected_rocks(outer_area_m2, cfg, lo) <= room:
        return lo, False
    a, b = lo, cfg.d_max_m  # N(>D) falls with D and is 0 at d_max_m
    for _ in range(60):
        mid = 0.5 * (a + b)
        a, b = (a, mid) if expected_rocks(outer_area_m2, cfg, mid) <= room else (mid, b)
    cut = math.ceil(b / CUTOFF_STEP_M - 1e-9) * CUTOFF_STEP_M
    return round(min(cut, cfg.d_max_m), 6), True


def plan_levels(cfg: RockConfig, footprint_xy_m: Bounds, focus_xy_m: Bounds | None, *,
                two_level_terrain: bool = False) -> RockLevels:
    """Decide where the rocks go (see the module docstring); one-line :class:`ConfigError`
    naming the option to change when no plan fits ``cfg.max_rocks``.

    ``focus_xy_m`` is the focus square (``None``: the scene has none, so one level);
    ``two_level_terrain``: the terrain has two levels, so the rocks do too.
    """
    area = _area(footprint_xy_m)
    full = expected_rocks(area, cfg, cfg.d_min_m)
    everything = cfg.outer_d_min_m <= cfg.d_min_m
    if focus_xy_m is None or (not two_level_terrain and (full <= cfg.max_rocks or everything)):
        if full > cfg.max_rocks:
            ask = (f"rocks.outer_d_min_m = {cfg.outer_d_min_m:g} <= d_min_m asks for every rock "
                   "everywhere; " if everything and focus_xy_m is not None else "")
            raise ConfigError(
                f"rocks: about {full:.3g} rocks expected from d_min_m = {cfg.d_min_m:g} m on "
                f"{area:.3g} m^2 ({ask}~{gib(full):.2g} GiB while placing), above rocks.max_rocks"
                f" = {cfg.max_rocks}: raise rocks.d_min_m, or set rocks.max_rocks >= "
                f"{math.ceil(full * 1.01):d} to place them all")
        return RockLevels(None, cfg.d_min_m, full, 0.0)
    focus_area = _area(focus_xy_m)
    inner = expected_rocks(focus_area, cfg, cfg.d_min_m)
    if inner > cfg.max_rocks:
        raise ConfigError(
            f"rocks: about {inner:.3g} rocks expected from d_min_m = {cfg.d_min_m:g} m in the "
            f"{math.sqrt(focus_area):g} m focus square (~{gib(inner):.2g} GiB while placing), "
            f"above rocks.max_rocks = {cfg.max_rocks}: raise rocks.d_min_m, shrink "
            "terrain.focus_size_m (--focus-size-m) or raise rocks.max_rocks")
    outer_area = max(0.0, area - focus_area)
    if everything:
        outer = expected_rocks(outer_area, cfg, cfg.d_min_m)
        if inner + outer > cfg.max_rocks:
            raise ConfigError(
                f"rocks: about {inner + outer:.3g} rocks expected from d_min_m = "
                f"{cfg.d_min_m:g} m on {area:.3g} m^2 (rocks.outer_d_min_m = "
                f"{cfg.outer_d_min_m:g} <= d_min_m asks for every rock everywhere; "
                f"~{gib(inner + outer):.2g} GiB while placing), above rocks.max_rocks = "
                f"{cfg.max_rocks}: set rocks.max_rocks >= {math.ceil((inner + outer) * 1.01):d} "
                "or raise rocks.outer_d_min_m")
        return RockLevels(focus_xy_m, cfg.d_min_m, inner, outer)
    cut, raised = _cutoff(cfg, outer_area, cfg.max_rocks - inner)
    return RockLevels(focus_xy_m, cut, inner, expected_rocks(outer_area, cfg, cut), raised)
