"""The rigid-wheel soil model against an independent evaluation of the published equations
(adaptive quadrature of Wong & Reece's stresses, written here from the papers' formulas, not
the module's Gauss-Legendre path), and the behaviour the theory predicts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from marsscene.errors import ConfigError
from marsscene.rover.terramechanics import (
    Soil,
    sinkage_for_load,
    soil,
    soils,
    wheel_forces,
)

R_M, B_M = 0.25, 0.40  # a Curiosity wheel: 0.50 m across, 0.40 m wide
LOAD_N = 899.0 * 3.71 / 6  # the rover's Mars weight on six wheels


def _reference(sl: Soil, z: float, s: float) -> tuple[float, float, float]:
    """W, DP, T by scipy's adaptive quadrature of the Wong-Reece / Janosi-Hanamoto stresses."""
    t1 = math.acos(1 - z / R_M)
    tm, t2 = (sl.a0 + sl.a1 * s) * t1, sl.exit_ratio * t1
    n, k = sl.n + sl.n_slip * s, sl.k_c / B_M + sl.k_phi

    def sigma(t: float) -> float:
        if t >= tm:
            return k * (R_M * (math.cos(t) - math.cos(t1))) ** n
        return k * (R_M * (math.cos(t1 - (t - t2) / (tm - t2) * (t1 - tm)) - math.cos(t1))) ** n

    def tau(t: float) -> float:
        j = R_M * ((t1 - t) - (1 - s) * (math.sin(t1) - math.sin(t)))
        return (sl.cohesion_pa + sigma(t) * math.tan(math.radians(sl.friction_deg))) * (
            1 - math.exp(-j / sl.shear_modulus_m))

    def integral(f) -> float:
        return quad(f, t2, tm, epsabs=0, epsrel=1e-10)[0] + quad(f, tm, t1, epsabs=0,
                                                                 epsrel=1e-10)[0]

    w = R_M * B_M * integral(lambda t: sigma(t) * math.cos(t) + tau(t) * math.sin(t))
    dp = R_M * B_M * integral(lambda t: tau(t) * math.cos(t) - sigma(t) * math.sin(t))
    return w, dp, R_M * R_M * B_M * integral(tau)


@pytest.mark.parametrize("name", sorted(soils()))
def test_forces_match_an_independent_quadrature_of_the_equations(name):
    sl = soil(name)
    for z in (0.005, 0.03, 0.12):
        for s in (0.0, 0.1, 0.4, 0.8):
            got = wheel_forces(sl, R_M, B_M, z, s)
            w, dp, t = _reference(sl, z, s)
            assert float(got.load_n) == pytest.approx(w, rel=2e-4), (z, s)
            assert float(got.torque_nm) == pytest.approx(t, rel=2e-4), (z, s)
            assert float(got.drawbar_n) == pytest.approx(dp, rel=2e-3, abs=0.05), (z, s)


@pytest.mark.parametrize("name", sorted(soils()))
def test_a_loaded_wheel_pulls_more_the_more_it_slips(name):
    sl, slips = soil(name), np.array([0.0, 0.05, 0.1, 0.2, 0.4, 0.6, 0.8])
    z = sinkage_for_load(sl, R_M, B_M, LOAD_N, slips)
    f = wheel_forces(sl, R_M, B_M, z, slips)
    np.testing.assert_allclose(f.load_n, LOAD_N, rtol=1e-4)  # the sinkage carries the load
    assert f.drawbar_n[0] < 0  # a free-rolling wheel in soil is held back (compaction)
    assert np.all(np.diff(f.torque_nm) > 0)
    rising = f.drawbar_n if sl.n_slip == 0 else f.drawbar_n[:5]  # slip sinkage: past ~50 %
    assert np.all(np.diff(rising) > 0)  # the pull is eaten by digging in (Ding et al. 2011)
    assert np.all(0 < z) and np.all(z < 0.5 * R_M)


def test_weaker_soil_gives_less_pull_and_slip_sinkage_where_the_soil_has_it():
    slips = np.array([0.0, 0.3, 0.7])
    pull = {n: wheel_forces(soil(n), R_M, B_M,
                            sinkage_for_load(soil(n), R_M, B_M, LOAD_N, slips), slips).drawbar_n
            for n in ("firm_regolith", "drift_sand", "megaripple_sand")}
    assert np.all(pull["firm_regolith"] > pull["drift_sand"])
    assert np.all(pull["drift_sand"] > pull["megaripple_sand"])
    z = sinkage_for_load(soil("marssim_sand"), R_M, B_M, LOAD_N, slips)
    assert z[2] > 2.5 * z[0]  # the sinkage exponent grows with slip: the wheel digs in


@settings(max_examples=60, deadline=None)
@given(r=st.floats(0.05, 1.0), b=st.floats(0.05, 1.0), frac=st.floats(0.0, 1.0),
       s=st.floats(0.0, 0.99), name=st.sampled_from(sorted(soils())))
def test_any_wheel_sinkage_and_slip_gives_finite_forces(r, b, frac, s, name):
    f = wheel_forces(soil(name), r, b, frac * r, s)
    assert np.isfinite([f.load_n, f.drawbar_n, f.torque_nm]).all() and f.load_n >= 0


def test_bad_soils_are_one_line_errors():
    with pytest.raises(ConfigError, match="unknown"):
        soil("quicksand")
    with pytest.raises(ConfigError, match="positive"):
        Soil(name="x", cohesion_pa=0, friction_deg=30, k_c=0, k_phi=0, n=1,
             shear_modulus_m=0.01)
    with pytest.raises(ConfigError, match="friction"):
        Soil(name="x", cohesion_pa=0, friction_deg=95, k_c=0, k_phi=1e6, n=1,
             shear_modulus_m=0.01)
