"""Seeded crater populations (:doc:`/science/craters`).

The catalogue holds the *recognisable* craters of a surface: those whose relief has not been
degraded below the recognisability limit ``s <= S_ERASE`` (see :mod:`.morphology`). Their
cumulative density follows ``min(production isochron, equilibrium)`` at every diameter, the
density that crater counters see on old surfaces (Hartmann 1984), with the degradation states
of a steady-state population: young craters fresh, older ones shallower.

Algorithm (all vectorised):

1. Tabulate the production function of a surface of age ``T`` on a fine log-D grid over
   [``d_min_m``, ``d_max_m``]; the mass of each cell is ``N(>=D_i) - N(>=D_i+1)``.
2. Equilibrium (Hartmann 1984): per cell, the recognisable mass is ``min(production,
   equilibrium)`` (a *differential* cap, so the cumulative density never exceeds equilibrium).
   Equivalently, a crater of size D stays recognisable while fewer than ``N1_eq(D) = N1(T) *
   mass_eq / mass_prod`` craters >= 1 km per km^2 (the crater-count clock) have formed since
   it did; for sizes below equilibrium ``N1_eq > N1(T)``.
3. Each cell's mass is multiplied by the area of the scene grown by the crater's footprint
   reach (``ejecta_reach * R``) so craters centred outside whose ejecta or rim crosses the edge
   are included; the count is ``Poisson(sum)``.
4. Diameters: cell by inverse CDF, then the exact local power law inside the cell.
5. Formation ages, uniform in the crater-count clock: ``N1(tau) = u * min(N1(T), N1_eq(D))``
   (the PF shape is time-invariant).
6. Degradation (topographic diffusion, ``s = sqrt(2 K) / R`` with ``K`` the accumulated
   diffusivity-time): impact-driven, ``K_imp = (S_ERASE R)^2 / 2 * N1(tau) / N1_eq(D)``, so a
   crater reaches the limit exactly when its size reaches equilibrium (a diffusivity growing
   about linearly with D, as found for the Moon by Fassett & Thomson 2014); plus an optional
   background ``kappa_bg * tau`` (``diffusivity_m2_per_myr``, aeolian infill, default 0),
   which removes small craters faster and lowers their density *below* equilibrium, as
   observed on parts of Mars. Craters beyond ``S_ERASE`` are dropped (``degraded_away``: 0
   unless a background diffusivity is set).
7. Positions uniform in the grown box (corners beyond the reach rejected), optional
   ellipticity; resurfacing events.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

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
    """Tabulated recognisable crater density of a surface on log-spaced diameter cells.

    Attributes
    ----------
    edges_m : ndarray of shape (n + 1,)
        Cell edges (in m).
    production_cum_per_km2 : ndarray of shape (n + 1,)
        Production isochron N(>=D) at the edges (per km^2).
    visible_mass_per_km2 : ndarray of shape (n,)
        Recognisable craters per km^2 in each cell (``min(production, equilibrium)``).
    n1_eq_per_km2 : ndarray of shape (n,)
        Crater-count clock ``N1`` (craters >= 1 km per km^2 formed since) at which a crater of
        the cell becomes unrecognisable; ``inf`` without an equilibrium.
    age_cap_ga : ndarray of shape (n,)
        Oldest recognisable formation age in each cell (``min(T, t_eq)``) (in Ga).
    """

    edges_m: FloatArray
    production_cum_per_km2: FloatArray
    visible_mass_per_km2: FloatArray
    n1_eq_per_km2: FloatArray
    age_cap_ga: FloatArray


def size_distribution(config: CraterConfig, *, n_cells: int = _N_CELLS) -> SizeDistribution:
    """Tabulate the recognisable crater density of ``config``'s surface."""
    edges = np.geomspace(config.d_min_m, config.d_max_m, n_cells + 1)
    n1_t = float(n1_per_km2(config.age_ga, system=config.system))
    cum = production_shape(edges, system=config.system) * n1_t
    mass = cum[:-1] - cum[1:]
    cap = np.full(n_cells, float(config.age_ga))
    n1_eq = np.full(n_cells, np.inf)
    if config.equilibrium == "hartmann-1984":
        # the cumulative cap V(D) = min(PF(>=D), EQ(>=D)); a differential cap (min of the cell
        # masses) would fall up to ~20 % below it above the crossover, where the PF is steeper
        eq = equilibrium_density_per_km2(edges)
        vis = np.minimum(cum, eq)
        vis_mass = np.minimum(vis[:-1] - vis[1:], mass)
        frac = np.divide(vis_mass, mass, out=np.ones_like(mass), where=mass > 0)
        mid = np.sqrt(edges[:-1] * edges[1:])
        to_eq = (equilibrium_density_per_km2(mid)
                 / (production_shape(mid, system=config.system) * n1_t))
        capped = frac < 1.0 - 1e-12
        # lifetime on the crater-count clock: the recognisable fraction of the production for
        # capped cells; the time for the isochron to reach equilibrium (>= T) otherwise
        n1_eq = n1_t * np.where(capped, frac, np.maximum(to_eq, 1.0))
        cap = np.where(capped, age_from_n1_ga(np.minimum(n1_eq, n1_t), system=config.system),
                       cap)
        mass = vis_mass
    return SizeDistribution(edges, cum, mass, n1_eq, cap)


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
    config: CraterConfig, fam: ProfileFamily, n1_eq: FloatArray
) -> Callable[[FloatArray, FloatArray, FloatArray], FloatArray]:
    def relief(d_m: FloatArray, formed_ga: FloatArray, at_ga: FloatArray) -> FloatArray:
        state = fam.state_of_s(_s_of(config, d_m, n1_eq, formed_ga, at_ga))
        return np.asarray(
            d_m * np.interp(state, np.arange(fam.s.size), fam.depth_over_d + fam.rim_over_d),
            dtype=np.float64,
        )

    return relief


def _s_of(
    config: CraterConfig,
    d_m: FloatArray,
    n1_eq: FloatArray,
    formed_ga: FloatArray,
    at_ga: FloatArray | float = 0.0,
) -> FloatArray:
    """Diffusion length over radius, ``sqrt(2 K) / R``, of craters formed ``formed_ga`` ago,
    seen ``at_ga`` ago (0: today).

    ``2 K / R^2 = S_ERASE^2 * dN1 / N1_eq(D) + 2 kappa_bg dt / R^2``: the impact-driven part
    runs on the crater-count clock ``dN1 = N1(formed) - N1(at)`` and reaches ``S_ERASE`` when
    the crater's size class reaches equilibrium; the background part on time.
    """
    if config.degradation == "none":
        return np.zeros_like(d_m)
    radius = d_m / 2.0
    at = np.minimum(np.asarray(at_ga, dtype=np.float64), formed_ga)
    dn1 = n1_per_km2(formed_ga, system=config.system) - n1_per_km2(at, system=config.system)
    with np.errstate(divide="ignore"):
        s2 = S_ERASE**2 * np.maximum(dn1, 0.0) / n1_eq
    s2 = s2 + 2.0 * config.diffusivity_m2_per_myr * (formed_ga - at) * 1e3 / radius**2
    return np.asarray(np.sqrt(s2), dtype=np.float64)


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

    Diameters follow the production function of the surface age ``config.age_ga``, capped at
    the equilibrium density; centres are uniform over a footprint grown by the largest
    crater, so craters reach in from outside (:doc:`/science/craters`). Stamp the table into
    a terrain with :func:`stamp_craters`; :func:`marsscene.build_scene` does both.

    Parameters
    ----------
    bounds_xy_m : tuple of float
        Scene footprint ``(x_min, y_min, x_max, y_max)`` (in m).
    config : CraterConfig
        Age, diameter range, chronology system, profile, degradation and resurfacing.
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
        Expected, sampled, resurfaced, degraded-away and kept counts (for the manifest).

    Examples
    --------
    >>> import numpy as np
    >>> from marsscene.craters import CraterConfig, sample_craters, stamp_craters
    >>> cfg = CraterConfig(d_min_m=5.0, d_max_m=50.0)
    >>> table, stats = sample_craters((0, 0, 100, 100), cfg, rng=np.random.default_rng(1))
    >>> len(table) == stats.kept
    True
    >>> bool(table.diameter_m.min() >= 5.0), table.center_xy_m.shape == (len(table), 2)
    (True, True)

    Stamped into flat ground 100 m x 100 m (1 m posts), the craters dig below it:

    >>> from marsscene.terrain import Heightfield
    >>> hf = Heightfield(np.zeros((101, 101), np.float32), cell_size_m=1.0)
    >>> bool(stamp_craters(hf, table).z_m.min() < 0.0)
    True
    """
    x0, y0, x1, y1 = (float(v) for v in bounds_xy_m)
    width, height = x1 - x0, y1 - y0
    dist = size_distribution(config)
    cell, diameter, age, ratio, azimuth = _draw_sizes_ages(dist, config, width, height, rng)
    n = diameter.size
    g = config.ejecta_reach * diameter / 2.0 / np.sqrt(config.axis_ratio_min)
    cx = x0 - g + rng.random(n) * (width + 2 * g)
    cy = y0 - g + rng.random(n) * (height + 2 * g)
    ddx = np.maximum(np.maximum(x0 - cx, cx - x1), 0.0)
    ddy = np.maximum(np.maximum(y0 - cy, cy - y1), 0.0)
    keep = ddx**2 + ddy**2 <= g**2
    sampled = int(keep.sum())
    centers = np.stack([cx, cy], axis=1)
    n1_eq = dist.n1_eq_per_km2[cell]
    fam = profile_family(**config.profile_kwargs())
    alive = _not_resurfaced(config, fam, centers, diameter, age, n1_eq, rng, heightfield,
                            origin_lonlat_deg, grid_convergence_deg)
    n_resurfaced = int((keep & ~alive).sum())
    keep &= alive
    s = _s_of(config, diameter, n1_eq, age)
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
        expected_in_scene=float((dist.visible_mass_per_km2 * width * height / 1e6).sum()),
        sampled=sampled,
        resurfaced=n_resurfaced,
        degraded_away=n_degraded,
        kept=len(table),
    )
    return table, stats


def _draw_sizes_ages(dist: Any, config: CraterConfig, width: float, height: float,
                     rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Poisson count over the footprint grown by each size bin's ejecta reach, then per crater
    its size bin, diameter (exact local power law in the bin), age, axis ratio and azimuth."""
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
    n1_cap = np.minimum(dist.n1_eq_per_km2[cell], n1_per_km2(config.age_ga, system=config.system))
    age = age_from_n1_ga(rng.random(n) * n1_cap, system=config.system)
    if config.axis_ratio_min < 1.0:
        ratio = rng.uniform(config.axis_ratio_min, 1.0, n)
        azimuth = rng.uniform(0.0, 180.0, n)
    else:
        ratio, azimuth = np.ones(n), np.zeros(n)
    return cell, diameter, age, ratio, azimuth


def _not_resurfaced(config: CraterConfig, fam: Any, centers: np.ndarray, diameter: np.ndarray,
                    age: np.ndarray, n1_eq: np.ndarray, rng: np.random.Generator,
                    heightfield: Heightfield | None, origin_lonlat_deg: Any,
                    grid_convergence_deg: float) -> np.ndarray:
    """Craters no resurfacing event erased (all, without events)."""
    if not config.resurfacing:
        return np.ones(diameter.size, dtype=bool)
    weights = [
        mask_weights(ev, centers, heightfield=heightfield, origin_lonlat_deg=origin_lonlat_deg,
                     grid_convergence_deg=grid_convergence_deg)
        for ev in config.resurfacing
    ]
    return np.asarray(erase_by_events(diameter, age, weights, config.resurfacing,
                                      relief_at=_relief_fn(config, fam, n1_eq), rng=rng))
