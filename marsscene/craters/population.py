"""Seeded crater populations (SCIENCE.md sections 2.5-2.6, 4.1).

Algorithm (all vectorised):

1. Tabulate the production function of a surface of age ``T`` on a fine log-D grid over
   [``d_min_m``, ``d_max_m``]; the mass of each cell is ``N(>=D_i) - N(>=D_i+1)``.
2. Equilibrium cap (Hartmann 1984): per cell, the visible mass is ``min(production,
   equilibrium)`` (a *differential* cap, so the cumulative density never exceeds equilibrium);
   equivalently a crater of size D is erased when older than its equilibrium age
   ``t_eq(D)`` with ``N1(t_eq) = N1(T) * mass_eq / mass_prod``.
3. Each cell's mass is multiplied by the area of the scene grown by the crater's footprint
   reach (``ejecta_reach * R``) so craters centred outside whose ejecta or rim crosses the edge
   are included; the count is ``Poisson(sum)``.
4. Diameters: cell by inverse CDF, then the exact local power law inside the cell.
5. Formation ages: ``tau = N1^-1(u * N1(min(T, t_eq(D))))`` (the PF shape is time-invariant).
6. Positions uniform in the grown box (corners beyond the reach rejected), optional
   ellipticity; resurfacing events; degradation by diffusion for ``kappa * tau``; craters whose
   relief fell below ~25 % of fresh (``s > S_ERASE = 0.6``) are no longer recognisable and
   are dropped (counted as degraded away).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.craters.config import CraterConfig
from marsscene.craters.functions import (
    age_from_n1_ga,
    equilibrium_density_per_km2,
    n1_per_km2,
    production_shape,
)
from marsscene.craters.morphology import PROFILE_IDS, S_ERASE, ProfileFamily, profile_family
from marsscene.craters.resurfacing import erase_by_events, mask_weights
from marsscene.craters.table import CraterTable
from marsscene.errors import MemoryBudgetError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["PopulationStats", "SizeDistribution", "sample_craters", "size_distribution"]

FloatArray = NDArray[np.float64]
_N_CELLS = 2048
#: Largest expected number of sampled craters (memory plan: ~120 bytes per crater).
MAX_CRATERS = 5e6


@dataclass(frozen=True, eq=False)
class SizeDistribution:
    """Tabulated visible crater density of a surface on log-spaced diameter cells.

    Attributes
    ----------
    edges_m : ndarray of shape (n + 1,)
        Cell edges (in m).
    production_cum_per_km2 : ndarray of shape (n + 1,)
        Production isochron N(>=D) at the edges (per km^2).
    visible_mass_per_km2 : ndarray of shape (n,)
        Craters per km^2 in each cell after the equilibrium cap.
    age_cap_ga : ndarray of shape (n,)
        Oldest surviving formation age in each cell (``min(T, t_eq)``) (in Ga).
    """

    edges_m: FloatArray
    production_cum_per_km2: FloatArray
    visible_mass_per_km2: FloatArray
    age_cap_ga: FloatArray


def size_distribution(config: CraterConfig, *, n_cells: int = _N_CELLS) -> SizeDistribution:
    """Tabulate the (equilibrium-capped) crater density of ``config``'s surface."""
    edges = np.geomspace(config.d_min_m, config.d_max_m, n_cells + 1)
    n1_t = float(n1_per_km2(config.age_ga, system=config.system))
    cum = production_shape(edges, system=config.system) * n1_t
    mass = cum[:-1] - cum[1:]
    cap = np.full(n_cells, float(config.age_ga))
    if config.equilibrium == "hartmann-1984":
        eq = equilibrium_density_per_km2(edges)
        mass_eq = eq[:-1] - eq[1:]
        capped = mass_eq < mass
        frac = np.where(capped, mass_eq / np.where(mass > 0, mass, 1.0), 1.0)
        cap = np.where(capped, age_from_n1_ga(frac * n1_t, system=config.system), cap)
        mass = np.minimum(mass, mass_eq)
    return SizeDistribution(edges, cum, mass, cap)


@dataclass(frozen=True)
class PopulationStats:
    """Counts of one sampling run (for the manifest)."""

    expected_in_scene: float
    """Expected number of visible craters centred inside the scene (before resurfacing)."""
    sampled: int
    """Craters drawn over the grown area (after the equilibrium cap)."""
    resurfaced: int
    degraded_away: int
    kept: int


def _relief_fn(
    config: CraterConfig, fam: ProfileFamily, cap_ga: FloatArray
) -> Callable[[FloatArray, FloatArray], FloatArray]:
    def relief(d_m: FloatArray, elapsed_ga: FloatArray) -> FloatArray:
        state = fam.state_of_s(_s_of(config, d_m, elapsed_ga, cap_ga))
        return np.asarray(
            d_m * np.interp(state, np.arange(fam.s.size), fam.depth_over_d + fam.rim_over_d),
            dtype=np.float64,
        )

    return relief


def _s_of(
    config: CraterConfig, d_m: FloatArray, age_ga: FloatArray, cap_ga: FloatArray
) -> FloatArray:
    """Diffusion length over radius, ``sqrt(2 kappa tau) / R``.

    ``kappa = max(diffusivity_m2_per_myr, kappa_eq(D))``: for sizes capped at equilibrium,
    ``kappa_eq = (S_ERASE R)^2 / (2 t_eq(D))`` degrades a crater to the erased state exactly at its
    equilibrium age, so the cap acts by degradation rather than by sudden removal.
    """
    if config.degradation == "none":
        return np.zeros_like(d_m)
    radius = d_m / 2.0
    kappa = np.full(d_m.shape, config.diffusivity_m2_per_myr)
    if config.equilibrium != "none":
        capped = cap_ga < config.age_ga
        k_eq = (S_ERASE * radius) ** 2 / (2.0 * np.maximum(cap_ga, 1e-12) * 1e3)
        kappa = np.where(capped, np.maximum(kappa, k_eq), kappa)
    kappa_t = kappa * age_ga * 1e3  # m^2
    return np.asarray(np.sqrt(2.0 * kappa_t) / radius, dtype=np.float64)


def sample_craters(
    bounds_xy_m: tuple[float, float, float, float],
    config: CraterConfig,
    *,
    rng: np.random.Generator,
    heightfield: Heightfield | None = None,
    origin_lonlat_deg: tuple[float, float] | None = None,
    grid_convergence_deg: float = 0.0,
) -> tuple[CraterTable, PopulationStats]:
    """Sample a crater population over a scene footprint.

    Parameters
    ----------
    bounds_xy_m : tuple of float
        Scene footprint ``(x_min, y_min, x_max, y_max)`` (in m).
    config : CraterConfig
    rng : numpy.random.Generator
        The crater stage's stream.
    heightfield : Heightfield, optional
        Grid for raster resurfacing masks.
    origin_lonlat_deg : tuple, optional
        Scene origin for lon/lat resurfacing polygons.
    grid_convergence_deg : float
        Angle from true north to scene +y (polar stereographic DEMs).

    Returns
    -------
    table : CraterTable
        Rows in formation order (oldest first), the stamping order.
    stats : PopulationStats

    Examples
    --------
    >>> import numpy as np
    >>> cfg = CraterConfig(d_min_m=5.0, d_max_m=50.0)
    >>> table, stats = sample_craters((0, 0, 100, 100), cfg, rng=np.random.default_rng(1))
    >>> len(table) == stats.kept
    True
    """
    x0, y0, x1, y1 = (float(v) for v in bounds_xy_m)
    width, height = x1 - x0, y1 - y0
    dist = size_distribution(config)
    edges = dist.edges_m
    mid = np.sqrt(edges[:-1] * edges[1:])
    grow = config.ejecta_reach * mid / 2.0 / np.sqrt(config.axis_ratio_min)
    box_km2 = (width + 2 * grow) * (height + 2 * grow) / 1e6
    weight = dist.visible_mass_per_km2 * box_km2
    total = float(weight.sum())
    if total > MAX_CRATERS:
        raise MemoryBudgetError(
            f"the crater population would hold ~{total:.3g} craters (> {MAX_CRATERS:.0e}; "
            f"~{total * 120 / 1e9:.3g} GB while sampling); raise craters.d_min_m "
            f"(= {config.d_min_m!r}), enable craters.equilibrium or shrink the scene"
        )
    n = int(rng.poisson(total))
    cdf = np.cumsum(weight) / total if total > 0 else np.ones(weight.size)
    cell = np.minimum(np.searchsorted(cdf, rng.random(n), side="right"), mid.size - 1)
    # exact local power law inside the cell: N(>=D) = N_i (D / D_i)^k
    c_lo, c_hi = dist.production_cum_per_km2[cell], dist.production_cum_per_km2[cell + 1]
    d_lo, d_hi = edges[cell], edges[cell + 1]
    k = np.log(c_hi / c_lo) / np.log(d_hi / d_lo)
    v = rng.random(n)
    diameter = d_lo * ((c_lo - v * (c_lo - c_hi)) / c_lo) ** (1.0 / k)
    diameter = np.clip(diameter, d_lo, d_hi)
    cap = dist.age_cap_ga[cell]
    n1_cap = n1_per_km2(cap, system=config.system)
    age = age_from_n1_ga(rng.random(n) * n1_cap, system=config.system)
    if config.axis_ratio_min < 1.0:
        ratio = rng.uniform(config.axis_ratio_min, 1.0, n)
        azimuth = rng.uniform(0.0, 180.0, n)
    else:
        ratio, azimuth = np.ones(n), np.zeros(n)
    g = config.ejecta_reach * diameter / 2.0 / np.sqrt(config.axis_ratio_min)
    cx = x0 - g + rng.random(n) * (width + 2 * g)
    cy = y0 - g + rng.random(n) * (height + 2 * g)
    ddx = np.maximum(np.maximum(x0 - cx, cx - x1), 0.0)
    ddy = np.maximum(np.maximum(y0 - cy, cy - y1), 0.0)
    keep = ddx**2 + ddy**2 <= g**2
    centers = np.stack([cx, cy], axis=1)
    expected = float((dist.visible_mass_per_km2 * width * height / 1e6).sum())

    fam = profile_family(**config.profile_kwargs())
    if config.resurfacing:
        weights = [
            mask_weights(ev, centers, heightfield=heightfield, origin_lonlat_deg=origin_lonlat_deg,
                         grid_convergence_deg=grid_convergence_deg)
            for ev in config.resurfacing
        ]
        alive = erase_by_events(
            diameter, age, weights, config.resurfacing,
            relief_at=_relief_fn(config, fam, cap), rng=rng,
        )
    else:
        alive = np.ones(n, dtype=bool)
    n_resurfaced = int((keep & ~alive).sum())
    keep &= alive
    s = _s_of(config, diameter, age, cap)
    gone = s > S_ERASE * (1 + 1e-9)
    n_degraded = int((keep & gone).sum())
    keep &= ~gone
    idx = np.nonzero(keep)[0]
    idx = idx[np.argsort(-age[idx], kind="stable")]  # oldest first: stamping order
    state = fam.state_of_s(s[idx])
    rows = np.arange(fam.s.size)
    d_sel = diameter[idx]
    table = CraterTable(
        centers[idx],
        d_sel,
        d_sel * np.interp(state, rows, fam.depth_over_d),
        d_sel * np.interp(state, rows, fam.rim_over_d),
        age[idx],
        np.full(idx.size, PROFILE_IDS[config.profile], dtype=np.int64),
        ratio[idx],
        azimuth[idx],
    )
    stats = PopulationStats(
        expected_in_scene=expected,
        sampled=int(keep.size - (~(ddx**2 + ddy**2 <= g**2)).sum()),
        resurfaced=n_resurfaced,
        degraded_away=n_degraded,
        kept=len(table),
    )
    return table, stats
