"""Partial resurfacing (Michael & Neukum 2010 forward model, :doc:`/science/craters`).

Each event erases craters formed *before* it (formation age > event age) whose centre lies in
its mask, by one of three rules (sharp diameter threshold, burial thickness, soft ramp). Events
are applied oldest first; craters formed after an event are untouched, so the population
re-accumulates and the cumulative SFD shows the characteristic kink at the erasure diameter.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.craters.config import ResurfacingEvent
from marsscene.craters.geo import lonlat_to_xy_m
from marsscene.errors import ConfigError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["erase_by_events", "mask_weights", "points_in_polygon"]

FloatArray = NDArray[np.float64]

CITATION = (
    "Michael, G. G., Neukum, G. (2010), Planetary surface dating from crater size-frequency "
    "distribution measurements: partial resurfacing events and statistical age uncertainty, "
    "EPSL 294, 223-229, doi:10.1016/j.epsl.2009.12.041"
)


def points_in_polygon(
    x: FloatArray, y: FloatArray, polygon: Sequence[tuple[float, float]]
) -> NDArray[np.bool_]:
    """Even-odd rule point-in-polygon test, vectorised over points (loop over edges only)."""
    poly = np.asarray(polygon, dtype=np.float64)
    inside = np.zeros(np.shape(x), dtype=bool)
    xj, yj = poly[-1]
    for xi, yi in poly:
        crosses = (yi > y) != (yj > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = (xj - xi) * (y - yi) / (yj - yi) + xi
        inside ^= crosses & (x < x_cross)
        xj, yj = xi, yi
    return inside


def mask_weights(
    event: ResurfacingEvent,
    center_xy_m: FloatArray,
    *,
    heightfield: Heightfield | None = None,
    origin_lonlat_deg: tuple[float, float] | None = None,
    raster: NDArray[np.floating] | None = None,
    grid_convergence_deg: float = 0.0,
) -> FloatArray:
    """Erasure weight (0-1) of an event's mask at crater centres.

    Parameters
    ----------
    event : ResurfacingEvent
    center_xy_m : ndarray of shape (N, 2)
        Crater centres in the scene frame (in m).
    heightfield : Heightfield, optional
        Grid of raster masks (``raster`` or ``event.mask_path``); centres off the grid take the
        nearest edge post.
    origin_lonlat_deg : tuple, optional
        Scene origin, needed for ``polygon_lonlat_deg``.
    grid_convergence_deg : float
        Angle from true north to scene +y (polar stereographic DEMs).
    raster : ndarray of shape (rows, cols), optional
        In-memory raster mask (overrides ``event.mask_path``), row 0 = south, values 0-1.

    Returns
    -------
    ndarray of shape (N,)
    """
    x, y = center_xy_m[:, 0], center_xy_m[:, 1]
    if event.polygon_xy_m is not None:
        return points_in_polygon(x, y, event.polygon_xy_m).astype(np.float64)
    if event.polygon_lonlat_deg is not None:
        if origin_lonlat_deg is None:
            raise ConfigError(
                "craters.resurfacing.polygon_lonlat_deg needs a georeferenced terrain "
                "(the scene frame has no lon/lat); use polygon_xy_m instead"
            )
        lon, lat = np.asarray(event.polygon_lonlat_deg, dtype=np.float64).T
        px, py = lonlat_to_xy_m(lon, lat, origin_lonlat_deg=origin_lonlat_deg,
                                grid_convergence_deg=grid_convergence_deg)
        return points_in_polygon(x, y, list(zip(px, py, strict=True))).astype(np.float64)
    if raster is None and event.mask_path is not None:
        try:
            raster = np.load(Path(event.mask_path), allow_pickle=False)
        except (OSError, ValueError) as err:
            raise ConfigError(
                f"craters.resurfacing.mask_path = {event.mask_path!r}: {err}"
            ) from None
    if raster is None:
        return np.ones(x.shape)
    if heightfield is None or np.shape(raster) != heightfield.shape:
        want = None if heightfield is None else heightfield.shape
        raise ConfigError(
            f"resurfacing raster mask has shape {np.shape(raster)}; expected the terrain's {want}"
        )
    rows, cols = heightfield.shape
    r, c = heightfield.rowcol_of(x, y)
    ri = np.clip(np.rint(r), 0, rows - 1).astype(np.int64)
    ci = np.clip(np.rint(c), 0, cols - 1).astype(np.int64)
    return np.clip(np.asarray(raster, dtype=np.float64)[ri, ci], 0.0, 1.0)


def _rule_probability(
    event: ResurfacingEvent, diameter_m: FloatArray, relief_m: FloatArray
) -> FloatArray:
    if event.rule == "sharp":
        return (diameter_m < float(event.d_max_m or 0.0)).astype(np.float64)
    if event.rule == "burial":
        return (relief_m < float(event.thickness_m or 0.0)).astype(np.float64)
    lo, hi = np.log(event.d_min_m), np.log(event.d_max_m)  # type: ignore[arg-type]
    return np.clip((hi - np.log(diameter_m)) / (hi - lo), 0.0, 1.0)


def erase_by_events(
    diameter_m: FloatArray,
    age_ga: FloatArray,
    weights: Sequence[FloatArray],
    events: Sequence[ResurfacingEvent],
    *,
    relief_at: Callable[[FloatArray, FloatArray, FloatArray], FloatArray],
    rng: np.random.Generator,
) -> NDArray[np.bool_]:
    """Which craters survive a sequence of resurfacing events.

    Parameters
    ----------
    diameter_m, age_ga : ndarray of shape (N,)
        Crater diameters (in m) and formation ages (in Ga).
    weights : sequence of ndarray of shape (N,)
        Mask weight of each event at each crater (:func:`mask_weights`).
    events : sequence of ResurfacingEvent
        Applied oldest first (sorted here).
    relief_at : callable
        ``relief_at(diameter_m, formed_ga, at_ga)`` -> floor depth + rim height (in m) of
        craters formed ``formed_ga`` ago, degraded until ``at_ga`` ago (the burial rule).
    rng : numpy.random.Generator

    Returns
    -------
    ndarray of shape (N,), bool
        True for surviving craters.
    """
    alive = np.ones(diameter_m.shape, dtype=bool)
    order = sorted(range(len(events)), key=lambda i: -events[i].age_ga)
    for i in order:
        ev = events[i]
        u = rng.random(diameter_m.shape)  # one draw per crater and event: stable streams
        before = age_ga > ev.age_ga
        relief = relief_at(diameter_m, age_ga, np.full(age_ga.shape, ev.age_ga))
        p = weights[i] * _rule_probability(ev, diameter_m, relief)
        alive &= ~(before & (u < p))
    return alive
