"""Cited morphometry defaults and degradation reference values (issue 13 part 3; data in
``marsscene/craters/data/mars_crater_morphometry.toml``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.craters import CraterConfig, crater_models, crater_profile, profile_family
from marsscene.craters.morphology import S_ERASE
from marsscene.craters.morphometry import (
    DEFAULT_DEPTH_TO_DIAMETER,
    background_diffusivities,
    fresh_depth_to_diameter,
    morphometry_data,
)


@pytest.mark.parametrize(("d_m", "expected"), [(100.0, 0.1762), (500.0, 0.1500),
                                               (1000.0, 0.1400), (8000.0, 0.1137)])
def test_fresh_depth_is_the_garvin_frawley_law(d_m: float, expected: float) -> None:
    """d = 0.14 D^0.90 (km) (Garvin & Frawley 1998): d/D = 0.14 D_km^-0.1 (docs/science/craters.md:
    0.18 at 100 m, 0.15 at 500 m, 0.14 at 1 km)."""
    assert float(fresh_depth_to_diameter(d_m)) == pytest.approx(expected, abs=5e-5)


def test_small_craters_keep_the_50m_ratio() -> None:
    """Millot et al. (2024): depth ~ proportional to D below 50 m, so d/D is held there."""
    law_50 = 0.14 * 0.05**0.9 / 0.05
    np.testing.assert_allclose(fresh_depth_to_diameter([1.0, 5.0, 25.0, 50.0]), law_50)
    assert DEFAULT_DEPTH_TO_DIAMETER == pytest.approx(law_50)
    assert float(fresh_depth_to_diameter(25.0)) < 0.14 * 0.025**0.9 / 0.025  # law unextended


def test_config_default_depth_follows_the_diameter_range() -> None:
    small = CraterConfig(d_min_m=2.0, d_max_m=20.0)
    large = CraterConfig(d_min_m=100.0, d_max_m=1000.0)
    assert small.effective_depth_to_diameter == pytest.approx(0.1889, abs=1e-4)
    assert large.effective_depth_to_diameter == pytest.approx(
        0.14 * (math.sqrt(0.1 * 1.0)) ** -0.1, abs=1e-6)
    assert CraterConfig(depth_to_diameter=0.1).effective_depth_to_diameter == 0.1
    fam = profile_family(**small.profile_kwargs())
    assert fam.depth_over_d[0] + fam.rim_over_d[0] == pytest.approx(0.1889, abs=1e-4)
    cites = " ".join(c for _, c in crater_models(small))
    assert "10.1029/1998GL900177" in cites and "10.1029/2024JE008844" in cites


def _kappa(site_prefix: str) -> dict[str, object]:
    rows = [r for r in background_diffusivities() if str(r["site"]).startswith(site_prefix)]
    assert len(rows) == 1
    return rows[0]


def test_homestead_diffusivity_reproduces_the_observed_hollow() -> None:
    """Warner et al. (2020): a 27 m crater 0.3 m deep after ~0.55 Ga. The tabulated kappa,
    applied with this package's degradation model to the default fresh profile, gives it."""
    row = _kappa("Homestead")
    d_m, t_myr = float(row["diameter_m"]), float(row["age_ga"]) * 1e3  # type: ignore[arg-type]
    length_m = math.sqrt(2.0 * float(row["kappa_m2_per_myr"]) * t_myr)  # type: ignore[arg-type]
    floor_m = -float(crater_profile(0.0, diameter_m=d_m, diffusion_length_m=length_m))
    assert floor_m == pytest.approx(float(row["depth_m"]), rel=0.1)  # type: ignore[arg-type]


def test_meridiani_diffusivity_makes_class5_craters_unrecognisable_in_7_ma() -> None:
    """Golombek et al. (2014): ~10-22 m craters reach class 5 (shallow, planed rims) in
    4-10 Ma; with the tabulated kappa an 11 m crater reaches the limit s = S_ERASE at 7 Ma."""
    kappa = float(_kappa("Meridiani")["kappa_m2_per_myr"])  # type: ignore[arg-type]
    s = math.sqrt(2.0 * kappa * 7.0) / 5.5
    assert s == pytest.approx(S_ERASE, rel=0.01)


def test_every_reference_value_names_its_source() -> None:
    data = morphometry_data()
    for key in ("fresh_depth", "rim_height", "cavity", "ejecta"):
        assert "doi:" in data[key]["reference"] or "Press" in data[key]["reference"]
    for row in data["background_diffusivity"]:
        assert "doi:" in row["reference"] and row["kappa_m2_per_myr"] > 0
