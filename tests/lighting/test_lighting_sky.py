"""Sky colour, visibility, contrast and the W/m^2 -> USD unit mapping."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.lighting import (
    LightingConfig,
    compute_lighting,
    contrast_transmission,
    extinction_coefficient_per_m,
    shadow_contrast,
    sky_color_rgb,
    sun_color_rgb,
    usd_dome_intensity,
    usd_light_intensity,
    visibility_m,
)


def test_visibility_from_tau_and_scale_height() -> None:
    assert float(extinction_coefficient_per_m(1.0)) == pytest.approx(1 / 11_000)
    assert float(visibility_m(1.0)) == pytest.approx(-math.log(0.02) * 11_000, rel=1e-12)
    v_half = float(visibility_m(0.5, dust_scale_height_m=10_000))
    assert v_half == pytest.approx(78_240.46, abs=0.01)
    assert np.isinf(visibility_m(0.0))
    v = visibility_m([0.3, 1.0, 3.0, 6.0])
    assert np.all(np.diff(v) < 0)
    # at the visibility distance the contrast has fallen to the 2 % threshold
    assert float(contrast_transmission(float(v[2]), tau=3.0)) == pytest.approx(0.02)
    with pytest.raises(ConfigError, match="tau"):
        visibility_m(-1.0)


def test_colours_are_normalised_and_physically_ordered() -> None:
    for tau in (0.0, 0.5, 3.0, 10.0):
        for el in (-5.0, 5.0, 45.0):
            for near in (False, True):
                c = sky_color_rgb(tau, sun_elevation_deg=el, near_sun=near)
                assert max(c) == pytest.approx(1.0) and min(c) > 0.0
    day = sky_color_rgb(0.5, sun_elevation_deg=40.0)
    assert day[0] > day[1] > day[2]  # butterscotch: red > green > blue
    sunset = sky_color_rgb(0.5, sun_elevation_deg=2.0, near_sun=True)
    assert sunset[2] > sunset[0]  # blue aureole around a low sun in a clear-ish sky
    storm = sky_color_rgb(6.0, sun_elevation_deg=2.0, near_sun=True)
    assert storm[2] < storm[0]  # washed out in a dust storm
    low = sun_color_rgb(1.0, air_mass=20.0)
    high = sun_color_rgb(1.0, air_mass=1.0)
    assert low[2] < high[2] <= 1.0


def test_shadow_contrast_fades_with_dust() -> None:
    lts = [compute_lighting(LightingConfig(sun_azimuth_deg=90.0, sun_elevation_deg=50.0, tau=t),
                            lat_deg=0.0, lon_east_deg=0.0) for t in (0.3, 1.0, 3.0, 6.0)]
    c = [lt.shadow_contrast for lt in lts]
    assert all(a > b for a, b in itertools.pairwise(c))
    assert c[0] > 0.7 and c[-1] < 0.02
    assert float(shadow_contrast(0.0, 0.0)) == 0.0


def test_usd_unit_mapping() -> None:
    assert usd_light_intensity(500.0) == pytest.approx(49_000.0)
    assert usd_light_intensity(500.0, units="w_m2") == 500.0
    assert usd_light_intensity(500.0, luminous_efficacy_lm_per_w=110.0) == pytest.approx(55_000.0)
    assert usd_dome_intensity(math.pi * 100.0) == pytest.approx(9800.0)
    with pytest.raises(ConfigError, match="usd_units"):
        usd_light_intensity(1.0, units="nits")
