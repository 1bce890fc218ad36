"""Seeded populations: KS tests, Poisson bounds, equilibrium cap, edges, determinism."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats

import marsscene.craters as mc
from marsscene.craters import CraterConfig, sample_craters
from marsscene.errors import ExtrapolationWarning

BOX_1KM = (-500.0, -500.0, 500.0, 500.0)


def _inside(table: mc.CraterTable, box: tuple[float, float, float, float]) -> np.ndarray:
    x, y = table.center_xy_m.T
    return (x >= box[0]) & (x <= box[2]) & (y >= box[1]) & (y <= box[3])


def _pure(**kw: object) -> CraterConfig:
    base = {"system": "ivanov-2001", "age_ga": 1.0, "d_min_m": 10.0, "d_max_m": 1000.0,
            "equilibrium": "none", "degradation": "none"}
    base.update(kw)
    return CraterConfig(**base)  # type: ignore[arg-type]


@pytest.fixture(autouse=True)
def _quiet() -> None:
    warnings.simplefilter("ignore", ExtrapolationWarning)


def test_expected_count_and_quantiles_match_science_reference() -> None:
    # Ivanov PF + CF, 1 Ga, D in [10 m, 1 km]: 2129.596 per km^2, median 12.6696 m
    table, st = sample_craters(BOX_1KM, _pure(), rng=np.random.default_rng(3))
    assert st.expected_in_scene == pytest.approx(2129.596, rel=1e-6)
    d = table.diameter_m[_inside(table, BOX_1KM)]
    q = np.quantile(d, [0.5, 0.9])
    assert q[0] == pytest.approx(12.6696, rel=0.01)
    assert q[1] == pytest.approx(21.2422, rel=0.03)


def _truncated_cdf(cfg: CraterConfig):  # type: ignore[no-untyped-def]
    def cdf(d: np.ndarray) -> np.ndarray:
        c = mc.cumulative_density_per_km2(d, age_ga=cfg.age_ga, system=cfg.system)
        c0, c1 = mc.cumulative_density_per_km2(
            [cfg.d_min_m, cfg.d_max_m], age_ga=cfg.age_ga, system=cfg.system)
        return (c0 - c) / (c0 - c1)

    return cdf


@pytest.mark.parametrize("system", ["ivanov-2001", "hartmann-daubar-2016"])
def test_ks_diameters_against_truncated_cdf(system: str) -> None:
    cfg = _pure(system=system, d_min_m=2.0 if system.startswith("h") else 10.0, d_max_m=300.0)
    box = (0.0, 0.0, 600.0, 600.0)
    table, _ = sample_craters(box, cfg, rng=np.random.default_rng(11))
    d = table.diameter_m[_inside(table, box)]
    assert d.size > 500
    assert d.min() >= cfg.d_min_m and d.max() <= cfg.d_max_m
    res = stats.kstest(d, _truncated_cdf(cfg))
    assert res.pvalue > 0.01


def test_poisson_counts_over_seeds() -> None:
    cfg = _pure(d_min_m=30.0)
    counts = []
    for seed in range(8):
        table, st = sample_craters(BOX_1KM, cfg, rng=np.random.default_rng(seed))
        counts.append(int(_inside(table, BOX_1KM).sum()))
    lam = st.expected_in_scene
    lo, hi = stats.poisson.ppf([0.0005, 0.9995], lam)
    assert all(lo <= c <= hi for c in counts), (counts, lam)
    # the mean of 8 draws: 4 sigma of the Poisson mean
    assert abs(np.mean(counts) - lam) < 4 * np.sqrt(lam / len(counts))


def test_formation_ages_follow_chronology() -> None:
    cfg = _pure(system="neukum-ivanov-2001", age_ga=3.5, d_min_m=20.0)
    table, _ = sample_craters(BOX_1KM, cfg, rng=np.random.default_rng(5))
    n1_t = mc.n1_per_km2(3.5)
    res = stats.kstest(table.age_ga, lambda t: mc.n1_per_km2(np.clip(t, 0, 3.5)) / n1_t)
    assert res.pvalue > 0.01
    assert np.all(np.diff(table.age_ga) <= 0)  # rows in formation order, oldest first


def test_equilibrium_cap_holds() -> None:
    cfg = CraterConfig(system="hartmann-daubar-2016", age_ga=3.5, d_min_m=1.0, d_max_m=300.0,
                       degradation="none")
    box = (0.0, 0.0, 300.0, 300.0)
    area_km2 = 0.09
    table, _ = sample_craters(box, cfg, rng=np.random.default_rng(2))
    d = np.sort(table.diameter_m[_inside(table, box)])
    for d_min in (1.0, 2.0, 5.0, 10.0, 30.0, 100.0):
        observed = (d >= d_min).sum()
        cap = area_km2 * float(mc.equilibrium_density_per_km2(d_min))
        assert observed <= cap + 3.0 * np.sqrt(cap) + 1, (d_min, observed, cap)
    # the small end sits at equilibrium (not far below), far below production
    n1 = (d >= 1.0).sum()
    eq1 = area_km2 * float(mc.equilibrium_density_per_km2(1.0))
    prod1 = area_km2 * float(mc.cumulative_density_per_km2(1.0, age_ga=3.5,
                                                            system="hartmann-daubar-2016"))
    assert n1 > eq1 - 4 * np.sqrt(eq1)
    assert prod1 > 50 * eq1


def test_edge_craters_included_and_footprints_touch_scene() -> None:
    cfg = _pure(d_min_m=10.0, d_max_m=200.0)
    box = (0.0, 0.0, 200.0, 200.0)
    table, _ = sample_craters(box, cfg, rng=np.random.default_rng(8))
    x, y = table.center_xy_m.T
    outside = ~_inside(table, box)
    assert outside.sum() > 10
    gap = np.hypot(np.maximum(np.maximum(-x, x - 200), 0), np.maximum(np.maximum(-y, y - 200), 0))
    assert np.all(gap <= cfg.ejecta_reach * table.diameter_m / 2 + 1e-9)


def test_deterministic_and_ellipticity() -> None:
    cfg = _pure(d_min_m=20.0, axis_ratio_min=0.6)
    a, _ = sample_craters(BOX_1KM, cfg, rng=np.random.default_rng(4))
    np.random.default_rng(999).random(10)
    b, _ = sample_craters(BOX_1KM, cfg, rng=np.random.default_rng(4))
    for name in ("center_xy_m", "diameter_m", "depth_m", "age_ga", "axis_ratio", "azimuth_deg"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.axis_ratio.min() >= 0.6 and a.axis_ratio.max() <= 1.0 and a.axis_ratio.std() > 0.05


def test_degradation_makes_old_craters_shallow() -> None:
    cfg = CraterConfig(system="neukum-ivanov-2001", age_ga=3.5, d_min_m=50.0, d_max_m=500.0,
                       equilibrium="none", diffusivity_m2_per_myr=0.5)
    table, _ = sample_craters((0, 0, 3000, 3000), cfg, rng=np.random.default_rng(1))
    dd = table.depth_m / table.diameter_m
    fresh = cfg.effective_depth_to_diameter - cfg.rim_height_to_diameter
    assert dd.max() <= fresh + 1e-9
    young, old = table.age_ga < 1.0, table.age_ga > 3.0
    assert dd[young].mean() > dd[old].mean() + 0.01
    rho, p = stats.spearmanr(table.age_ga, dd)
    assert rho < -0.3 and p < 1e-3
