"""Rock-stage bookkeeping: the MJCF contact-rock rule and the manifest notes/summary."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from marsscene.rocks.config import RockConfig
from marsscene.rocks.sfd import FITTED_K_RANGE, cumulative_area_fraction, expected_count
from marsscene.rocks.table import RockTable
from marsscene.terrain.heightfield import Heightfield

if TYPE_CHECKING:
    from marsscene.craters.table import CraterTable
    from marsscene.rocks.budget import RockLevels

__all__ = ["EJECTA_CITATION", "inside_focus", "level_summary", "mjcf_focus", "mjcf_rock_selection",
           "rock_notes", "rock_summary"]

EJECTA_CITATION = (
    "rocky rims and ejecta around fresh craters (Golombek et al. 2008, doi:10.1029/2007JE003065); "
    "map architecture after synthterrain rock/__init__.py (NeoGeographyToolkit/synthterrain)"
)


def mjcf_rock_selection(rocks: RockTable, cfg: RockConfig,
                        within: Heightfield | tuple[float, float, float, float] | None = None
                        ) -> NDArray[np.int64]:
    """Indices of the rocks exported as MJCF collision geoms, largest first.

    Rule: diameter >= ``mjcf_min_diameter_m``; on ``within`` if given (the focus square of a
    level-of-detail scene or of a two-level rock population: a heightfield's footprint or
    ``(x0, y0, x1, y1)``); within ``mjcf_region_radius_m`` of ``mjcf_region_xy_m`` if a region
    is set; then at most ``mjcf_max_rocks``, keeping the largest (ties broken by table order).
    """
    keep = rocks.diameter_m >= cfg.mjcf_min_diameter_m
    if within is not None:
        keep &= inside_focus(within, rocks.position_xyz_m[:, 0], rocks.position_xyz_m[:, 1])
    if cfg.mjcf_region_xy_m is not None and cfg.mjcf_region_radius_m is not None:
        cx, cy = cfg.mjcf_region_xy_m
        dist = np.hypot(rocks.position_xyz_m[:, 0] - cx, rocks.position_xyz_m[:, 1] - cy)
        keep &= dist <= cfg.mjcf_region_radius_m
    idx = np.flatnonzero(keep)
    order = np.argsort(-rocks.diameter_m[idx], kind="stable")
    return np.asarray(idx[order][: cfg.mjcf_max_rocks], dtype=np.int64)


def inside_focus(within: Heightfield | tuple[float, float, float, float],
                 x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Which of the points ``(x, y)`` lie on ``within`` (a heightfield or ``(x0, y0, x1, y1)``)."""
    if isinstance(within, Heightfield):
        return np.asarray(within.contains(x, y), dtype=bool)
    x0, y0, x1, y1 = within
    return np.asarray((x >= x0) & (x <= x1) & (y >= y0) & (y <= y1), dtype=bool)


def mjcf_focus(scene: Any) -> Heightfield | tuple[float, float, float, float] | None:
    """Where a scene's MJCF rock geoms come from: the focus heightfield of a level-of-detail
    scene, the focus square of a two-level rock population, else anywhere (``None``)."""
    if scene.outer is not None:
        return scene.heightfield
    levels = scene.provenance.extra.get("rocks", {}).get("levels")
    return tuple(levels["focus_bounds_xy_m"]) if levels else None


def rock_notes(
    hf: Heightfield, craters: CraterTable, cfg: RockConfig, rocks: RockTable
) -> list[str]:
    """Human-readable rules applied by the rock stage (for the manifest)."""
    notes = [
        f"rocks: diameters {cfg.d_min_m:g}-{cfg.d_max_m:g} m sampled (rocks below d_min_m are "
        f"not modelled; F_k(d_min) - F_k(d_max) = "
        f"{float(cumulative_area_fraction(cfg.d_min_m, k=cfg.k) - cumulative_area_fraction(cfg.d_max_m, k=cfg.k)):.4g} "  # noqa: E501
        f"of the area at k = {cfg.k:g})",
        f"rocks: none placed where the slope exceeds {cfg.max_slope_deg:g} deg; tilt clamped to "
        f"{cfg.max_tilt_deg:g} deg from vertical",
    ]
    if not FITTED_K_RANGE[0] <= cfg.k <= FITTED_K_RANGE[1]:
        notes.append(f"rocks: k = {cfg.k:g} is outside the fitted range {list(FITTED_K_RANGE)}")
    if cfg.placement == "ejecta" and len(craters) == 0:
        notes.append("rocks: placement 'ejecta' with no craters: uniform placement")
    sel = mjcf_rock_selection(rocks, cfg)
    n_big = int((rocks.diameter_m >= cfg.mjcf_min_diameter_m).sum())
    region = ""
    if cfg.mjcf_region_xy_m is not None:
        region = (f" within {cfg.mjcf_region_radius_m:g} m of "
                  f"({cfg.mjcf_region_xy_m[0]:g}, {cfg.mjcf_region_xy_m[1]:g})")
    smallest = float(rocks.diameter_m[sel].min()) if len(sel) else float("nan")
    verb = "baked into the hfield as bumps" if cfg.mjcf_small_rocks == "bake" else "dropped"
    notes.append(
        f"rocks/mjcf: rocks >= {cfg.mjcf_min_diameter_m:g} m{region}, at most "
        f"{cfg.mjcf_max_rocks} (largest first), become convex mesh geoms: {len(sel)} of "
        f"{n_big} rocks >= {cfg.mjcf_min_diameter_m:g} m (smallest exported "
        f"{smallest:.3g} m); the other {len(rocks) - len(sel)} rocks are {verb} in MJCF "
        "(all rocks are in USD and the catalogue)"
    )
    return notes


def rock_summary(
    hf: Heightfield, cfg: RockConfig, rocks: RockTable, prototypes: tuple[Any, ...]
) -> dict[str, Any]:
    """JSON-serialisable summary values of the rock stage."""
    area = float(hf.area_m2)
    covered = float(np.sum(np.pi * rocks.diameter_m**2 / 4.0)) / area if area > 0 else 0.0
    return {
        "count": len(rocks),
        "expected_count_at_k": round(expected_count(area, k=cfg.k, d_min_m=cfg.d_min_m,
                                               d_max_m=cfg.d_max_m), 3),
        "area_fraction": round(covered, 6),
        "max_diameter_m": round(float(rocks.diameter_m.max()), 4) if len(rocks) else 0.0,
        "prototypes": len(prototypes),
        "collision": cfg.collision,
        "mjcf_rocks": len(mjcf_rock_selection(rocks, cfg)),
    }


def level_summary(levels: RockLevels, rocks: RockTable) -> dict[str, Any]:
    """The manifest's account of a two-level rock population: the focus square, the cut-off
    outside it (and whether the budget raised it), expected and placed counts."""
    assert levels.focus_bounds_xy_m is not None
    x, y = rocks.position_xyz_m[:, 0], rocks.position_xyz_m[:, 1]
    inside = int(np.count_nonzero(inside_focus(levels.focus_bounds_xy_m, x, y)))
    return {
        "focus_bounds_xy_m": [round(float(v), 6) for v in levels.focus_bounds_xy_m],
        "outer_d_min_m": levels.outer_d_min_m,
        "outer_d_min_raised": levels.raised,
        "focus_count": inside,
        "outer_count": len(rocks) - inside,
        "expected_focus": round(levels.focus_expected, 1),
        "expected_outer": round(levels.outer_expected, 1),
    }
