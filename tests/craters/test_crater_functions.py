"""Production, chronology and equilibrium functions against docs/science/craters.md values."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import marsscene.craters as mc
from marsscene.errors import ConfigError, ExtrapolationWarning

REL = 1e-6

# docs/science/craters.md: (system, t, N(>=1 km), N(>=100 m), N(>=10 km))
TABLE = [
    ("ivanov-2001", 1.0, 4.130000e-04, 1.524507e00, 5.902096e-06),
    ("ivanov-2001", 3.5, 2.361610e-03, 8.717410e00, 3.374927e-05),
    ("neukum-ivanov-2001", 1.0, 4.875000e-04, 1.799509e00, 6.966760e-06),
    ("neukum-ivanov-2001", 3.5, 2.806949e-03, 1.036129e01, 4.011352e-05),
    ("hartmann-2005", 1.0, 5.840000e-04, 1.284738e00, 8.077792e-06),
    ("hartmann-2005", 3.5, 3.339543e-03, 7.346641e00, 4.619201e-05),
]


@pytest.mark.parametrize(("system", "t", "n1", "n100", "n10k"), TABLE)
def test_reference_isochrons(system: str, t: float, n1: float, n100: float, n10k: float) -> None:
    assert mc.n1_per_km2(t, system=system) == pytest.approx(n1, rel=REL)
    got = mc.cumulative_density_per_km2([1000.0, 100.0, 10000.0], age_ga=t, system=system)
    np.testing.assert_allclose(got, [n1, n100, n10k], rtol=REL)


@pytest.mark.parametrize(
    ("system", "t", "n10"),
    [("ivanov-2001", 1.0, 2.129597e03), ("neukum-ivanov-2001", 3.5, 1.447378e04),
     ("hartmann-2005", 3.5, 5.623882e03)],
)
def test_ten_metre_values_and_extrapolation_warning(system: str, t: float, n10: float) -> None:
    if system.startswith("hartmann"):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # 10 m is inside the Hartmann table
            got = mc.cumulative_density_per_km2(10.0, age_ga=t, system=system)
    else:
        with pytest.warns(ExtrapolationWarning, match="validity range"):
            got = mc.cumulative_density_per_km2(10.0, age_ga=t, system=system)
    assert float(got) == pytest.approx(n10, rel=REL)


def test_extra_n1_values() -> None:
    np.testing.assert_allclose(
        mc.n1_per_km2([3.0, 4.0], system="ivanov-2001"), [1.267650e-3, 3.094594e-2], rtol=REL
    )
    assert mc.n1_per_km2(4.0) == pytest.approx(3.714645e-2, rel=REL)


def test_equilibrium_values() -> None:
    np.testing.assert_allclose(
        mc.equilibrium_density_per_km2([10.0, 100.0, 1000.0]), [331.13, 4.8978, 0.072444],
        rtol=2e-5,  # the reference values have 5 significant digits
    )


def test_age_inverse_and_formation_age_quantiles() -> None:
    ages = np.array([0.0, 0.01, 0.5, 1.0, 2.0, 3.5, 4.4])
    for system in mc.SYSTEMS:
        np.testing.assert_allclose(
            mc.age_from_n1_ga(mc.n1_per_km2(ages, system=system), system=system), ages,
            atol=1e-10,
        )
    # tau = N1^-1(u N1(T)), H&N CF, T = 3.5 Ga (docs/science/craters.md)
    u = np.array([0.1, 0.5, 0.9])
    tau = mc.age_from_n1_ga(u * mc.n1_per_km2(3.5))
    np.testing.assert_allclose(tau, [0.5758, 2.8534, 3.4608], atol=5e-5)


def test_isochron_crosses_equilibrium_where_documented() -> None:
    d = np.geomspace(20.0, 400.0, 20001)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        for system, t, d_x in [("ivanov-2001", 1.0, 42.5), ("neukum-ivanov-2001", 1.0, 48.2),
                               ("ivanov-2001", 3.5, 145.0), ("neukum-ivanov-2001", 3.5, 161.0)]:
            diff = mc.cumulative_density_per_km2(d, age_ga=t, system=system) - \
                mc.equilibrium_density_per_km2(d)
            cross = d[np.nonzero(np.diff(np.sign(diff)))[0][0]]
            assert cross == pytest.approx(d_x, rel=0.01)


def test_hartmann_daubar_extends_hartmann_2005_to_one_metre() -> None:
    # same table above 31.25 m, so the shapes agree up to the 1-km normalisation
    d = np.array([40.0, 100.0, 1000.0, 5000.0])
    a = mc.production_shape(d, system="hartmann-2005")
    b = mc.production_shape(d, system="hartmann-daubar-2016")
    np.testing.assert_allclose(a / a[2], b / b[2], rtol=1e-12)
    lo, hi = mc.chronology_system("hartmann-daubar-2016").valid_diameter_m
    assert lo == pytest.approx(1000 * 2**-10) and hi == pytest.approx(1000 * 2**9.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mc.cumulative_density_per_km2(1.0, age_ga=3.5, system="hartmann-daubar-2016")


def test_bad_inputs() -> None:
    with pytest.raises(ConfigError, match="unknown"):
        mc.n1_per_km2(1.0, system="moon")
    with pytest.raises(ConfigError, match=r"-0.5.*\[0.0, 4.5\]"):
        mc.n1_per_km2(-0.5)
    with pytest.raises(ConfigError, match=r"4\.6"):
        mc.cumulative_density_per_km2(100.0, age_ga=4.6)
    with pytest.raises(ConfigError, match="diameter_m"):
        mc.cumulative_density_per_km2(-1.0, age_ga=1.0)
