"""Two-level level-of-detail terrain: a full-resolution focus square in a coarse footprint.

Level 0 is the **focus square** (``terrain.focus_size_m`` around ``terrain.focus_xy_m``) at
``terrain.focus_post_m`` (0.25 m); level 1 is the **outer terrain** over the whole footprint at
``terrain.post_m``. The focus square is snapped to the coarse posts, so every coarse post on or
inside it coincides with a fine post.

* **Independence.** The focus terrain is built in tiles (:mod:`marsscene.terrain.tiles`): a
  cubic interpolation of the coarse grid (which carries every wavelength it resolves) plus
  pointwise fractal detail and the scene's craters, so a tile built alone equals the same tile
  of a full build (tested) and the focus agrees with the coarse terrain around it.
* **Seams.** :func:`taper_detail` fades the fine terrain's sub-coarse-post detail to 0 over
  :data:`TAPER_POSTS` coarse posts inside the focus border, so the fine border posts lie on the
  straight segments between coarse border posts. :func:`stitch` then sets the coarse posts on and
  inside the focus square to the fine heights and bends the outer terrain onto the focus border
  over ``terrain.lod_blend_m`` outside it (a smoothstep falloff of the border mismatch, carried
  outward from the nearest border post). The two meshes then share their border exactly.
* **Craters.** One table for the footprint: :func:`merge_craters` keeps the focus sample's
  craters (every crater whose reach touches the focus) and the outer sample's craters that do
  not reach it, so craters straddling the border are the same in both grids.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["TAPER_POSTS", "FocusPlan", "OuterTerrain", "concat_tables", "lod_summary",
           "merge_craters",
           "plan_focus", "reaches_box", "stitch", "taper_detail"]

#: Width of the sub-post detail taper inside the focus border, in coarse posts.
TAPER_POSTS = 8


@dataclass(frozen=True, slots=True)
class FocusPlan:
    """The focus square on the coarse grid: ``cells`` coarse cells from post ``(row0, col0)``."""

    bounds_xy_m: tuple[float, float, float, float]
    fine_post_m: float
    coarse_post_m: float
    row0: int
    col0: int
    cells: int

    @property
    def ratio(self) -> int:
        """Fine posts per coarse post."""
        return round(self.coarse_post_m / self.fine_post_m)

    def contains(self, x: Any, y: Any) -> NDArray[np.bool_]:
        x0, y0, x1, y1 = self.bounds_xy_m
        xa, ya = np.asarray(x), np.asarray(y)
        return (xa >= x0) & (xa <= x1) & (ya >= y0) & (ya <= y1)


@dataclass(frozen=True, eq=False)
class OuterTerrain:
    """The coarse terrain of a level-of-detail scene (the whole footprint, stitched to the
    focus square, which :attr:`marsscene.Scene.heightfield` holds at full resolution)."""

    heightfield: Heightfield
    focus_bounds_xy_m: tuple[float, float, float, float]
    level: int = 1


def plan_focus(coarse: Heightfield, *, center_xy_m: tuple[float, float] | None, size_m: float,
               fine_post_m: float) -> FocusPlan:
    """Snap the focus square to ``coarse``'s posts; one-line errors for impossible plans."""
    pc = coarse.cell_size_m
    ratio = round(pc / fine_post_m)
    if ratio < 1 or abs(ratio * fine_post_m - pc) > 1e-9 * pc:
        raise ConfigError(f"terrain.post_m = {pc:g} must be a whole multiple of "
                          f"terrain.focus_post_m = {fine_post_m:g} for level-of-detail terrain")
    cx, cy = center_xy_m if center_xy_m is not None else (0.0, 0.0)
    cells = max(round(size_m / pc), 2 * TAPER_POSTS)
    ox, oy = coarse.origin_xy_m
    col0 = round((cx - cells * pc / 2.0 - ox) / pc)
    row0 = round((cy - cells * pc / 2.0 - oy) / pc)
    rows, cols = coarse.shape
    if min(row0, col0) < 1 or row0 + cells > rows - 2 or col0 + cells > cols - 2:
        x0, y0, x1, y1 = coarse.bounds_xy_m
        raise ConfigError(f"the {cells * pc:g} m focus square around ({cx:g}, {cy:g}) m must lie "
                          f"inside the footprint [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m: move "
                          "--focus-xy or shrink terrain.focus_size_m (--focus-size-m)")
    x0, y0 = ox + col0 * pc, oy + row0 * pc
    side = cells * pc
    return FocusPlan((x0, y0, x0 + side, y0 + side), fine_post_m, pc, row0, col0, cells)


def _smoothstep(t: NDArray[np.float64]) -> NDArray[np.float64]:
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _lerp_weights(n_fine: int, k: int, n_coarse: int) -> tuple[NDArray[np.int64], NDArray[Any]]:
    i = np.arange(n_fine)
    i0 = np.minimum(i // k, n_coarse - 2)
    return i0, ((i - i0 * k) / k).astype(np.float32)


def coarse_surface(fine: Heightfield, k: int) -> NDArray[np.float32]:
    """The bilinear surface through every ``k``-th post of ``fine`` (the coarse posts)."""
    zc = fine.z_m[::k, ::k]
    r0, fr = _lerp_weights(fine.shape[0], k, zc.shape[0])
    c0, fc = _lerp_weights(fine.shape[1], k, zc.shape[1])
    rows = zc[r0] * (1 - fr)[:, None] + zc[r0 + 1] * fr[:, None]
    return np.asarray(rows[:, c0] * (1 - fc) + rows[:, c0 + 1] * fc, dtype=np.float32)


def taper_detail(fine: Heightfield, plan: FocusPlan, *,
                 origin_posts: tuple[int, int] = (0, 0)) -> Heightfield:
    """Fade the detail between coarse posts to 0 at the focus border (coarse posts unchanged).

    ``fine`` is the whole focus grid or a window of it whose first post is focus post
    ``origin_posts`` (a whole number of coarse cells from the focus corner).
    """
    k = plan.ratio
    lin = coarse_surface(fine, k)
    rows, cols = fine.shape
    n = plan.cells * k + 1  # fine posts per focus side
    r = origin_posts[0] + np.arange(rows)
    c = origin_posts[1] + np.arange(cols)
    d_r = np.minimum(r, n - 1 - r).astype(np.float64)
    d_c = np.minimum(c, n - 1 - c).astype(np.float64)
    span = TAPER_POSTS * k
    w_r = _smoothstep(d_r / span).astype(np.float32)
    w_c = _smoothstep(d_c / span).astype(np.float32)
    w = np.minimum(w_r[:, None], w_c[None, :])
    z = lin + w * (fine.z_m - lin)
    z[::k, ::k] = fine.z_m[::k, ::k]  # exact at the coarse posts
    return fine.with_z(z)


def stitch(coarse: Heightfield, fine: Heightfield, plan: FocusPlan, *,
           blend_m: float) -> Heightfield:
    """Coarse terrain equal to ``fine`` on the focus posts, bent onto it over ``blend_m``."""
    k, n, pc = plan.ratio, plan.cells, plan.coarse_post_m
    r0, c0 = plan.row0, plan.col0
    z = coarse.z_m.copy()
    inner = fine.z_m[::k, ::k]
    delta = inner - z[r0:r0 + n + 1, c0:c0 + n + 1]
    b = int(np.ceil(blend_m / pc))
    rows, cols = z.shape
    rr = np.arange(max(r0 - b, 0), min(r0 + n + b + 1, rows))
    cc = np.arange(max(c0 - b, 0), min(c0 + n + b + 1, cols))
    dr = np.maximum(np.maximum(r0 - rr, rr - (r0 + n)), 0) * pc
    dc = np.maximum(np.maximum(c0 - cc, cc - (c0 + n)), 0) * pc
    dist = np.hypot(dr[:, None], dc[None, :])
    w = 1.0 - _smoothstep(dist / blend_m) if blend_m > 0 else (dist == 0).astype(np.float64)
    near = delta[np.clip(rr, r0, r0 + n) - r0][:, np.clip(cc, c0, c0 + n) - c0]
    z[rr[0]:rr[-1] + 1, cc[0]:cc[-1] + 1] += (near * w).astype(np.float32)
    z[r0:r0 + n + 1, c0:c0 + n + 1] = inner
    return coarse.with_z(z)


def reaches_box(centers_xy_m: NDArray[np.float64], reach_m: NDArray[np.float64],
                bounds_xy_m: tuple[float, float, float, float]) -> NDArray[np.bool_]:
    """True where a disc of radius ``reach_m`` around a centre touches the box."""
    x0, y0, x1, y1 = bounds_xy_m
    cx, cy = centers_xy_m[:, 0], centers_xy_m[:, 1]
    ddx = np.maximum(np.maximum(x0 - cx, cx - x1), 0.0)
    ddy = np.maximum(np.maximum(y0 - cy, cy - y1), 0.0)
    return np.asarray(ddx**2 + ddy**2 <= reach_m**2)


def concat_tables(*tables: Any) -> Any:
    """Row-concatenate column tables of the same dataclass type (``None`` columns stay
    ``None`` only when every table's is)."""
    first = tables[0]
    out: dict[str, Any] = {}
    for f in dataclasses.fields(first):
        cols = [getattr(t, f.name) for t in tables]
        if all(v is None for v in cols):
            out[f.name] = None
            continue
        out[f.name] = np.concatenate([np.asarray(v) if v is not None else _fill(f.name, len(t))
                                      for v, t in zip(cols, tables, strict=True)])
    return type(first)(**out)


def _fill(name: str, n: int) -> NDArray[np.float64]:
    return np.ones(n) if name == "axis_ratio" else np.zeros(n)


def merge_craters(focus: Any, outer: Any, bounds_xy_m: tuple[float, float, float, float], *,
                  ejecta_reach: float, axis_ratio_min: float) -> Any:
    """One crater table for the footprint: ``focus`` (sampled over the focus square) plus the
    ``outer`` craters that do not reach it, oldest first (the stamping order).

    The reach is the population sampler's own ``ejecta_reach * D / 2 / sqrt(axis_ratio_min)``,
    so the two samples cover disjoint sets of craters and their union is one population.
    """
    reach = ejecta_reach * outer.diameter_m / 2.0 / np.sqrt(axis_ratio_min)
    kept = outer.take(~reaches_box(outer.center_xy_m, reach, bounds_xy_m))
    table = concat_tables(focus, kept)
    order = np.argsort(-table.age_ga, kind="stable")
    return table.take(order)


def lod_summary(fine: Heightfield, outer: OuterTerrain, tcfg: Any, *, tiles: int, tile_m: float,
                detail_rms_m: float) -> dict[str, Any]:
    """Manifest summary of a level-of-detail terrain (``tiles``: focus tiles per side)."""
    coarse = outer.heightfield
    return {
        "focus_tiles": [tiles, tiles],
        "focus_tile_m": round(tile_m, 6),
        "focus_detail_rms_m": round(detail_rms_m, 6),
        "levels": 2,
        "footprint_bounds_xy_m": [round(v, 6) for v in coarse.bounds_xy_m],
        "focus_bounds_xy_m": [round(v, 6) for v in outer.focus_bounds_xy_m],
        "focus_post_m": fine.cell_size_m,
        "focus_posts": int(fine.z_m.size),
        "outer_post_m": coarse.cell_size_m,
        "outer_posts": int(coarse.z_m.size),
        "blend_m": tcfg.lod_blend_m,
        "taper_m": TAPER_POSTS * coarse.cell_size_m,
    }
