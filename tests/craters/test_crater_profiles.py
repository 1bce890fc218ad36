"""Profiles: Fassett-Thomson reference values, rim continuity, volumes, diffusion."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ive

from marsscene.craters import crater_profile, profile_family
from marsscene.craters.morphology import S_ERASE, profile_over_diameter


def test_fassett_thomson_reference_values() -> None:
    rho = np.array([0.5, 0.8, 0.98, 1.2, 1.5])
    got = profile_over_diameter(rho, model="fassett-thomson-2014")
    # docs/science/craters.md (6 decimals): inner(0.98) = 0.036822, outer(1.2) = 0.016375
    np.testing.assert_allclose(got, [-0.099201, -0.013812, 0.036822, 0.016375, 2.5e-10],
                               atol=6e-7)
    assert float(profile_over_diameter(0.1, model="fassett-thomson-2014")) == -0.181
    assert float(profile_over_diameter(1.6, model="fassett-thomson-2014")) == 0.0


def test_ftmod_flat_rim_and_floor() -> None:
    rho = np.array([0.0, 0.99, 1.0, 1.01])
    got = profile_over_diameter(rho, model="ftmod", depth_to_diameter=0.15)
    np.testing.assert_allclose(got, [0.036822095 - 0.15, 0.036822095, 0.036822095, 0.036822095],
                               rtol=1e-9)


@pytest.mark.parametrize(("model", "rim", "tol"), [
    ("watters-2015", 1.0, 1e-9), ("ftmod", 0.98, 1e-9), ("ftmod", 1.02, 2e-5),
    ("fassett-thomson-2014", 0.98, 2e-5),
])
def test_continuity_at_the_rim(model: str, rim: float, tol: float) -> None:
    eps = 1e-9
    a, b = profile_over_diameter([rim - eps, rim + eps], model=model)
    assert abs(a - b) < tol


def test_watters_shape_depth_rim_and_exponent() -> None:
    d = 20.0
    h = crater_profile(np.array([0.0, 0.5, 1.0, 2.5, 3.0]), diameter_m=d,
                       depth_to_diameter=0.2, rim_height_to_diameter=0.04, cavity_exponent=1.75)
    floor = (0.04 - 0.2) * d
    assert h[0] == pytest.approx(floor)
    assert h[2] == pytest.approx(0.04 * d)  # rim crest
    assert h[1] == pytest.approx(0.04 * d - 0.2 * d * (1 - 0.5**1.75))
    assert h[3] == 0.0 and h[4] == 0.0


def _volume(h: np.ndarray, rho: np.ndarray) -> tuple[float, float]:
    step = rho[1] - rho[0]
    w = 2 * np.pi * rho * step
    return float((np.minimum(h, 0) * w).sum()), float((np.maximum(h, 0) * w).sum())


@pytest.mark.parametrize(("model", "lo", "hi"), [
    ("watters-2015", 0.65, 0.80),       # defaults: rim + ejecta = 0.72 x cavity (docs)
    ("fassett-thomson-2014", 0.35, 0.45),
    ("ftmod", 0.43, 0.53),
])
def test_cavity_vs_rim_ejecta_volume(model: str, lo: float, hi: float) -> None:
    rho = np.linspace(0, 3, 300001)
    cavity, above = _volume(profile_over_diameter(rho, model=model), rho)
    assert lo < above / -cavity < hi


def test_diffusion_conserves_volume_and_matches_heat_kernel() -> None:
    fam = profile_family("watters-2015")
    w = 2 * np.pi * fam.rho * (fam.rho[1] - fam.rho[0])
    vols = fam.h_over_d @ w
    # exact while a raised rim remains to take back the trimmed tail (every state up to and
    # well past the recognisability limit S_ERASE)
    alive = fam.rim_over_d > 0
    assert fam.s[alive].max() > 2 * S_ERASE
    np.testing.assert_allclose(vols[alive], vols[0], rtol=1e-3)
    # exact axisymmetric heat kernel: h(r) = int h0(r') r'/s^2 exp(-(r-r')^2/2s^2) ive0(r r'/s^2)
    fine = np.arange(0.0, 2.5, 0.0005) + 0.00025
    h0 = profile_over_diameter(fine)
    for i in (10, 25, 35):
        s = fam.s[i]
        r = np.array([0.0, 0.5, 1.0, 1.5, 2.0])[:, None]
        k = np.exp(-((r - fine) ** 2) / (2 * s * s)) * ive(0, r * fine / (s * s)) * fine / (s * s)
        exact = (k * 0.0005) @ h0
        got = np.interp(r[:, 0], fam.rho, fam.h_over_d[i])
        np.testing.assert_allclose(got, exact, atol=2e-3 * 0.18)


def test_degraded_states_are_monotonic() -> None:
    fam = profile_family("watters-2015")
    assert np.all(np.diff(fam.depth_over_d) < 0)
    rim = fam.rim_over_d
    assert np.all(np.diff(rim[rim > 0]) < 0) and np.all(np.diff(rim) <= 0)
    assert fam.depth_over_d[-1] < 0.1 * fam.depth_over_d[0]
    h = crater_profile(0.0, diameter_m=10.0, diffusion_length_m=2.0)
    assert -10.0 * fam.depth_over_d[0] < float(h) < -0.3
