"""Partial resurfacing (Michael & Neukum 2010): age recovery, masks, rules."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import marsscene.craters as mc
from marsscene.craters import CraterConfig, ResurfacingEvent, sample_craters
from marsscene.craters.resurfacing import mask_weights, points_in_polygon
from marsscene.errors import ConfigError, ExtrapolationWarning
from marsscene.terrain.heightfield import Heightfield

SIDE = 8000.0  # 8 km x 8 km, half resurfaced
BOX = (0.0, 0.0, SIDE, SIDE)
WEST = ((0.0, 0.0), (SIDE / 2, 0.0), (SIDE / 2, SIDE), (0.0, SIDE))


def _fit_age(d: np.ndarray, area_km2: float, d_lo: float, d_hi: float) -> float:
    """Cumulative fit with the Michael-Neukum correction: only craters in [d_lo, d_hi) count,
    so craters above the range (older population) do not bias the young age."""
    n = ((d >= d_lo) & (d < d_hi)).sum()
    phi = mc.production_shape([d_lo, d_hi], system="neukum-ivanov-2001")
    return float(mc.age_from_n1_ga(n / (area_km2 * (phi[0] - phi[1]))))


def test_science_reference_forward_model() -> None:
    # C_obs(D) = Phi(D) N1(te) + Phi(max(D, De)) (N1(T) - N1(te)), docs/science/craters.md
    n1 = mc.n1_per_km2
    d = np.array([50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        c = mc.production_shape(d) * n1(1.0) + mc.production_shape(np.maximum(d, 500.0)) * (
            n1(3.5) - n1(1.0))
    np.testing.assert_allclose(
        c, [1.66387e01, 1.82564e00, 1.90963e-01, 3.16248e-02, 2.80695e-03, 4.13418e-04],
        rtol=1e-5)


@pytest.mark.parametrize("seed", [0, 1])
def test_recovered_ages_match_surface_and_event(seed: int) -> None:
    cfg = CraterConfig(
        system="neukum-ivanov-2001", age_ga=3.5, d_min_m=20.0, d_max_m=2000.0,
        equilibrium="none", degradation="none",
        resurfacing=({"age_ga": 1.0, "rule": "sharp", "d_max_m": 100.0,
                      "polygon_xy_m": [list(p) for p in WEST]},),  # type: ignore[arg-type]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        table, stats = sample_craters(BOX, cfg, rng=np.random.default_rng(seed))
    assert stats.resurfaced > 1000
    x, y = table.center_xy_m.T
    inside = (x >= 0) & (x <= SIDE) & (y >= 0) & (y <= SIDE)
    west = inside & (x < SIDE / 2)
    east = inside & (x >= SIDE / 2)
    half_km2 = SIDE * SIDE / 2 / 1e6
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        t_young = _fit_age(table.diameter_m[west], half_km2, 25.0, 100.0)
        t_old_west = _fit_age(table.diameter_m[west], half_km2, 100.0, 2000.0)
        t_east = _fit_age(table.diameter_m[east], half_km2, 25.0, 2000.0)
    assert t_young == pytest.approx(1.0, abs=0.05)
    assert t_old_west == pytest.approx(3.5, abs=0.1)
    assert t_east == pytest.approx(3.5, abs=0.05)
    # the kink: below D_e the resurfaced half holds ~N1(1)/N1(3.5) of the other half's craters
    small = table.diameter_m < 60
    ratio = (west & small).sum() / (east & small).sum()
    assert ratio == pytest.approx(float(mc.n1_per_km2(1.0) / mc.n1_per_km2(3.5)), rel=0.1)
    # craters formed after the event are untouched; older small ones are gone from the mask
    assert not np.any(west & (table.age_ga > 1.0) & (table.diameter_m < 100.0))


def test_points_in_polygon_and_lonlat_mask() -> None:
    x = np.array([1.0, 5.0, 3.0, -1.0])
    y = np.array([1.0, 1.0, 3.9, 1.0])
    tri = [(0.0, 0.0), (4.0, 0.0), (0.0, 4.0)]
    np.testing.assert_array_equal(points_in_polygon(x, y, tri), [True, False, False, False])
    ev = ResurfacingEvent(age_ga=1.0, d_max_m=5.0,
                          polygon_lonlat_deg=((137.0, -5.0), (137.1, -5.0), (137.1, -4.9)))
    with pytest.raises(ConfigError, match="georeferenced"):
        mask_weights(ev, np.zeros((1, 2)))
    # a point just inside the south-east corner (origin at lon 137.0, lat -5.0)
    w = mask_weights(ev, np.array([[1000.0, 100.0], [-1000.0, 100.0]]),
                     origin_lonlat_deg=(137.0, -5.0))
    np.testing.assert_array_equal(w, [1.0, 0.0])


def test_raster_mask_and_soft_weights(tmp_path) -> None:  # type: ignore[no-untyped-def]
    hf = Heightfield.centered(np.zeros((11, 21), np.float32), 1.0)
    mask = np.zeros(hf.shape)
    mask[:, 10:] = 0.5  # east half erased with probability 0.5
    path = tmp_path / "mask.npy"
    np.save(path, mask)
    ev = ResurfacingEvent(age_ga=1.0, d_max_m=5.0, mask_path=str(path))
    w = mask_weights(ev, np.array([[-5.0, 0.0], [5.0, 0.0], [50.0, 0.0]]), heightfield=hf)
    np.testing.assert_array_equal(w, [0.0, 0.5, 0.5])
    with pytest.raises(ConfigError, match="shape"):
        mask_weights(ev, np.zeros((1, 2)), heightfield=Heightfield.centered(np.zeros((5, 5)), 1.0))


@pytest.mark.parametrize("rule", ["burial", "ramp"])
def test_burial_and_ramp_rules(rule: str) -> None:
    kw = {"thickness_m": 3.0} if rule == "burial" else {"d_min_m": 20.0, "d_max_m": 40.0}
    cfg = CraterConfig(system="neukum-ivanov-2001", age_ga=3.0, d_min_m=10.0, d_max_m=200.0,
                       equilibrium="none", degradation="none",
                       resurfacing=(ResurfacingEvent(age_ga=0.5, rule=rule, **kw),))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        table, _ = sample_craters((0, 0, 2000, 2000), cfg, rng=np.random.default_rng(3))
    old = table.age_ga > 0.5
    relief = table.depth_m + table.rim_height_m
    if rule == "burial":  # fresh relief = d/D * D (rim crest to floor): erased below 3 m
        assert relief[old].min() >= 3.0 - 1e-9
        d_erased = 3.0 / cfg.effective_depth_to_diameter  # 15.9 m
        assert (old & (table.diameter_m < d_erased * (1 - 1e-9))).sum() == 0
    else:
        assert (old & (table.diameter_m < 20.0)).sum() == 0
        mid = old & (table.diameter_m >= 20.0) & (table.diameter_m < 40.0)
        assert mid.sum() > 0  # partially erased: a continuous range of ages
    assert (~old & (table.diameter_m < 16.0)).sum() > 100
