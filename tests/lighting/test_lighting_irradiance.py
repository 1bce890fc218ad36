"""Irradiance: TOA, air mass, Beer's law, A&F net-flux table and delta-Eddington
(docs/science/atmosphere.md)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from marsscene.errors import ConfigError, ExtrapolationWarning
from marsscene.lighting import (
    air_mass,
    diffuse_irradiance_w_m2,
    direct_irradiance_w_m2,
    global_irradiance_w_m2,
    toa_irradiance_from_ls_w_m2,
    toa_irradiance_w_m2,
)
from marsscene.lighting._netflux import net_flux_polynomial, table_albedo_0p1
from marsscene.lighting.delta_eddington import delta_eddington_fluxes

Z = [0, 60, 80, 85, 89, 90]


def test_air_mass_reference_values() -> None:
    np.testing.assert_allclose(
        air_mass(Z), [1.0, 1.99041, 5.48727, 9.73225, 20.05770, 24.86875], atol=1e-5)
    np.testing.assert_allclose(
        air_mass(Z, scale_height_km=11.1), [1.0, 1.99032, 5.48503, 9.72065, 19.98642, 24.75665],
        atol=1e-5)
    sec = air_mass(Z, model="secant")
    np.testing.assert_allclose(sec[:5], [1, 2, 5.75877, 11.47371, 57.29869], atol=1e-5)
    assert np.isinf(sec[5])
    assert np.all(np.isfinite(air_mass(np.linspace(0, 120, 50))))


def test_toa_irradiance() -> None:
    np.testing.assert_allclose(
        toa_irradiance_from_ls_w_m2([248, 68, 0, 90, 180, 270]),
        [717.79, 493.53, 559.15, 500.96, 643.16, 708.89], atol=0.01)
    assert float(toa_irradiance_w_m2(1.393583)) == pytest.approx(700.8, abs=0.05)
    assert float(toa_irradiance_w_m2(1.523679)) == pytest.approx(586.2, abs=0.05)


def test_beer_law_direct_beam() -> None:
    i0 = float(toa_irradiance_w_m2(1.5))
    got = direct_irradiance_w_m2([0.0, 60.0, 85.0], tau=0.5, distance_au=1.5)
    m = air_mass([0.0, 60.0, 85.0])
    np.testing.assert_allclose(got, i0 * np.exp(-0.5 * m), rtol=1e-12)
    sec = direct_irradiance_w_m2(60.0, tau=1.0, distance_au=1.5, air_mass_model="secant")
    assert float(sec) == pytest.approx(i0 * np.exp(-2.0), rel=1e-12)
    assert float(direct_irradiance_w_m2(0.0, tau=0.0, distance_au=1.5)) == pytest.approx(i0)


def test_sun_below_horizon_gives_no_light() -> None:
    z = np.array([90.0, 95.0, 120.0, 180.0])
    for tau in (0.0, 0.5, 3.0):
        assert np.all(direct_irradiance_w_m2(z, tau=tau) == 0.0)
        assert np.all(diffuse_irradiance_w_m2(z, tau=tau) == 0.0)
        assert np.all(global_irradiance_w_m2(z, tau=tau) == 0.0)


# docs/science/atmosphere.md reference cells (table, al = 0.1, secant air mass)
AF_CELLS = [  # tau, z, f(table), G_h/(G_ob cos z), diffuse/global, polynomial f
    (0.3, 0, 0.848, 0.9422, 0.214, 0.8485), (0.3, 60, 0.773, 0.8589, 0.361, 0.7749),
    (1, 0, 0.728, 0.8089, 0.545, 0.7275), (1, 60, 0.557, 0.6189, 0.781, 0.5575),
    (3, 0, 0.457, 0.5078, 0.902, 0.4566), (3, 60, 0.273, 0.3033, 0.992, 0.2740),
    (6, 0, 0.229, 0.2544, 0.990, 0.2289), (6, 60, 0.128, 0.1422, 1.000, 0.1280),
]


@pytest.mark.parametrize("tau, z, f, ratio, dfrac, fpoly", AF_CELLS)
def test_appelbaum_flood_reference_cells(
    tau: float, z: float, f: float, ratio: float, dfrac: float, fpoly: float
) -> None:
    kw = {"distance_au": 1.0, "solar_constant_w_m2": 1.0}
    cz = np.cos(np.radians(z))
    g = float(global_irradiance_w_m2(z, tau=tau, **kw))
    assert g / cz == pytest.approx(ratio, abs=1e-4)
    d = float(diffuse_irradiance_w_m2(z, tau=tau, air_mass_model="secant", **kw))
    assert d / g == pytest.approx(dfrac, abs=1.5e-3)
    assert float(net_flux_polynomial(np.array(z), np.array(tau), 0.1)) == pytest.approx(
        fpoly, abs=1e-4)
    # the polynomial fallback agrees with the table within its stated accuracy (< 7 %)
    gp = float(global_irradiance_w_m2(z, tau=tau, model="polynomial", **kw))
    assert gp == pytest.approx(g, rel=0.07)
    assert f == pytest.approx(g / cz * 0.9, abs=1e-9)


def test_table_interpolates_between_cells_and_is_monotone() -> None:
    _tau, _z, f = table_albedo_0p1()
    assert f.shape == (58, 18)
    assert np.all(np.diff(f, axis=0) <= 0) and np.all(np.diff(f, axis=1) <= 0)  # typos fixed
    kw = {"distance_au": 1.0, "solar_constant_w_m2": 1.0}
    mid = float(global_irradiance_w_m2(62.5, tau=0.325, **kw)) / np.cos(np.radians(62.5)) * 0.9
    corners = [0.773, 0.747, 0.754, 0.726]  # tau 0.3/0.35 x z 60/65
    assert mid == pytest.approx(np.mean(corners), abs=1e-9)


def test_global_geq_diffuse_geq_zero_and_diffuse_fraction_to_one() -> None:
    z = np.linspace(0.0, 89.9, 60)[:, None]
    taus = np.array([0.0, 0.05, 0.1, 0.3, 0.7, 1.0, 2.0, 3.0, 4.5, 6.0])[None, :]
    for model in ("table", "polynomial", "delta_eddington"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExtrapolationWarning)
            g = global_irradiance_w_m2(z, tau=taus, model=model)
            d = diffuse_irradiance_w_m2(z, tau=taus, model=model)
        assert np.all(d >= 0.0)
        assert np.all(g >= d - 1e-9)
        frac = d[:40] / g[:40]  # z < ~60 deg
        assert np.all(np.diff(frac, axis=1) >= -1e-3), model  # grows with tau
        assert np.all(frac[:, -1] > 0.98)


def test_direct_plus_diffuse_is_global() -> None:
    z = np.linspace(0, 85, 18)
    g = global_irradiance_w_m2(z, tau=0.8)
    b = direct_irradiance_w_m2(z, tau=0.8) * np.cos(np.radians(z))
    d = diffuse_irradiance_w_m2(z, tau=0.8)
    np.testing.assert_allclose(b + d, g, rtol=1e-12)


COMIMART = [(0.3, 0.9445, 0.3103), (0.6, 0.8923, 0.5244), (1.0, 0.8276, 0.7104),
            (1.5, 0.7538, 0.8444), (2.5, 0.6270, 0.9552), (5.0, 0.4006, 0.9980)]


@pytest.mark.parametrize("tau, total, dfrac", COMIMART)
def test_delta_eddington_comimart_table3(tau: float, total: float, dfrac: float) -> None:
    t, d = delta_eddington_fluxes(0.7, tau=tau, single_scattering_albedo=0.97, asymmetry=0.70,
                                  surface_albedo=0.25)
    assert float(t) == pytest.approx(total, abs=1e-4)
    assert 1 - float(d) / float(t) == pytest.approx(dfrac, abs=1e-4)


def test_delta_eddington_illustrative_values() -> None:
    t, d = delta_eddington_fluxes(np.cos(np.radians(60)), tau=1.0, single_scattering_albedo=0.93,
                                  asymmetry=0.68, surface_albedo=0.0)
    assert float(t) == pytest.approx(0.6546, abs=1e-4)
    assert 1 - float(d / t) == pytest.approx(0.793, abs=1e-3)


def test_negative_tau_and_extrapolation() -> None:
    with pytest.raises(ConfigError, match="tau"):
        direct_irradiance_w_m2(0.0, tau=-0.1)
    with pytest.raises(ConfigError, match="tau"):
        diffuse_irradiance_w_m2(0.0, tau=[0.5, -1.0])
    with pytest.warns(ExtrapolationWarning):
        diffuse_irradiance_w_m2(30.0, tau=8.0)
    with pytest.raises(ConfigError, match="diffuse_model"):
        diffuse_irradiance_w_m2(30.0, tau=1.0, model="disort")  # type: ignore[arg-type]
