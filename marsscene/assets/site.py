"""Site search and levelling for assets (pure, vectorised over the heightfield).

:func:`find_site` scores every candidate post by the terrain inside a square window as wide
as the asset's pad: the window's mean slope (the tilt of the pad before levelling) must stay
below ``max_slope_deg``, and the site with the smallest relief (RMS height about the window
mean, a roughness measure that also penalises tilt) wins. Windows are box filters
(:func:`scipy.ndimage.uniform_filter`) on a grid decimated to about a quarter of the pad width.
Candidates keep clear of the footprint edge (pad + blend), of the origin (the rover's start) and
of assets already placed.

:func:`level_site` sets the pad (the disc of ``pad_radius_m``) to the pad's mean height and
blends back to the terrain over ``blend_m`` with a smoothstep, so the asset's base sits on the
ground and the pad has no step.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from marsscene.assets.config import AssetConfig
from marsscene.assets.model import AssetModel, PlacedAsset
from marsscene.errors import ConfigError
from marsscene.rocks.table import RockTable
from marsscene.terrain.heightfield import Heightfield

__all__ = ["clear_rocks", "find_site", "level_site", "place_assets"]


def find_site(
    hf: Heightfield, pad_radius_m: float, *, max_slope_deg: float, clearance_m: float,
    avoid: list[tuple[float, float, float]] | None = None,
) -> tuple[float, float]:
    """The flattest suitable ``(x, y)`` for a pad of ``pad_radius_m``.

    ``avoid`` lists ``(x, y, radius)`` discs the pad must not overlap (the rover start, other
    assets); ``clearance_m`` is kept from the footprint edge. Raises :class:`ConfigError` when
    no site qualifies.
    """
    step = max(1, int(pad_radius_m / 2.0 / hf.cell_size_m))
    z = hf.z_m[::step, ::step].astype(np.float64)
    gy, gx = np.gradient(z, hf.cell_size_m * step)
    win = max(1, round(2.0 * pad_radius_m / (hf.cell_size_m * step))) | 1
    mean = ndimage.uniform_filter(z, win, mode="nearest")
    rough = np.sqrt(np.maximum(ndimage.uniform_filter(z * z, win, mode="nearest") - mean**2, 0))
    tilt = np.hypot(ndimage.uniform_filter(gx, win, mode="nearest"),
                    ndimage.uniform_filter(gy, win, mode="nearest"))
    x = hf.origin_xy_m[0] + np.arange(z.shape[1]) * hf.cell_size_m * step
    y = hf.origin_xy_m[1] + np.arange(z.shape[0]) * hf.cell_size_m * step
    x0, y0, x1, y1 = hf.bounds_xy_m
    edge = pad_radius_m + clearance_m
    ok = tilt <= np.tan(np.radians(max_slope_deg))
    ok &= ((x >= x0 + edge) & (x <= x1 - edge))[None, :] & ((y >= y0 + edge) & (y <= y1 - edge))[
        :, None]
    for ax, ay, ar in avoid or []:
        ok &= np.hypot(x[None, :] - ax, y[:, None] - ay) > ar + pad_radius_m
    if not ok.any():
        raise ConfigError(f"no site for an asset pad of radius {pad_radius_m:.1f} m with slopes "
                          f"below assets.max_slope_deg = {max_slope_deg:g} deg; give "
                          "assets.xy_m (CLI --asset-xy X Y) or raise max_slope_deg")
    cost = np.where(ok, rough, np.inf)
    r, c = np.unravel_index(int(np.argmin(cost)), cost.shape)  # first minimum: deterministic
    return float(x[c]), float(y[r])


def level_site(
    hf: Heightfield, xy_m: tuple[float, float], pad_radius_m: float, blend_m: float
) -> tuple[Heightfield, float]:
    """Level a pad at ``xy_m``: a new heightfield and the pad height (in m)."""
    rr, cc = hf.rowcol_of(xy_m[0], xy_m[1])
    reach = int(np.ceil((pad_radius_m + blend_m) / hf.cell_size_m)) + 1
    r0, r1 = max(0, int(rr) - reach), min(hf.shape[0], int(rr) + reach + 2)
    c0, c1 = max(0, int(cc) - reach), min(hf.shape[1], int(cc) + reach + 2)
    xs, ys = hf.xy_of(np.zeros(c1 - c0), np.arange(c0, c1))[0], hf.xy_of(np.arange(r0, r1), 0)[1]
    d = np.hypot(xs[None, :] - xy_m[0], ys[:, None] - xy_m[1])
    block = hf.z_m[r0:r1, c0:c1].astype(np.float64)
    inside = d <= pad_radius_m
    if not inside.any():
        raise ConfigError(f"asset at {xy_m} is outside the terrain footprint")
    base = float(block[inside].mean())
    t = np.clip((d - pad_radius_m) / blend_m, 0.0, 1.0)
    w = t * t * (3.0 - 2.0 * t)  # smoothstep: 0 on the pad, 1 at the blend's outer edge
    z = hf.z_m.copy()
    z[r0:r1, c0:c1] = (base * (1.0 - w) + block * w).astype(np.float32)
    return hf.with_z(z), float(np.float32(base))


def place_assets(
    hf: Heightfield, models: list[AssetModel], cfg: AssetConfig
) -> tuple[Heightfield, tuple[PlacedAsset, ...]]:
    """Place and level every asset (given points or searched sites, in order)."""
    placed: list[PlacedAsset] = []
    avoid = [(0.0, 0.0, cfg.keep_clear_m)]
    for i, model in enumerate(models):
        pad = model.radius_m + cfg.margin_m + hf.cell_size_m
        if cfg.xy_m is not None:
            xy = (float(cfg.xy_m[i][0]), float(cfg.xy_m[i][1]))
            if not bool(hf.contains(*xy)):
                raise ConfigError(f"assets.xy_m {list(xy)} is outside the terrain footprint "
                                  f"{[round(v, 1) for v in hf.bounds_xy_m]}")
        else:
            xy = find_site(hf, pad, max_slope_deg=cfg.max_slope_deg,
                           clearance_m=cfg.blend_m, avoid=avoid)
        hf, base = level_site(hf, xy, pad, cfg.blend_m)
        avoid.append((xy[0], xy[1], pad + cfg.blend_m))
        placed.append(PlacedAsset(model=model, xy_m=xy, base_z_m=base, pad_radius_m=pad))
    return hf, tuple(placed)


def clear_rocks(rocks: RockTable, placed: tuple[PlacedAsset, ...]) -> RockTable:
    """Rocks outside every asset's pad (rocks under a habitat are removed)."""
    keep = np.ones(len(rocks), dtype=bool)
    xy = rocks.position_xyz_m[:, :2]
    for a in placed:
        keep &= np.hypot(xy[:, 0] - a.xy_m[0], xy[:, 1] - a.xy_m[1]) > a.pad_radius_m
    return rocks.take(keep)
