"""Golombek–Huertas SFD: docs/science/rocks.md reference values, sampling, bad configs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import quad
from scipy.optimize import brentq

from marsscene.errors import ConfigError, ExtrapolationWarning
from marsscene.rocks import (
    RockConfig,
    cumulative_area_fraction,
    cumulative_number_density_per_m2,
    diameter_cdf,
    differential_number_density,
    expected_count,
    sample_diameters,
)

# k, D, F_k(D), N(>D), n(D) — docs/science/rocks.md
REFERENCE = [
    (0.05, 0.1, 3.084649e-02, 1.034198e00, 1.896981e01),
    (0.05, 0.5, 4.468367e-03, 1.355339e-02, 1.099173e-01),
    (0.05, 1.0, 3.993261e-04, 3.728434e-04, 2.455754e-03),
    (0.05, 2.0, 3.189226e-06, 8.520583e-07, 4.903233e-06),
    (0.10, 0.1, 7.182052e-02, 1.863514e00, 3.026820e01),
    (0.10, 0.5, 1.910921e-02, 4.993378e-02, 3.221371e-01),
    (0.10, 1.0, 3.651617e-03, 3.074629e-03, 1.538946e-02),
    (0.10, 2.0, 1.333431e-04, 3.336234e-05, 1.404910e-04),
    (0.07, 1.0, 1.332513e-03, 1.181888e-03, 6.720993e-03),
    (0.19, 1.0, 1.425381e-02, 1.107944e-02, 4.700464e-02),
]


@pytest.mark.parametrize(("k", "d", "f", "n_cum", "n_diff"), REFERENCE)
def test_reference_values(k: float, d: float, f: float, n_cum: float, n_diff: float) -> None:
    np.testing.assert_allclose(cumulative_area_fraction(d, k=k), f, rtol=1e-6)
    np.testing.assert_allclose(cumulative_number_density_per_m2(d, k=k), n_cum, rtol=1e-6)
    np.testing.assert_allclose(differential_number_density(d, k=k), n_diff, rtol=1e-6)


def test_k_002_outside_fit_warns_but_matches_reference() -> None:
    with pytest.warns(ExtrapolationWarning, match="fitted range"):
        val = cumulative_number_density_per_m2(0.5, k=0.02)
    np.testing.assert_allclose(val, 6.780351e-04, rtol=1e-6)


def test_closed_form_matches_quadrature() -> None:
    num, _ = quad(lambda x: float(differential_number_density(x, k=0.2)), 0.3, 40.0, limit=200)
    np.testing.assert_allclose(cumulative_number_density_per_m2(0.3, k=0.2), num, rtol=1e-7)


def test_expected_count_reference() -> None:
    # docs/science/rocks.md: N(>0.1) - N(>3) = 1.034198 per m^2 at k = 0.05
    np.testing.assert_allclose(expected_count(1.0, k=0.05, d_min_m=0.1, d_max_m=3.0), 1.034198,
                               rtol=1e-6)


def test_sampled_quantiles_and_ks() -> None:
    # docs/science/rocks.md quantiles of D for k = 0.05 on [0.1, 3] m
    for u, d_ref in [(0.5, 0.142426), (0.9, 0.275216), (0.99, 0.533738)]:
        d_u = brentq(lambda x, u=u: float(diameter_cdf(x, k=0.05, d_min_m=0.1, d_max_m=3.0)) - u,
                     0.1, 3.0, xtol=1e-12)
        assert abs(d_u - d_ref) < 1e-6  # reference printed to 6 decimals
    for seed in range(4):
        d = sample_diameters(20_000, k=0.05, d_min_m=0.1, d_max_m=3.0,
                             rng=np.random.default_rng(seed))
        assert d.min() >= 0.1 and d.max() <= 3.0
        res = stats.kstest(d, lambda x: diameter_cdf(x, k=0.05, d_min_m=0.1, d_max_m=3.0))
        assert res.pvalue > 0.001


def test_inverse_cdf_is_accurate() -> None:
    d = sample_diameters(50_000, k=0.3, d_min_m=0.05, d_max_m=5.0, rng=np.random.default_rng(1))
    u = np.random.default_rng(1).random(50_000)  # the same uniforms the sampler drew
    np.testing.assert_allclose(diameter_cdf(d, k=0.3, d_min_m=0.05, d_max_m=5.0), u, atol=1e-6)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"k": 0.0}, "rocks.k"),
        ({"k": -0.1}, "rocks.k"),
        ({"k": 0.95}, "rocks.k"),
        ({"d_min_m": 1.0, "d_max_m": 0.5}, "d_min_m"),
        ({"d_min_m": 0.5, "d_max_m": 0.5}, "d_min_m"),
        ({"placement": "grid"}, "rocks.placement"),
        ({"collision": "vhacd"}, "rocks.collision"),
        ({"height_ratio": (0.6, 0.3)}, "height_ratio"),
        ({"burial_fraction": 0.95}, "burial_fraction"),
        ({"mjcf_region_xy_m": (0.0, 0.0)}, "mjcf_region"),
        ({"field_polygon_xy_m": ((0.0, 0.0), (1.0, 1.0))}, "field_polygon"),
    ],
)
def test_bad_config(changes: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        RockConfig(**changes)


def test_k_bounds_in_functions() -> None:
    with pytest.raises(ConfigError, match=r"\(0, 0.9\]"):
        cumulative_area_fraction(0.1, k=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cumulative_area_fraction(0.1, k=0.3)  # inside the fitted range: no warning
    with pytest.warns(ExtrapolationWarning):
        cumulative_area_fraction(0.1, k=0.6)


def test_toml_style_config_round_trip() -> None:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({"rocks": {
        "k": 0.1, "height_ratio": [0.4, 0.6], "burial_fraction": 0.2,
        "field_polygon_xy_m": [[0, 0], [10, 0], [10, 10]], "mjcf_region_xy_m": [1, 2],
        "mjcf_region_radius_m": 30.0, "size_classes_m": [0.5],
    }})
    r = cfg.rocks
    assert r.height_ratio == (0.4, 0.6) and r.range_of("burial_fraction") == (0.2, 0.2)
    assert r.field_polygon_xy_m == ((0.0, 0.0), (10.0, 0.0), (10.0, 10.0))
    assert r.mjcf_region_xy_m == (1, 2) and r.size_classes_m == (0.5,)
    assert cfg.to_dict()["rocks"]["field_polygon_xy_m"][1] == [10.0, 0.0]
    assert len(cfg.config_hash()) == 64
    with pytest.raises(ConfigError, match=r"unknown key rocks\.kk"):
        ms.SceneConfig.from_dict({"rocks": {"kk": 0.1}})
    with pytest.raises(ConfigError, match=r"rocks\.prototypes"):
        ms.SceneConfig.from_dict({"rocks": {"prototypes": 0}})
