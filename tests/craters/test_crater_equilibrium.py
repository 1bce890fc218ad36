"""Recognisable craters follow min(production, equilibrium) with steady-state degradation states
(issue 13 part 2; docs/science/craters.md)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from marsscene.craters import CraterConfig, profile_family, sample_craters
from marsscene.craters.functions import (
    equilibrium_density_per_km2,
    n1_per_km2,
    production_shape,
)
from marsscene.craters.morphology import S_ERASE

SIDE_M = 1000.0
D_MAX_M = 128.0
D_TEST_M = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0)


def _expected_cum_per_km2(cfg: CraterConfig, d_m: float) -> float:
    """min(PF, EQ) on [d_m, D_MAX_M): N(>=d) - N(>=D_max) of the recognisable population."""
    d = np.array([d_m, D_MAX_M])
    pf = production_shape(d, system=cfg.system) * n1_per_km2(cfg.age_ga, system=cfg.system)
    v = np.minimum(pf, equilibrium_density_per_km2(d))
    return float(v[0] - v[1])


@pytest.mark.parametrize("age_ga", [0.1, 1.0, 3.5])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_recognisable_density_follows_min_of_production_and_equilibrium(
    age_ga: float, seed: int
) -> None:
    cfg = CraterConfig(d_min_m=1.0, d_max_m=D_MAX_M, age_ga=age_ga)
    table, st = sample_craters((0.0, 0.0, SIDE_M, SIDE_M), cfg, rng=np.random.default_rng(seed))
    assert st.degraded_away == 0  # the catalogue *is* the recognisable population
    c = table.center_xy_m
    inside = (c >= 0.0).all(axis=1) & (c <= SIDE_M).all(axis=1)
    d = table.diameter_m[inside]
    for d_m in D_TEST_M:
        mu = _expected_cum_per_km2(cfg, d_m) * SIDE_M**2 / 1e6
        lo, hi = stats.poisson.ppf([5e-4, 1 - 5e-4], mu)
        n = int((d >= d_m).sum())
        assert 0.9 * lo <= n <= 1.1 * hi + 1, (age_ga, d_m, n, mu)


def test_old_surface_keeps_equilibrium_density_at_small_sizes() -> None:
    """The regression of issue 13: at 3.5 Ga, D >= 1 m held ~25 % of equilibrium."""
    cfg = CraterConfig(system="hartmann-daubar-2016", d_min_m=1.0, d_max_m=D_MAX_M, age_ga=3.5)
    table, _ = sample_craters((0.0, 0.0, SIDE_M, SIDE_M), cfg, rng=np.random.default_rng(7))
    eq = _expected_cum_per_km2(cfg, 1.0)
    assert len(table) / (SIDE_M**2 / 1e6) > 0.95 * eq  # grown area: centres outside count too


def _recovered_s(cfg: CraterConfig, depth_m: np.ndarray, d_m: np.ndarray) -> np.ndarray:
    fam = profile_family(**cfg.profile_kwargs())
    return np.asarray(fam.s_of_state(fam.state_of_depth(depth_m / d_m)))


@pytest.mark.parametrize("age_ga", [1.0, 3.5])
def test_depth_distribution_is_the_steady_state_of_the_degradation_model(age_ga: float) -> None:
    """Sizes at equilibrium: formation on the crater-count clock is uniform over the lifetime
    and s^2 grows linearly with it, so (s / S_ERASE)^2 ~ U(0, 1); the d/D distribution is its
    image under the profile family's depth(s)."""
    cfg = CraterConfig(d_min_m=1.0, d_max_m=8.0, age_ga=age_ga)  # all below the crossover
    table, _ = sample_craters((0.0, 0.0, 400.0, 400.0), cfg, rng=np.random.default_rng(11))
    s = _recovered_s(cfg, table.depth_m, table.diameter_m)
    u = (s / S_ERASE) ** 2
    assert u.max() <= 1.0 + 1e-6
    assert stats.kstest(u, "uniform").pvalue > 1e-3
    # and it is not the uniform-in-time answer of some other model: fresh craters are rare
    dd = table.depth_m / table.diameter_m
    fam = profile_family(**cfg.profile_kwargs())
    fresh = fam.depth_over_d[0]
    assert 0.05 < float(np.mean(dd > 0.9 * fresh)) < 0.2


def test_background_diffusivity_lowers_small_craters_below_equilibrium() -> None:
    """An aeolian background kappa removes small craters faster (documented Mars behaviour);
    every kept crater is still recognisable (s <= S_ERASE)."""
    base = CraterConfig(d_min_m=1.0, d_max_m=D_MAX_M, age_ga=3.5)
    windy = CraterConfig(d_min_m=1.0, d_max_m=D_MAX_M, age_ga=3.5, diffusivity_m2_per_myr=0.01)
    box = (0.0, 0.0, 500.0, 500.0)
    a, _ = sample_craters(box, base, rng=np.random.default_rng(5))
    b, st = sample_craters(box, windy, rng=np.random.default_rng(5))
    assert st.degraded_away > 0 and len(b) < 0.8 * len(a)
    small = lambda t: int((t.diameter_m < 4.0).sum())  # noqa: E731
    big = lambda t: int((t.diameter_m >= 32.0).sum())  # noqa: E731
    assert small(b) < 0.7 * small(a) and big(b) >= 0.8 * big(a)
    s = _recovered_s(windy, b.depth_m, b.diameter_m)
    assert s.max() <= S_ERASE * (1 + 1e-6)
    fam = profile_family(**windy.profile_kwargs())
    limit = fam.recognisable_depth_over_d()
    assert 0.25 < limit / fam.depth_over_d[0] < 0.4  # about a third of the fresh floor depth
    assert (b.depth_m / b.diameter_m).min() >= limit * (1 - 1e-6)
